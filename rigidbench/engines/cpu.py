"""C MuJoCo, the default engine: `mujoco.rollout`, threaded over a batch, in C, float64.

Most runs never build this object: with no engine in effect (`rigidbench.engines.base.current` is None)
`rigidbench.simulate` calls `mujoco.rollout` itself. `CEngine` is the same path behind the `Engine` interface, for
code that takes an engine object (tests, comparisons with the batched engines). A model declaring a Python force
(`rigidbench.forces`) has its callback attached first and is stepped on one thread (the callback holds the GIL).
"""

from __future__ import annotations

import os

import mujoco
import numpy as np
from mujoco import rollout

from rigidbench import forces
from rigidbench.engines.base import Engine


class CEngine(Engine):
    """C MuJoCo through `mujoco.rollout` (threaded over a batch, in C, float64)."""

    def rollout(
        self, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None = None
    ) -> np.ndarray:
        nbatch = len(states0)
        forces.attach(model)
        nthread = forces.threads_for(model, min(nbatch, os.cpu_count() or 1))
        datas = [mujoco.MjData(model) for _ in range(max(nthread, 1))]
        out = np.empty((nbatch, nstep, states0.shape[1]))
        kwargs = {} if control is None else {"control": control}
        rollout.rollout(model, datas if nbatch > 1 else datas[0], states0, nstep=nstep, state=out, **kwargs)
        return out
