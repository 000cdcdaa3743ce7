"""The measurement in mjx-n1-advance-h.txt (2026-11-26 (h)), kept as run: a vector env of one on MJX (float32, CPU)
with the previous `MjxWorlds.advance` (copied here) against the current one, alternating in one process with the
raw call (the program back to back, zero inputs kept on the device).

Usage: ``python docs/measurements/mjx-n1-advance-h.py HeavyTop-v0 [rounds]``
"""

import sys
import time

import gymnasium as gym
import numpy as np

import rigidbench  # noqa: F401  (registers the envs)
from rigidbench import engines


def old_advance(self, data, nstep: int) -> None:
    """`MjxWorlds.advance` before 2026-11-26 (h)."""
    inputs = np.concatenate((data.ctrl, data.qfrc_applied, data.xfrc_applied.ravel()), dtype=self._np_dtype)
    self._d_bufs, state = self._program(self._m_bufs, self._d_bufs, inputs[None], nstep=nstep)
    state = np.asarray(state)[0]
    nq = self.model.nq
    data.qpos[:], data.qvel[:] = state[:nq], state[nq:]
    k = self._k.item() + nstep
    self._k[0] = k
    data.time = self._t0.item() + self.model.opt.timestep * k


def _us_per_call(f, seconds: float = 0.03) -> float:
    f()
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        f()
        count += 1
    return (time.perf_counter() - start) / count * 1e6


def main() -> None:
    name, rounds = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 80
    env = gym.make_vec(f"rigidbench/{name}", num_envs=1, vectorization_mode="vector_entry_point", engine="mjx")
    env.reset(seed=0)
    worlds = env.unwrapped.worlds
    fs = env.unwrapped.env.frame_skip
    new_advance = engines.MjxWorlds.advance
    action = np.zeros((1, *env.single_action_space.shape))
    worlds.raw_step(fs)  # compiles and places the raw call's zero inputs
    raw, old, new = [], [], []
    for _ in range(rounds):
        raw.append(_us_per_call(lambda: worlds.raw_step(fs)))
        engines.MjxWorlds.advance = old_advance
        env.reset(seed=0)
        old.append(_us_per_call(lambda: env.step(action)))
        engines.MjxWorlds.advance = new_advance
        env.reset(seed=0)
        new.append(_us_per_call(lambda: env.step(action)))
    raw, old, new = map(np.array, (raw, old, new))
    print(
        f"{name:20s} raw {np.median(raw):.1f} old {np.median(old):.1f} new {np.median(new):.1f} us; "
        f"ratio old {np.median(raw / old):.3f} new {np.median(raw / new):.3f}; saved {np.median(old - new):.2f} us"
    )


if __name__ == "__main__":
    main()
