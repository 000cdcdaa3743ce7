"""Vector envs: gymnasium's sync vector env against the best a batched (`mujoco.rollout`) one could do.

A batched vector env would step the N copies' physics in one threaded `mujoco.rollout` call (the actions as
``control_spec = mjSTATE_XFRC_APPLIED | mjSTATE_QFRC_APPLIED | mjSTATE_CTRL``) and still run each copy's
Python for the observation and reward. The physics-only rollout below is an upper bound on its throughput.

Measured (mujoco 4.0, 2 shared CPUs, load ~3.5, medians of 3 alternating 1 s rounds, env-steps/s): sync
11.5k-12k on the tops at N = 8 and 32, physics-only 13.5k-19k; a batched implementation that wrote each
copy's state back and scored it with the env's own hooks (bit-identical to single envs) reached 10k-13k, and
5k-7k on TopPrecession: no faster than sync, so it was not kept. Beating sync here would take scoring the batch
in numpy as well, for at most the physics-only bound (1.2-1.6x).

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


def vector_rate(env_id: str, n: int, seconds: float, mode: str | None) -> float:
    """Env-steps per second of ``gym.make_vec(env_id, num_envs=n, vectorization_mode=mode)``, zero actions."""
    envs = gym.make_vec(env_id, num_envs=n, vectorization_mode=mode)
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
    control_spec = (
        mujoco.mjtState.mjSTATE_XFRC_APPLIED | mujoco.mjtState.mjSTATE_QFRC_APPLIED | mujoco.mjtState.mjSTATE_CTRL
    )
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
    print(f"{'env (env-steps/s, median)':36s} {'N':>4s} {'sync':>8s} {'physics only':>13s}")
    for env_id in ("rigidbench/HeavyTop-v0", "rigidbench/FreeSymmetricTop-v0", "rigidbench/TopPrecession-v0"):
        for n in (8, 32):
            rates = {"sync": [], "physics": []}
            for _ in range(args.rounds):
                rates["sync"].append(vector_rate(env_id, n, args.seconds, "sync"))
                rates["physics"].append(rollout_rate(env_id, n, args.seconds, args.nthread))
            sync, physics = (float(np.median(rates[k])) for k in ("sync", "physics"))
            print(f"{env_id:36s} {n:4d} {sync:8.0f} {physics:13.0f}")


if __name__ == "__main__":
    main()
