"""The kernels a MuJoCo Warp rollout (`rigidbench.engines.WarpEngine`) adds to Warp's step: set the controls of
the step at the device-side step index, record the state at that index, and advance the index (its own launch, so no
world reads it while it changes). Imported only when Warp runs (Warp reads these annotations, so this module does
not use postponed annotations)."""

import warp as wp


@wp.kernel
def set_ctrl(ctrl: wp.array3d(dtype=wp.float32), index: wp.array(dtype=wp.int32), out: wp.array2d(dtype=wp.float32)):
    w, j = wp.tid()
    out[w, j] = ctrl[w, index[0], j]


@wp.kernel
def record(
    qpos: wp.array2d(dtype=wp.float32),
    qvel: wp.array2d(dtype=wp.float32),
    index: wp.array(dtype=wp.int32),
    qs: wp.array3d(dtype=wp.float32),
    vs: wp.array3d(dtype=wp.float32),
):
    w = wp.tid()
    i = index[0]
    for j in range(qpos.shape[1]):
        qs[i, w, j] = qpos[w, j]
    for j in range(qvel.shape[1]):
        vs[i, w, j] = qvel[w, j]


@wp.kernel
def advance(index: wp.array(dtype=wp.int32)):
    index[0] = index[0] + 1
