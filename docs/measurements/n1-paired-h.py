"""The paired N = 1 measurements of 2026-11-26 (h), kept as run: a vector env of one with a previous version of one
function (copied here) against the current one, alternating in one process with the engine's raw step.

* ``one-array``: `VectorScenarioEnv._step_one` on C MuJoCo (vector-n1-one-array-h.txt; 300 rounds of 0.02 s);
* ``mjx-advance``: `MjxWorlds.advance` on MJX float32 (mjx-n1-advance-h.txt; 80 rounds of 0.03 s).

Usage: ``python docs/measurements/n1-paired-h.py {one-array,mjx-advance} HeavyTop-v0 [rounds]``
"""

import sys
import time

import gymnasium as gym
import numpy as np

import rigidbench  # noqa: F401  (registers the envs)
import rigidbench.envs.vector as V
from rigidbench import engines


def old_step_one(self, actions):
    """`VectorScenarioEnv._step_one` before 2026-11-26 (h): the single env's step, its info wrapped by `_one`."""
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


# what: (the class whose method is compared, its name, the old version, the engine, seconds a round, rounds)
WHAT = {
    "one-array": (V.VectorScenarioEnv, "_step_one", old_step_one, None, 0.02, 300),
    "mjx-advance": (engines.MjxWorlds, "advance", old_advance, "mjx", 0.03, 80),
}


def _us_per_call(f, seconds: float) -> float:
    f()
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        f()
        count += 1
    return (time.perf_counter() - start) / count * 1e6


def main() -> None:
    what, name = sys.argv[1], sys.argv[2]
    cls, method, old, engine, seconds, rounds = WHAT[what]
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else rounds
    new = getattr(cls, method)
    env = gym.make_vec(f"rigidbench/{name}", num_envs=1, vectorization_mode="vector_entry_point", engine=engine)
    env.reset(seed=0)
    template = env.unwrapped.env
    fs = template.frame_skip
    if engine is None:  # C MuJoCo's batch of one world (a batch of one env steps its template's `MjData` instead)
        worlds = engines.worlds(None, template.model, 1)
        worlds.load(np.arange(1), template.data)
    else:
        worlds = env.unwrapped.worlds
    action = np.zeros((1, *env.single_action_space.shape))
    times: dict[str, list[float]] = {"raw": [], "old": [], "new": []}
    for _ in range(rounds):
        times["raw"].append(_us_per_call(lambda: worlds.raw_step(fs), seconds))
        for label, version in (("old", old), ("new", new)):
            setattr(cls, method, version)
            if engine is not None:
                env.reset(seed=0)
            times[label].append(_us_per_call(lambda: env.step(action), seconds))
    raw, old_t, new_t = (np.array(times[k]) for k in ("raw", "old", "new"))
    print(
        f"{name:20s} raw {np.median(raw):.1f} old {np.median(old_t):.1f} new {np.median(new_t):.1f} us; "
        f"ratio old {np.median(raw / old_t):.3f} new {np.median(raw / new_t):.3f}; "
        f"saved {np.median(old_t - new_t):.2f} us"
    )


if __name__ == "__main__":
    main()
