"""The control tasks' speed at the validation reference against their task settings (issue 36), side by side.

For every task (`rigidbench.registry.env_classes`, the `TaskEnv`s), in one run and one process:

* one-shot tasks: shots per second of a single env under random actions (a reset and a step each), at
  ``profile="reference"`` (the task as it was) and ``profile="task"`` (its own settings, `TaskEnv.task_settings`);
* closed-loop tasks: env steps per second under random actions, and the median ``reset`` time (ms), both profiles,
  and the reset as it was before issue 36 (the whole baseline simulated at reset: the same rollout, forced);
* the theory action's regret at the task settings against the random policy's, each the mean |regret| over
  ``--seeds`` action seeds (seed s: ``reset(seed=s)``, actions from ``action_space`` seeded s; a closed-loop task
  scores an episode's summed regret, whose theory value is 0 by construction, `ClosedLoopTask`), and their
  ratio, which issue 36 wants at most 1 %.

Usage: ``python benchmarks/task_speed.py [--seeds 20] [--shots 20] [--steps 500] [--tasks CueShot-v0 ...]
[--markdown]``. Timings are wall-clock on whatever else the machine runs: they are comparable within one run.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import gymnasium as gym
import numpy as np

from rigidbench import registry
from rigidbench.envs.task import ClosedLoopTask, ShotTask

PROFILES = ("reference", "task")
ROUNDS = 10
TASKS = (
    "CueShot-v0",
    "ScatterToAngle-v0",
    "PercussionStrike-v0",
    "TopPrecession-v0",
    "PendulumEnergyTransfer-v0",
)


def _make(task: str, profile: str) -> gym.Env:
    return gym.make(f"rigidbench/{task}", profile=profile).unwrapped


def _shots(env, shots: int) -> float:
    """Seconds for `shots` one-shot episodes (a reset and a random step each)."""
    t0 = time.perf_counter()
    for _ in range(shots):
        env.reset()
        env.step(env.action_space.sample())
    return time.perf_counter() - t0


def _steps(env, steps: int) -> float:
    """Seconds for `steps` random env steps (regret on), resetting at each episode's end."""
    t0 = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
    return time.perf_counter() - t0


def _resets(env, resets: int, eager: bool = False) -> list[float]:
    """Each of `resets` resets' seconds (a random step between them, as in training). ``eager``: the reset as it was
    before issue 36, which simulated the whole baseline (reading `_reference` does that same rollout now)."""
    times = []
    for _ in range(resets):
        t = time.perf_counter()
        env.reset()
        if eager:
            _ = env._reference
        times.append(time.perf_counter() - t)
        env.step(env.action_space.sample())
    return times


def speeds(task: str, closed_loop: bool, work: int, rounds: int = ROUNDS) -> dict[str, tuple[float, float | None]]:
    """Per profile: (shots or env steps per second, median reset ms or None). The two profiles are timed in
    alternating rounds, so that a load that comes and goes during the run weighs on both alike."""
    envs = {profile: _make(task, profile) for profile in PROFILES}
    seconds = dict.fromkeys(PROFILES, 0.0)
    resets: dict[str, list[float]] = {profile: [] for profile in (*PROFILES, "eager")}
    for env in envs.values():
        env.reset(seed=0)
        env.action_space.seed(0)
    per_round = max(1, work // rounds)
    for _ in range(rounds):
        for profile, env in envs.items():
            if closed_loop:
                seconds[profile] += _steps(env, per_round)
                resets[profile] += _resets(env, 5)
                if profile == "reference":
                    resets["eager"] += _resets(env, 2, eager=True)
            else:
                seconds[profile] += _shots(env, per_round)
    out = {
        profile: (
            per_round * rounds / seconds[profile],
            1e3 * statistics.median(resets[profile]) if closed_loop else None,
        )
        for profile in PROFILES
    }
    out["eager"] = (math.nan, 1e3 * statistics.median(resets["eager"]) if closed_loop else None)
    return out


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
        "reset ms (before / ref / task)",
        "settings",
        "theory regret",
        "random regret",
        "ratio",
    )
    rows = []
    for task in args.tasks:
        cls = classes[f"rigidbench/{task}"]
        if not issubclass(cls, ShotTask | ClosedLoopTask):
            continue
        closed_loop = issubclass(cls, ClosedLoopTask)
        measured = speeds(task, closed_loop, args.steps if closed_loop else args.shots)
        (ref, ref_reset), (new, new_reset) = measured["reference"], measured["task"]
        unit = "steps/s" if closed_loop else "shots/s"
        eager_reset = measured["eager"][1]
        resets = f"{eager_reset:.0f} / {ref_reset:.2f} / {new_reset:.2f}" if closed_loop else "-"
        settings = cls.task_settings
        theory, random = regrets(task, args.seeds)
        rows.append(
            (
                task,
                f"{ref:.3g} {unit}",
                f"{new:.3g} {unit}",
                f"{new / ref:.2g}x",
                resets,
                " ".join(f"{k}={v}" for k, v in settings.items()) or "the reference's",
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
