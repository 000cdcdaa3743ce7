"""Vector envs: gymnasium's sync vector env against rigidbench's batched one (`rigidbench.envs.batched`).

The batched vector env steps the N copies' physics in one threaded `mujoco.rollout` call (the torque actions as
``control_spec = mjSTATE_XFRC_APPLIED | mjSTATE_CTRL``) and still runs each copy's Python for the observation
and reward. The physics-only rollout is an upper bound on its throughput. The rounds alternate between the
implementations and the median is reported, since a shared machine's load changes from second to second.

Usage: ``python benchmarks/vector_envs.py [--seconds 1] [--rounds 3] [--nthread 2]``
"""

from __future__ import annotations

import argparse
import os
import time

import gymnasium as gym
import mujoco
import numpy as np
from mujoco import rollout

import rigidbench  # noqa: F401  (registers the envs)


def vector_rate(env_id: str, n: int, seconds: float, mode: str | None, nthread: int | None = None) -> float:
    """Env-steps per second of ``gym.make_vec(env_id, num_envs=n, vectorization_mode=mode)``, zero actions."""
    kwargs = {} if nthread is None else {"nthread": nthread}
    envs = gym.make_vec(env_id, num_envs=n, vectorization_mode=mode, **kwargs)
    envs.reset(seed=0)
    actions = np.zeros(envs.action_space.shape)
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        envs.step(actions)
        count += 1
    rate = count * n / (time.perf_counter() - start)
    envs.close()
    return rate


def rollout_rate(env_id: str, n: int, seconds: float, nthread: int) -> float:
    """Env-steps per second of the physics alone: N copies, frame_skip steps each, one threaded rollout call."""
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    model, spec = env.model, mujoco.mjtState.mjSTATE_FULLPHYSICS
    control_spec = mujoco.mjtState.mjSTATE_XFRC_APPLIED | mujoco.mjtState.mjSTATE_CTRL
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, env.data, state, spec)
    states = np.tile(state, (n, 1))
    control = np.zeros((n, 1, mujoco.mj_stateSize(model, control_spec)))
    out = np.empty((n, env.frame_skip, state.size))
    datas = [mujoco.MjData(model) for _ in range(nthread)]
    models, nstep = [model] * n, env.frame_skip
    count = 0
    with rollout.Rollout(nthread=nthread) as pool:
        start = time.perf_counter()
        while time.perf_counter() - start < seconds:
            pool.rollout(models, datas, states, control, control_spec=control_spec, nstep=nstep, state=out)
            count += 1
        return count * n / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=1.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--nthread", type=int, default=os.cpu_count())
    args = parser.parse_args()
    load = os.getloadavg()[0]
    print(f"mujoco {mujoco.__version__}, {os.cpu_count()} CPUs (load {load:.1f}), rollout nthread = {args.nthread}")
    print(f"{'env (env-steps/s, median)':36s} {'N':>4s} {'sync':>8s} {'batched':>8s} {'physics only':>13s}")
    for env_id in ("rigidbench/HeavyTop-v0", "rigidbench/FreeSymmetricTop-v0", "rigidbench/TopPrecession-v0"):
        for n in (8, 32):
            rates = {"sync": [], "batched": [], "physics": []}
            for _ in range(args.rounds):
                rates["sync"].append(vector_rate(env_id, n, args.seconds, "sync"))
                rates["batched"].append(vector_rate(env_id, n, args.seconds, None, args.nthread))
                rates["physics"].append(rollout_rate(env_id, n, args.seconds, args.nthread))
            sync, batched, physics = (float(np.median(rates[k])) for k in ("sync", "batched", "physics"))
            print(f"{env_id:36s} {n:4d} {sync:8.0f} {batched:8.0f} {physics:13.0f}")


if __name__ == "__main__":
    main()
