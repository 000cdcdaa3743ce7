"""The control tasks' speed at the validation reference against their task settings (issue 36), side by side.

For every task (`rigidbench.registry.env_classes`, the `TaskEnv`s), in one run and one process:

* one-shot tasks: shots per second of a single env under random actions (a reset and a step each), at
  ``profile="reference"`` (the task as it was) and ``profile="task"`` (its own settings, `TaskEnv.task_settings`);
* closed-loop tasks: env steps per second under random actions, and the median ``reset`` time (ms), both profiles;
* the theory action's regret at the task settings against the random policy's, each the mean |regret| over
  ``--seeds`` action seeds (seed s: ``reset(seed=s)``, actions from ``action_space`` seeded s; a closed-loop task
  scores an episode's summed regret, whose theory value is 0 by construction, `ClosedLoopTask`), and their
  ratio, which issue 36 wants at most 1 %.

Usage: ``python benchmarks/task_speed.py [--seeds 20] [--shots 20] [--steps 500] [--tasks CueShot-v0 ...]
[--markdown]``. Timings are wall-clock on whatever else the machine runs: they are comparable within one run.
"""

from __future__ import annotations

import argparse
import statistics
import time

import gymnasium as gym
import numpy as np

from rigidbench import registry
from rigidbench.envs.task import ClosedLoopTask, ShotTask

TASKS = (
    "CueShot-v0",
    "ScatterToAngle-v0",
    "PercussionStrike-v0",
    "TopPrecession-v0",
    "PendulumEnergyTransfer-v0",
)


def _make(task: str, profile: str) -> gym.Env:
    return gym.make(f"rigidbench/{task}", profile=profile).unwrapped


def shots_per_second(task: str, profile: str, shots: int) -> float:
    env = _make(task, profile)
    env.reset(seed=0)
    env.action_space.seed(0)
    t0 = time.perf_counter()
    for _ in range(shots):
        env.reset()
        env.step(env.action_space.sample())
    return shots / (time.perf_counter() - t0)


def closed_loop_speed(task: str, profile: str, steps: int, resets: int = 20) -> tuple[float, float]:
    """(env steps per second with regret on, median reset time in ms)."""
    env = _make(task, profile)
    env.reset(seed=0)
    env.action_space.seed(0)
    done, t0 = 0, time.perf_counter()
    while done < steps:
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        done += 1
        if terminated or truncated:
            env.reset()
    rate = steps / (time.perf_counter() - t0)
    times = []
    for _ in range(resets):
        t = time.perf_counter()
        env.reset()
        times.append(time.perf_counter() - t)
        env.step(env.action_space.sample())  # a step between resets, as in training
    return rate, 1e3 * statistics.median(times)


def _episode_regret(env, seed: int, policy) -> float:
    env.reset(seed=seed)
    env.action_space.seed(seed)
    total = 0.0
    while True:
        _, _, terminated, truncated, info = env.step(policy(env))
        total += info["regret"]
        if terminated or truncated:
            return total


def regrets(task: str, seeds: int) -> tuple[float, float]:
    """(mean |regret| of the theory action, of the random policy) at the task settings, over `seeds` seeds."""
    env = _make(task, "task")
    theory = [abs(_episode_regret(env, s, lambda e: e.theory_action())) for s in range(seeds)]
    random = [abs(_episode_regret(env, s, lambda e: e.action_space.sample())) for s in range(seeds)]
    return float(np.mean(theory)), float(np.mean(random))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=list(TASKS))
    ap.add_argument("--seeds", type=int, default=20, help="action seeds of the regret columns (default 20)")
    ap.add_argument("--shots", type=int, default=20, help="shots timed per one-shot task and profile")
    ap.add_argument("--steps", type=int, default=500, help="env steps timed per closed-loop task and profile")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    registry.register_envs()
    classes = registry.env_classes()
    header = (
        "task",
        "reference",
        "task settings",
        "speed-up",
        "reset ms (ref / task)",
        "settings",
        "theory regret",
        "random regret",
        "ratio",
    )
    rows = []
    for task in args.tasks:
        cls = classes[f"rigidbench/{task}"]
        if issubclass(cls, ShotTask):
            ref = shots_per_second(task, "reference", args.shots)
            new = shots_per_second(task, "task", args.shots)
            unit, resets = "shots/s", "-"
        elif issubclass(cls, ClosedLoopTask):
            ref, ref_reset = closed_loop_speed(task, "reference", args.steps)
            new, new_reset = closed_loop_speed(task, "task", args.steps)
            unit, resets = "steps/s", f"{ref_reset:.2f} / {new_reset:.2f}"
        else:
            continue
        settings = cls.task_settings or {"(reference)": ""}
        theory, random = regrets(task, args.seeds)
        rows.append(
            (
                task,
                f"{ref:.3g} {unit}",
                f"{new:.3g} {unit}",
                f"{new / ref:.2g}x",
                resets,
                " ".join(f"{k}={v}" for k, v in settings.items()).strip(),
                f"{theory:.3g}",
                f"{random:.3g}",
                f"{theory / random:.2%}" if random else "-",
            )
        )
        print("  ".join(rows[-1]), flush=True)
    if args.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
        for row in rows:
            print("| " + " | ".join(row) + " |")
    else:
        widths = [max(len(str(r[i])) for r in (header, *rows)) for i in range(len(header))]
        for row in (header, *rows):
            print("  ".join(str(v).ljust(w) for v, w in zip(row, widths, strict=True)))


if __name__ == "__main__":
    main()
