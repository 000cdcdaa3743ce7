"""The measurement in vector-n1-one-array-h.txt (2026-11-26 (h)), kept as run: a vector env of one on C MuJoCo with
the previous `VectorScenarioEnv._step_one` (copied here) against the current one, alternating in one process with
the raw `mujoco.batch` step of one world.

Usage: ``python docs/measurements/vector-n1-one-array-h.py StruckStick-v0 [rounds]``
"""

import sys
import time

import gymnasium as gym
import numpy as np

import rigidbench  # noqa: F401  (registers the envs)
import rigidbench.envs.vector as V
from rigidbench import engines


def old_step_one(self, actions):
    """`_step_one` before 2026-11-26 (h): the single env's step, its info wrapped by `_one`."""
    actions = np.asarray(actions)
    if actions.shape != (1, *self.single_action_space.shape):
        raise ValueError(actions.shape)
    env = self.env
    if self._autoreset[0]:
        obs, info = self._start_episode(None)
        self._autoreset[0] = False
        return obs[None], np.zeros(1), np.zeros(1, dtype=bool), np.zeros(1, dtype=bool), V._put({}, info, V._ONE, 1)
    obs, reward, terminated, truncated, info = env.step(actions[0])
    self._autoreset[0] = terminated or truncated
    return obs[None], np.array([reward], dtype=float), np.array([terminated]), np.array([truncated]), V._one(info)


def _us_per_call(f, seconds: float = 0.02) -> float:
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        f()
        count += 1
    return (time.perf_counter() - start) / count * 1e6


def main() -> None:
    name, rounds = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 300
    new_step_one = V.VectorScenarioEnv._step_one
    env = gym.make_vec(f"rigidbench/{name}", num_envs=1, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    action = np.zeros((1, *env.single_action_space.shape))
    worlds = engines.worlds(None, env.env.model, 1)
    worlds.load(np.arange(1), env.env.data)
    fs = env.env.frame_skip
    raw, old, new = [], [], []
    for _ in range(rounds):
        raw.append(_us_per_call(lambda: worlds.raw_step(fs)))
        V.VectorScenarioEnv._step_one = old_step_one
        old.append(_us_per_call(lambda: env.step(action)))
        V.VectorScenarioEnv._step_one = new_step_one
        new.append(_us_per_call(lambda: env.step(action)))
    raw, old, new = map(np.array, (raw, old, new))
    print(
        f"{name:20s} raw {np.median(raw):.1f} old {np.median(old):.1f} new {np.median(new):.1f} us; "
        f"ratio old {np.median(raw / old):.3f} new {np.median(raw / new):.3f}; saved {np.median(old - new):.2f} us"
    )


if __name__ == "__main__":
    main()
