"""Reproduce MJX not turning a slowly rotating body (docs/engines.md, Findings: "MJX drops rotations slower than
1e-8 rad/s").

MJX 3.17's `math.norm` returns 0 wherever ``jnp.allclose(x, 0.0)``, whose default ``atol`` is 1e-8 (absolute), and
`math.quat_integrate` takes the rotation's axis and angle from it. So a body whose angular velocity has every
component below 1e-8 rad/s is not turned at all, in float64 as in float32, however long it runs; C MuJoCo turns it
by omega t. rigidbench met it as a struck 80 m stick turning at 2.4e-9 rad/s (its cusps never found) and as a 96 m
stick hit by a light ball turning at 1.1e-10 rad/s (the ball rebounding 1.9e-5 too fast).

This script needs only mujoco and the `mjx` extra (no rigidbench): a free box with no gravity spins about z at
omega, and after `--steps` steps of 1 ms each prints the angle it turned on C MuJoCo and on MJX against omega t.

    python benchmarks/mjx_small_rotation.py            # float64 (jax_enable_x64)
    python benchmarks/mjx_small_rotation.py --float32
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

XML = """
<mujoco>
  <option gravity="0 0 0" timestep="0.001" integrator="RK4"/>
  <worldbody>
    <body name="box"><freejoint/><geom type="box" size="0.1 0.2 0.3" mass="1"/></body>
  </worldbody>
</mujoco>
"""


def _angle(quat: np.ndarray) -> float:
    """The rotation angle (rad) of a unit quaternion (w, x, y, z) about any axis."""
    return float(2.0 * np.arctan2(np.linalg.norm(quat[1:]), quat[0]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--float32", action="store_true", help="run MJX in float32 (default: float64)")
    parser.add_argument("--steps", type=int, default=1000, help="steps of 1 ms (default 1000)")
    args = parser.parse_args()
    if args.steps < 1:
        parser.error(f"--steps {args.steps}: expected >= 1")
    try:
        import jax
        from mujoco import mjx
    except ImportError:
        parser.exit(2, "mjx_small_rotation.py: needs MJX: pip install 'rigidbench[mjx]'\n")
    jax.config.update("jax_enable_x64", not args.float32)
    import mujoco

    model = mujoco.MjModel.from_xml_string(XML)
    mx = mjx.put_model(model)
    run = jax.jit(lambda d: jax.lax.fori_loop(0, args.steps, lambda _, d: mjx.step(mx, d), d))
    duration = args.steps * model.opt.timestep
    precision = "float32" if args.float32 else "float64"
    print(f"mujoco {mujoco.__version__}, MJX {precision}; a free box spinning about z, {args.steps} RK4 steps of 1 ms")
    print(f"{'omega (rad/s)':>13}  {'omega t (rad)':>13}  {'C MuJoCo (rad)':>14}  {'MJX (rad)':>10}  MJX / omega t")
    for omega in (1e-6, 1e-7, 2e-8, 1e-8, 5e-9, 1e-9, 1e-10):
        data = mujoco.MjData(model)
        data.qvel[5] = omega
        mjx_data = run(mjx.put_data(model, data))
        mujoco.mj_step(model, data, args.steps)
        expected = omega * duration
        c_angle, mjx_angle = _angle(data.qpos[3:7]), _angle(np.asarray(mjx_data.qpos, dtype=float)[3:7])
        print(f"{omega:>13.0e}  {expected:>13.3e}  {c_angle:>14.3e}  {mjx_angle:>10.3e}  {mjx_angle / expected:.3g}")


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:  # nothing is written: one line
        sys.exit("mjx_small_rotation.py: interrupted")
