"""PPO and SAC (Stable-Baselines3), the cross-entropy method, a random and the theory policy on the five control tasks.

Each learner trains at a fixed budget of env steps from seed 0 and is then scored on held-out episodes (seeds
10 000, 10 001, ...: targets the training never drew), as is every other policy: the mean over those episodes of
the summed ``info["regret"]`` (the theory action's reward minus the reward taken: against the closed form for the
one-shot tasks, against the baseline simulated from the same initial state for the closed-loop ones;
`rigidbench.envs.task`) and of the return. Nothing here is tuned:

* **PPO**: SB3's defaults, except ``n_steps=64, batch_size=32`` on the one-shot tasks, where the default rollout
  of 2048 steps is four times the budget and would leave PPO without a single update (the budget gives it 8).
* **SAC**: SB3's defaults.
* Both see the env's own action space: float32, normalised to [-1, 1] (the closed-loop tasks' torque is
  ``action_scale`` times it), as SB3 recommends; no wrapper.
* **CEM** (`examples/cem_shots.py`, imported, not copied): one-shot tasks only. It is a search per target, not a
  policy: for each evaluation episode it searches that episode's target (4 generations of 12 + 2 = 50 simulated
  shots each, about the learners' budget over the 10 targets) and is scored on its final mean. It gets what the
  learners do not: repeated resets at the target it is scored on. "n/a" on the closed-loop tasks (no such search).
* **random**: uniform actions, the action space seeded with 0. **theory**: ``env.unwrapped.theory_action()``.

torch runs on the CPU with one thread (``torch.set_num_threads(1)``): the networks are SB3's small MLPs, and the
machine this was measured on has two cores shared with other work.

Learning curves: ``--curves PATH.png`` also scores PPO and SAC on the same held-out episodes at `CHECKPOINTS`
evenly spaced points of their training (and before it) and plots mean regret against env steps, with the random,
theory and CEM levels (needs matplotlib, the `report` extra). The evaluations use their own envs and deterministic
actions, so the training, and the final row, are the same with or without them.

Usage: ``python benchmarks/rl_baselines.py [--json PATH] [--curves PATH.png] [--quick]`` (needs the `rl` extra:
docs/gymnasium.md); ``--quick`` cuts every budget and evaluation tenfold, to check that the script runs, not to
report.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.callbacks import BaseCallback

import rigidbench
from rigidbench.envs.task import ShotTask

ROOT = Path(__file__).resolve().parents[1]
TASKS = (
    "rigidbench/CueShot-v0",
    "rigidbench/PercussionStrike-v0",
    "rigidbench/ScatterToAngle-v0",
    "rigidbench/TopPrecession-v0",
    "rigidbench/PendulumEnergyTransfer-v0",
)
# Env steps of training per learner and task; one-shot tasks: one step = one whole shot (0.02-0.1 s of CPU each).
SHOT_BUDGET = 512
LOOP_BUDGET = 10_000
# Held-out evaluation episodes per policy and task.
SHOT_EPISODES = 10
LOOP_EPISODES = 3
EVAL_SEED = 10_000
TRAIN_SEED = 0
CEM = {"iterations": 4, "population": 12}  # 50 simulated shots per target, with the final two evaluations
METHODS = ("theory", "random", "PPO", "SAC", "CEM")
CHECKPOINTS = 8  # learning-curve points after the start (--curves)


def _cem_module():
    path = ROOT / "examples" / "cem_shots.py"
    spec = importlib.util.spec_from_file_location("cem_shots", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["cem_shots"] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def make_env(env_id: str) -> gym.Env:
    """The env as the learners see it: as registered (its action is normalised already)."""
    return gym.make(env_id)


def evaluate(env_id: str, act: Callable[[gym.Env, np.ndarray, int], np.ndarray], episodes: int) -> dict:
    """Mean summed regret and mean return of `act` (env, observation, episode index) -> action over `episodes`
    held-out episodes (seeds EVAL_SEED + i) of `make_env(env_id)`."""
    env = make_env(env_id)
    env.action_space.seed(0)
    regrets, returns = [], []
    for i in range(episodes):
        obs, _ = env.reset(seed=EVAL_SEED + i)
        regret = total = 0.0
        while True:
            obs, reward, terminated, truncated, info = env.step(act(env, obs, i))
            regret += info["regret"]
            total += reward
            if terminated or truncated:
                break
        regrets.append(regret)
        returns.append(total)
    env.close()
    return {"regret": float(np.mean(regrets)), "return": float(np.mean(returns)), "episodes": episodes}


def _theory(env: gym.Env, _obs, _i) -> np.ndarray:
    return env.unwrapped.theory_action()


def _random(env: gym.Env, _obs, _i) -> np.ndarray:
    return env.action_space.sample()


class _Curve(BaseCallback):
    """Scores the model on the held-out episodes at the start and every `budget // CHECKPOINTS` env steps."""

    def __init__(self, env_id: str, budget: int, episodes: int) -> None:
        super().__init__()
        self.env_id, self.budget, self.episodes = env_id, budget, episodes
        self.every = max(1, budget // CHECKPOINTS)
        self.points: list[tuple[int, float]] = []

    def _score(self) -> None:
        policy = lambda _env, obs, _i: self.model.predict(obs, deterministic=True)[0]  # noqa: E731
        self.points.append((self.num_timesteps, evaluate(self.env_id, policy, self.episodes)["regret"]))

    def _on_training_start(self) -> None:
        self._score()

    def _on_step(self) -> bool:
        # the point at the end of training is the final evaluation (`run`), after the last update
        if self.every * len(self.points) <= self.num_timesteps < self.budget:
            self._score()
        return True


def _learner(env_id: str, algo: str, budget: int, curve: _Curve | None = None):
    env = make_env(env_id)
    kwargs = {}
    if algo == "PPO" and issubclass(type(env.unwrapped), ShotTask):
        kwargs = {"n_steps": 64, "batch_size": 32}
    cls = {"PPO": PPO, "SAC": SAC}[algo]
    model = cls("MlpPolicy", env, seed=TRAIN_SEED, device="cpu", **kwargs)
    model.learn(total_timesteps=budget, callback=curve)
    env.close()
    # PPO finishes its last rollout: 10 240 steps for a budget of 10 000 at the default n_steps = 2048
    return (lambda _env, obs, _i: model.predict(obs, deterministic=True)[0]), model.num_timesteps


def _cem_policy(env_id: str, episodes: int, cem, settings: dict) -> Callable:
    """CEM's final mean for each evaluation episode's target, searched before the episode is played."""
    probe = gym.make(env_id).unwrapped
    actions = []
    for i in range(episodes):
        target = probe.reset(seed=EVAL_SEED + i)[1]["target"]
        target = {k: v for k, v in target.items() if k in probe._target_ranges()}
        actions.append(cem.cross_entropy_search(env_id, target, seed=TRAIN_SEED, **settings).mean)
    probe.close()
    return lambda _env, _obs, i: actions[i]


def run(quick: bool = False, curves: bool = False) -> list[dict]:
    """One row per (task, method): mean regret and return over the held-out episodes, budget and wall time (and,
    with `curves`, the learners' ``curve``: (env steps, mean regret) pairs)."""
    scale = 10 if quick else 1
    cem = _cem_module()
    rows = []
    for env_id in TASKS:
        shot = issubclass(type(gym.make(env_id).unwrapped), ShotTask)
        budget = (SHOT_BUDGET if shot else LOOP_BUDGET) // scale
        episodes = max(1, (SHOT_EPISODES if shot else LOOP_EPISODES) // scale)
        for method in METHODS:
            start = time.perf_counter()
            if method == "CEM" and not shot:
                rows.append({"task": env_id, "method": method, "regret": None, "return": None, "budget": None})
                continue
            if method == "theory":
                policy, steps = _theory, 0
            elif method == "random":
                policy, steps = _random, 0
            elif method == "CEM":
                settings = {"iterations": 2, "population": 4} if quick else CEM
                policy = _cem_policy(env_id, episodes, cem, settings)
                evaluations = settings["iterations"] * settings["population"] + 2
                steps = evaluations * episodes
            else:
                curve = _Curve(env_id, budget, episodes) if curves else None
                policy, steps = _learner(env_id, method, budget, curve)
            result = evaluate(env_id, policy, episodes)
            rows.append(
                {"task": env_id, "method": method, **result, "budget": steps, "wall_s": time.perf_counter() - start}
            )
            if method in ("PPO", "SAC") and curves:
                rows[-1]["curve"] = [*curve.points, (steps, result["regret"])]
            print(f"{env_id} {method}: {rows[-1]}", file=sys.stderr, flush=True)
    return rows


def plot_curves(rows: list[dict], path: Path) -> None:
    """Mean held-out regret against env steps of training, one panel per task, with the fixed policies' levels."""
    from rigidbench.plots import pyplot

    plt = pyplot()
    fig, axes = plt.subplots(1, len(TASKS), figsize=(4 * len(TASKS), 3.4), layout="constrained")
    for ax, env_id in zip(axes, TASKS, strict=True):
        by = {r["method"]: r for r in rows if r["task"] == env_id}
        for method, style in (("PPO", "o-"), ("SAC", "s-")):
            steps, regret = np.array(by[method]["curve"], dtype=float).T
            ax.plot(steps, regret, style, ms=3, label=method)
        for method, colour in (("random", "grey"), ("theory", "black"), ("CEM", "tab:green")):
            if by[method]["regret"] is not None:
                ax.axhline(by[method]["regret"], color=colour, ls="--", lw=1, label=method)
        ax.set_title(env_id.split("/")[1], fontsize=10)
        ax.set_xlabel("env steps of training")
    axes[0].set_ylabel("mean regret, held-out episodes")
    axes[0].legend(fontsize=8)
    fig.savefig(path, dpi=80)
    plt.close(fig)


def _cell(row: dict) -> str:
    if row["regret"] is None:
        return "n/a"
    return f"{row['regret']:.3g} ({row['return']:.3g})"


def markdown(rows: list[dict]) -> str:
    """Mean regret (mean return) per task and method, one task a row."""
    lines = ["| task | " + " | ".join(METHODS) + " |", "|---" * (len(METHODS) + 1) + "|"]
    for env_id in TASKS:
        cells = {r["method"]: _cell(r) for r in rows if r["task"] == env_id}
        lines.append(f"| `{env_id.split('/')[1]}` | " + " | ".join(cells[m] for m in METHODS) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, help="write the rows and the run's settings here")
    parser.add_argument("--curves", type=Path, help="plot the learning curves into this PNG (needs matplotlib)")
    parser.add_argument("--quick", action="store_true", help="budgets and evaluations / 10: a smoke run")
    args = parser.parse_args()
    torch.set_num_threads(1)
    start = time.perf_counter()
    rows = run(quick=args.quick, curves=args.curves is not None)
    wall = time.perf_counter() - start
    print(markdown(rows))
    if args.curves:
        plot_curves(rows, args.curves)
    import mujoco
    import stable_baselines3

    print(
        f"\nmean regret (mean return) over held-out episodes; budgets: {SHOT_BUDGET} shots / {LOOP_BUDGET} steps"
        f"{' / 10 (quick)' if args.quick else ''}; {wall:.0f} s; stable-baselines3 {stable_baselines3.__version__}, "
        f"torch {torch.__version__}, mujoco {mujoco.__version__}, rigidbench {rigidbench.__version__}"
    )
    if args.json:
        record = {
            "rows": rows,
            "quick": args.quick,
            "wall_s": wall,
            "budgets": {"shot": SHOT_BUDGET, "loop": LOOP_BUDGET},
            "episodes": {"shot": SHOT_EPISODES, "loop": LOOP_EPISODES},
            "eval_seed": EVAL_SEED,
            "train_seed": TRAIN_SEED,
            "cem": CEM,
            "versions": {
                "stable-baselines3": stable_baselines3.__version__,
                "torch": torch.__version__,
                "mujoco": mujoco.__version__,
                "python": platform.python_version(),
            },
        }
        args.json.write_text(json.dumps(record, indent=1, default=lambda v: None if math.isnan(v) else v))


if __name__ == "__main__":
    main()
