"""Collisions per second of the cross-section beam (rigidbench.simulate.final_states) by thread count.

Usage: python benchmarks/cross_section_rate.py [N] [THREADS ...]

Times only the batched rollout (the beam's initial states are drawn first), and compares with a plain Python
loop over mj_step on a few collisions: the speed-up batch work buys. Results vary with the machine's load;
report `os.getloadavg()` with them.
"""

from __future__ import annotations

import os
import sys
import time

import mujoco
import numpy as np

from rigidbench import registry
from rigidbench.settings import Settings
from rigidbench.simulate import final_states


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 20_000
    threads = [int(t) for t in sys.argv[2:]] or [1, 2]
    scenario = registry.get("cross-section")
    params = scenario.resolve(scenario.case("heavy-projectile"), {"n": n})
    model = scenario.build(params, Settings())
    data = scenario.start(model)
    states0, _ = scenario.beam(model, data)
    nstep = scenario._nstep(model)
    print(f"mujoco {mujoco.__version__}; {n} collisions x {nstep} RK4 steps; load {os.getloadavg()}")
    reference = None
    for nthread in threads:
        t0 = time.perf_counter()
        states, diverged = final_states(model, states0, nstep, nthread=nthread)
        wall = time.perf_counter() - t0
        same = "" if reference is None else f", same states as {threads[0]}: {np.array_equal(states, reference)}"
        reference = states if reference is None else reference
        print(f"{nthread} thread(s): {n / wall:8.0f} collisions/s ({wall:.2f} s, {diverged.sum()} diverged{same})")
    # A Python loop over collisions (one mj_setState + mj_step(nstep) call each, stepping in C), for comparison.
    k = 200
    d = mujoco.MjData(model)
    t0 = time.perf_counter()
    for state in states0[:k]:
        mujoco.mj_setState(model, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        for _ in range(nstep):
            mujoco.mj_step(model, d)
    wall = time.perf_counter() - t0
    print(f"python loop, one mj_step(nstep) call per collision: {k / wall:8.0f} collisions/s")


if __name__ == "__main__":
    main()
