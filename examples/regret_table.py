"""Mean regret of the theory policy and of a random policy on every control task, over seeded episodes.

Regret is the env's own ``info["regret"]`` summed over an episode: against the closed form of the theory action
for the one-shot tasks, against the baseline simulated from the same initial state for the closed-loop ones
(`rigidbench.envs.task`). Episode i is seeded with i; the random policy's action space is seeded with 0.

Usage: ``python examples/regret_table.py [--shots 30] [--loops 5]``
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

from rigidbench import registry
from rigidbench.envs.task import ShotTask, TaskEnv


def mean_regret(env_id: str, policy: str, episodes: int) -> tuple[float, float]:
    """Mean and largest summed regret over `episodes` seeded episodes of `policy` ("theory" or "random")."""
    env = gym.make(env_id).unwrapped
    env.action_space.seed(0)
    totals = []
    for seed in range(episodes):
        env.reset(seed=seed)
        total = 0.0
        while True:
            action = env.theory_action() if policy == "theory" else env.action_space.sample()
            _obs, _reward, terminated, truncated, info = env.step(action)
            total += info["regret"]
            if terminated or truncated:
                break
        totals.append(total)
    env.close()
    return float(np.mean(totals)), float(np.max(totals))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shots", type=int, default=30, help="episodes per one-shot task")
    parser.add_argument("--loops", type=int, default=5, help="episodes per closed-loop task")
    args = parser.parse_args()
    print(f"{'task':40s} {'episodes':>8s} {'theory mean':>12s} {'theory max':>11s} {'random mean':>12s} {'s':>6s}")
    for env_id, cls in sorted(registry.env_classes().items()):
        if not issubclass(cls, TaskEnv):
            continue
        n = args.shots if issubclass(cls, ShotTask) else args.loops
        start = time.perf_counter()
        theory_mean, theory_max = mean_regret(env_id, "theory", n)
        random_mean, _ = mean_regret(env_id, "random", n)
        wall = time.perf_counter() - start
        print(f"{env_id:40s} {n:8d} {theory_mean:12.3g} {theory_max:11.3g} {random_mean:12.3g} {wall:6.1f}")


if __name__ == "__main__":
    main()
