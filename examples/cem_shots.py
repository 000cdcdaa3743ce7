"""A plain black-box optimiser learns the one-shot tasks, and is compared with the theory's action.

The cross-entropy method (numpy only) searches the normalised action box [-1, 1]^n of ``CueShot-v0`` and
``ScatterToAngle-v0`` for a fixed target: sample a Gaussian population, keep the best fraction by simulated
reward, refit the mean and spread, repeat. It knows nothing of the physics; the theory does: the script prints
the distance from the optimiser's final mean to the nearest of ``env.unwrapped.theory_actions()`` (B1/B2 for the
cue: strike at 2R/5 above the centre with v0 = the target speed; C2/C3 for the spheres: an impact parameter
whose LAB angle is the target, on either branch, or the critical one b0 when the target exceeds the maximum LAB
angle).

Usage: ``python examples/cem_shots.py [--iterations 12] [--population 24] [--seed 0]``
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import rigidbench  # noqa: F401  (registers the envs)


@dataclass
class Search:
    """The optimiser's result: final mean action, its reward, the theory action and its reward."""

    mean: np.ndarray
    reward: float
    theory: np.ndarray
    theory_reward: float
    evaluations: int

    @property
    def distance(self) -> float:
        """Euclidean distance (normalised action units) from the final mean to the theory action."""
        return float(np.linalg.norm(self.mean - self.theory))


def cross_entropy_search(
    env_id: str,
    target: dict[str, float],
    *,
    iterations: int = 12,
    population: int = 24,
    elite_fraction: float = 0.25,
    seed: int = 0,
) -> Search:
    """Maximise the one-step reward of `env_id` at a fixed `target` with the cross-entropy method.

    Raises
    ------
    ValueError
        If `iterations` or `population` < 1, or `elite_fraction` is not in (0, 1].
    """
    if iterations < 1 or population < 1 or not 0 < elite_fraction <= 1:
        raise ValueError(
            f"need iterations, population >= 1 and elite_fraction in (0, 1]; got {iterations}, "
            f"{population}, {elite_fraction}"
        )
    env = gym.make(env_id, regret=False).unwrapped
    rng = np.random.default_rng(seed)
    low, high = env.action_space.low, env.action_space.high
    mean = (low + high) / 2
    std = (high - low) / 4
    n_elite = max(1, round(elite_fraction * population))

    def reward(action: np.ndarray) -> float:
        env.reset(options={"target": target})
        return float(env.step(action)[1])

    evaluations = 0
    for _ in range(iterations):
        samples = np.clip(rng.normal(mean, std, size=(population, mean.size)), low, high)
        rewards = np.array([reward(a) for a in samples])
        evaluations += population
        elite = samples[np.argsort(rewards)[-n_elite:]]
        mean = elite.mean(axis=0)
        std = elite.std(axis=0) + 1e-3 * (high - low)  # a floor keeps the search from freezing early
    env.reset(options={"target": target})
    # The optimum nearest to where the search ended (a heavy projectile reaches an angle on two branches).
    theory = min(env.theory_actions(), key=lambda a: float(np.linalg.norm(a - mean)))
    result = Search(mean, reward(mean), theory, reward(theory), evaluations + 2)
    env.close()
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=12)
    parser.add_argument("--population", type=int, default=24)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    for env_id in ("rigidbench/CueShot-v0", "rigidbench/ScatterToAngle-v0"):
        if env_id not in gym.registry:
            print(f"{env_id}: not registered (its scenario family is not installed)")
            continue
        env = gym.make(env_id).unwrapped
        target = {k: v for k, v in env.reset(seed=args.seed)[1]["target"].items() if k in env._target_ranges()}
        s = cross_entropy_search(env_id, target, iterations=args.iterations, population=args.population, seed=args.seed)
        print(
            f"{env_id}: target {target}; CEM mean {np.round(s.mean, 4)} (reward {s.reward:.3g}), theory "
            f"{np.round(s.theory, 4)} (reward {s.theory_reward:.3g}); distance {s.distance:.3g} after "
            f"{s.evaluations} episodes"
        )


if __name__ == "__main__":
    main()
