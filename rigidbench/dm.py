"""dm_env views of rigidbench's environments: the same scenario, the DeepMind `dm_env.Environment` API.

`DmEnv` wraps any registered gymnasium env (validation or task) without re-implementing physics,
measurement or reward: specs come from the gymnasium spaces, time steps from ``reset``/``step``. For
dm_control's own `control.Environment` (a `Physics` + `base.Task`), see `rigidbench.suite` (needs the ``dm``
extra).

Example
-------
>>> from rigidbench.dm import load
>>> env = load("heavy-top", case="looping")
>>> timestep = env.reset()
>>> timestep = env.step(np.zeros(3))
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import dm_env
import gymnasium as gym
import numpy as np
from dm_env import specs

from rigidbench import registry


class DmEnv(dm_env.Environment):
    """A `dm_env.Environment` over a rigidbench gymnasium env.

    Observations are ``{"observation": array}``; rewards are the gymnasium rewards (negative deviation from
    theory for validation envs); the discount is 1, and 0 on the last step of a terminated (diverged) episode;
    a truncated episode (the case's duration) also ends with a LAST step, with discount 1.
    """

    def __init__(self, env: gym.Env, *, options: Mapping[str, Any] | None = None, seed: int | None = None) -> None:
        self._env = env
        self._options = dict(options or {})
        self._seed = seed
        self._needs_reset = True
        self.last_info: dict[str, Any] = {}

    @property
    def gym_env(self) -> gym.Env:
        return self._env

    def reset(self) -> dm_env.TimeStep:
        obs, self.last_info = self._env.reset(seed=self._seed, options=self._options)
        self._seed = None  # seed once; later episodes continue the stream, as in gymnasium
        self._needs_reset = False
        return dm_env.restart({"observation": np.asarray(obs)})

    def step(self, action) -> dm_env.TimeStep:
        if self._needs_reset:
            return self.reset()
        obs, reward, terminated, truncated, self.last_info = self._env.step(action)
        observation = {"observation": np.asarray(obs)}
        if terminated:
            self._needs_reset = True
            return dm_env.termination(reward, observation)
        if truncated:
            self._needs_reset = True
            return dm_env.truncation(reward, observation)
        return dm_env.transition(reward, observation)

    def observation_spec(self) -> dict[str, specs.Array]:
        space = self._env.observation_space
        return {"observation": _spec(space, "observation")}

    def action_spec(self) -> specs.BoundedArray:
        # float64, as dm_control's actions are (the gymnasium space is float32 for SB3); bounds [-1, 1].
        space = self._env.action_space
        return specs.BoundedArray(space.shape, np.float64, space.low, space.high, name="action")

    def reward_spec(self) -> specs.Array:
        return specs.Array(shape=(), dtype=np.float64, name="reward")

    def close(self) -> None:
        self._env.close()


def _spec(space: gym.spaces.Box, name: str) -> specs.Array:
    if np.all(np.isfinite(space.low)) and np.all(np.isfinite(space.high)):
        return specs.BoundedArray(space.shape, space.dtype, space.low, space.high, name=name)
    return specs.Array(space.shape, space.dtype, name=name)


def load(scenario: str, *, case: str | None = None, params: Mapping[str, Any] | None = None, **env_kwargs) -> DmEnv:
    """The dm_env view of a scenario's gymnasium env (or of a task env id such as ``"rigidbench/CueShot-v0"``).

    Parameters
    ----------
    scenario : str
        A scenario slug (``"heavy-top"``) or a registered gymnasium id.
    case, params :
        Passed to the env's ``reset(options=...)`` every episode.
    **env_kwargs :
        Constructor arguments of the gymnasium env (``profile``, ``integrator``, ``timestep``, ``frame_skip``).

    Raises
    ------
    ValueError
        For an unknown scenario or id, or invalid options.
    """
    env_id = scenario if "/" in scenario else registry.get(scenario).env_id
    if env_id is None:
        raise ValueError(f"scenario '{scenario}' has no stepping environment (a batch scenario): no dm_env view")
    if env_id not in gym.registry:
        raise ValueError(f"unknown environment {env_id!r}")
    env = gym.make(env_id, **env_kwargs).unwrapped
    options = {k: v for k, v in (("case", case), ("params", params)) if v is not None}
    if options:
        env.reset(options=options)  # validate now, not at the first reset
    return DmEnv(env, options=options)
