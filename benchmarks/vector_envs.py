"""Batched vector envs against their engine's raw batched stepping and against gymnasium's SyncVectorEnv.

For each env, engine and N, three rates in env-steps per second (N copies x vector steps / s), zero actions (the
textbook problem, whose physics the raw step times; ``--actions random`` gives a new small random action every step,
as an agent would, and C MuJoCo's raw step one such action's inputs, held):

* ``raw``: the engine alone stepping N worlds of the env's model ``frame_skip`` steps per call
  (`rigidbench.engines.Worlds.raw_step`: C MuJoCo's `mujoco.batch`, MJX's jitted scan, Warp's captured graph),
  with no observation, reward or transfer: the most a batched env on that engine could reach;
* ``batched``: ``gymnasium.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point", engine=...)``;
* ``sync``: ``gymnasium.make_vec(id, num_envs=N, vectorization_mode="sync")`` (N single envs on C MuJoCo).

Rounds alternate the three; the medians are printed (and written as JSON with ``--json``), the ratios as the
median of each round's own ratio. The targets of issue 15:
batched >= 0.8 raw on every engine, batched >= 1.8 sync on C MuJoCo at N = 1024.

Usage: ``python benchmarks/vector_envs.py [--envs HeavyTop-v0 ...] [--ns 1 64 1024] [--engines mujoco mjx warp]
[--device cpu] [--seconds 1] [--rounds 3] [--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time

import gymnasium as gym
import mujoco
import numpy as np

import rigidbench  # noqa: F401  (registers the envs)
from rigidbench import engines, outputs

ENVS = ("HeavyTop-v0", "SimplePendulum-v0", "StruckStick-v0", "HardSpheres-v0")


def _rate(step, n: int, seconds: float) -> float:
    step()  # warm: compile, capture, first touch
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        step()
        count += 1
    return count * n / (time.perf_counter() - start)


def raw_worlds(env_id: str, n: int, engine, frame_skip: int | None, actions: str = "zero"):
    """The engine's worlds of the env's model, at its initial state, and their bare step.

    The worlds are loaded again from the initial state at the envs' episode length (as the envs' autoresets do), so
    the raw step simulates what an episode simulates: stepping on past it would time another motion (the hard
    spheres' free flight after the collision costs 7.0 us a step, the episode's contact 10.4 us).

    With ``actions="random"`` the worlds carry the inputs of one random action of the same size, held: C MuJoCo skips
    zero applied forces, so a raw step with zero inputs is 2.2-3.0 us (4-5 %) cheaper than the physics the envs'
    random actions ask for (HeavyTop, StruckStick; 2026-11-26 (h)). C MuJoCo's raw step carries them (its `load`
    copies the inputs with the state); MJX's raw call passes its own device zeros (a traced program computes the same
    whatever the values) and Warp's launches with the inputs already on its device, zero (its `load` fills only the
    host arrays)."""
    env = gym.make(env_id, frame_skip=frame_skip).unwrapped
    env.reset(seed=0)
    if actions == "random":
        env.apply_action(env._checked_action(_action_pool(env.action_space.shape)[1]))
    worlds = engines.worlds(engine, env.model, n)
    ids = np.arange(n)
    worlds.load(ids, env.data)
    fs = env.frame_skip
    episode = max(1, math.ceil(env.episode_duration / (env.model.opt.timestep * fs)))
    count = [0]

    def step() -> None:
        if count[0] == episode:
            worlds.load(ids, env.data)
            count[0] = 0
        worlds.raw_step(fs)
        count[0] += 1

    return worlds, step


def _action_pool(shape: tuple[int, ...]) -> np.ndarray:
    """16 actions of `shape`, a tenth of the action space, float32 as an agent's (drawn beforehand and cycled, so
    drawing costs nothing in a timed step)."""
    return np.random.default_rng(0).uniform(-0.1, 0.1, (16, *shape)).astype(np.float32)


def vector_env(env_id: str, n: int, mode: str, frame_skip: int | None, actions: str = "zero", **engine_kwargs):
    kwargs = {} if frame_skip is None else {"frame_skip": frame_skip}
    if mode == "sync":
        envs = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", **kwargs)
    else:
        envs = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs, **engine_kwargs)
    envs.reset(seed=0)
    if actions == "zero":
        zero = np.zeros(envs.action_space.shape)
        return envs, lambda: envs.step(zero)
    pool = _action_pool(envs.action_space.shape)
    count = [0]

    def step():
        count[0] += 1
        return envs.step(pool[count[0] % len(pool)])

    return envs, step


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", nargs="+", default=list(ENVS))
    parser.add_argument("--ns", nargs="+", type=int, default=[1, 64, 1024])
    parser.add_argument("--engines", nargs="+", default=["mujoco"], choices=engines.ENGINES)
    parser.add_argument("--device", default=None)
    parser.add_argument("--precision", default=None)
    parser.add_argument("--frame-skip", type=int, default=None, help="default: each env's own")
    parser.add_argument("--seconds", type=float, default=1.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-sync", action="store_true", help="skip SyncVectorEnv (slow to build at N = 1024)")
    parser.add_argument("--actions", choices=("zero", "random"), default="zero")
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    if args.json:
        outputs.check(args.json, "--json")  # before anything is measured
    print(
        f"mujoco {mujoco.__version__}, {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs "
        f"(load {os.getloadavg()[0]:.1f}); medians of {args.rounds} alternating rounds of {args.seconds:g} s"
    )
    print(f"{'env':22s} {'engine':18s} {'N':>5s} {'raw':>9s} {'batched':>9s} {'b/raw':>6s} {'sync':>8s} {'b/sync':>6s}")
    rows = []
    for name in args.envs:
        env_id = name if "/" in name else f"rigidbench/{name}"
        for engine_name in args.engines:
            # --device and --precision are the batched engines' (C MuJoCo runs on the CPU in float64)
            device, precision = (None, None) if engine_name == "mujoco" else (args.device, args.precision)
            engine = engines.engine_for(engine_name, device=device, precision=precision)
            label = "mujoco" if engine is None else f"{engine.name} {engine.precision} {engine.device}"
            kw = {"engine": engine_name, "device": device, "precision": precision}
            for n in args.ns:
                try:
                    built = {
                        "raw": raw_worlds(env_id, n, engine, args.frame_skip, args.actions),
                        "batched": vector_env(env_id, n, "batched", args.frame_skip, args.actions, **kw),
                    }
                except engines.EngineRefused as exc:  # a model the engine cannot simulate: say so, go on
                    print(f"{name:22s} {label:18s} {n:5d} unsupported: {exc}", flush=True)
                    rows.append({"env": env_id, "engine": label, "n": n, "unsupported": str(exc)})
                    break
                if engine is None and not args.no_sync:
                    built["sync"] = vector_env(env_id, n, "sync", args.frame_skip, args.actions)
                rates: dict[str, list[float]] = {key: [] for key in built}
                for _ in range(args.rounds):
                    for key, (_, step) in built.items():
                        rates[key].append(_rate(step, n, args.seconds))
                for obj, _ in built.values():
                    obj.close()
                med = {key: float(np.median(v)) for key, v in rates.items()}
                sync = med.get("sync", float("nan"))
                # The ratios are medians over the rounds of each round's own ratio: the two rates of a round were
                # measured a second apart, so a slow spell of this VM (rates vary by up to 25 % between runs) moves
                # both.
                paired = np.array(rates["batched"]) / np.array(rates["raw"])
                row = {"env": env_id, "engine": label, "n": n, **med, "batched_over_raw": float(np.median(paired))}
                row["batched_over_raw_rounds"] = paired.round(3).tolist()
                row["batched_over_sync"] = (
                    float(np.median(np.array(rates["batched"]) / np.array(rates["sync"]))) if "sync" in rates else sync
                )
                rows.append(row)
                print(
                    f"{name:22s} {label:18s} {n:5d} {med['raw']:9.0f} {med['batched']:9.0f} "
                    f"{row['batched_over_raw']:6.2f} {sync:8.0f} {row['batched_over_sync']:6.2f}",
                    flush=True,
                )
                if args.json:  # after every row, atomically: a run cut short keeps the rows it measured, whole
                    record = {"mujoco": mujoco.__version__, "cpus": os.cpu_count(), "rows": rows}
                    outputs.write(args.json, json.dumps(record, indent=1), "--json")


if __name__ == "__main__":
    try:
        main()
    except outputs.OutputError as exc:
        sys.exit(f"vector_envs.py: {exc}")
    except KeyboardInterrupt:  # --json holds the rows finished before it, whole
        sys.exit("vector_envs.py: interrupted")
