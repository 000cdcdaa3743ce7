"""A batched vector env: N copies of a rigidbench env whose physics is stepped in one threaded `mujoco.rollout`.

``gymnasium.make_vec(id, num_envs=N)`` uses it for the envs registered with a ``vector_entry_point``
(`rigidbench.registry.register_envs`: those whose class sets ``batched = True``). Each copy is a full single env:
its own seeding, reset, action hook, observation, reward and theory. Only the physics moves: every copy applies
its action to its own MjData (``xfrc_applied`` or ``ctrl``), the states and those inputs go to one
`mujoco.rollout` call (``control_spec = mjSTATE_XFRC_APPLIED | mjSTATE_CTRL``) of ``frame_skip`` steps on
``nthread`` threads, and each final state is written back before the copy scores it. Rollout steps with
`mj_step`, from the full physics state, so a copy's results equal the single env's bit for bit: for models
without contacts (the solver's warm start is not part of that state), which is why only those opt in.

Autoreset follows gymnasium's default (``AutoresetMode.NEXT_STEP``): the step after a copy's episode ends resets
that copy (reward 0) instead of stepping it.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium.vector.utils import batch_space, concatenate, create_empty_array
from mujoco import rollout

STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
CONTROL = mujoco.mjtState.mjSTATE_XFRC_APPLIED | mujoco.mjtState.mjSTATE_QFRC_APPLIED | mujoco.mjtState.mjSTATE_CTRL


class BatchedVectorEnv(gym.vector.VectorEnv):
    """N copies of one env class, physics batched through `mujoco.rollout`.

    Parameters
    ----------
    env_cls : type
        A `ScenarioEnv` subclass (the step split into `_before_physics` / `_after_physics`).
    num_envs : int
        Number of copies N (>= 1).
    nthread : int, optional
        Rollout threads (default: the CPU count, at most N).
    **kwargs :
        Constructor arguments of every copy.

    Raises
    ------
    ValueError
        If `num_envs` < 1, or the copies' models differ in size (rollout needs one size signature).
    """

    def __init__(self, env_cls: type, num_envs: int, *, nthread: int | None = None, **kwargs: Any) -> None:
        if int(num_envs) < 1:
            raise ValueError(f"num_envs = {num_envs!r} must be >= 1")
        self.num_envs = int(num_envs)
        self.envs = [env_cls(**kwargs) for _ in range(self.num_envs)]
        first = self.envs[0]
        self.metadata = {**first.metadata, "autoreset_mode": gym.vector.AutoresetMode.NEXT_STEP}
        self.render_mode = first.render_mode
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(first.observation_space, self.num_envs)
        self.action_space = batch_space(first.action_space, self.num_envs)
        self._nthread = max(1, min(nthread or os.cpu_count() or 1, self.num_envs))
        self._pool = rollout.Rollout(nthread=self._nthread)
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._observations = create_empty_array(self.single_observation_space, n=self.num_envs, fn=np.zeros)
        self._bind_models()

    def _bind_models(self) -> None:
        """Buffers sized for the copies' current models (a reset may compile a different model)."""
        models = [env.model for env in self.envs]
        sizes = {(mujoco.mj_stateSize(m, STATE), mujoco.mj_stateSize(m, CONTROL), m.nv) for m in models}
        if len(sizes) != 1:
            raise ValueError(f"the copies' models differ in size {sorted(sizes)}: rollout needs one size signature")
        (nstate, ncontrol, _nv) = sizes.pop()
        self._models = models
        self._datas = [mujoco.MjData(models[0]) for _ in range(self._nthread)]
        self._state = np.empty((self.num_envs, nstate))
        self._control = np.empty((self.num_envs, self.envs[0].frame_skip, ncontrol))  # held over the frame
        self._out = np.empty((self.num_envs, self.envs[0].frame_skip, nstate))

    def reset(self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None):
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} envs")
        infos: dict[str, Any] = {}
        observations = []
        for i, (env, s) in enumerate(zip(self.envs, seeds, strict=True)):
            obs, info = env.reset(seed=s, options=options)
            observations.append(obs)
            infos = self._add_info(infos, info, i)
        self._autoreset[:] = False
        self._rebind_if_needed()
        self._observations = concatenate(self.single_observation_space, observations, self._observations)
        return self._observations.copy(), infos

    def step(self, actions):
        actions = np.asarray(actions, dtype=np.float64)
        n = self.num_envs
        rewards = np.zeros(n)
        terminated = np.zeros(n, dtype=bool)
        truncated = np.zeros(n, dtype=bool)
        observations: list[Any] = [None] * n
        infos: dict[str, Any] = {}
        stepping = [i for i in range(n) if not self._autoreset[i]]
        for i in stepping:
            env = self.envs[i]
            env._before_physics(actions[i])
            mujoco.mj_getState(env.model, env.data, self._state[i], STATE)
            mujoco.mj_getState(env.model, env.data, self._control[i, 0], CONTROL)
        if stepping:
            self._rollout(stepping)
        for i in range(n):
            env = self.envs[i]
            if self._autoreset[i]:
                observations[i], info = env.reset()
            else:
                mujoco.mj_setState(env.model, env.data, self._out[i, -1], STATE)
                observations[i], rewards[i], terminated[i], truncated[i], info = env._after_physics()
            infos = self._add_info(infos, info, i)
        self._autoreset = terminated | truncated
        self._rebind_if_needed()
        self._observations = concatenate(self.single_observation_space, observations, self._observations)
        return self._observations.copy(), rewards, terminated, truncated, infos

    def _rollout(self, rows: list[int]) -> None:
        if len(rows) == self.num_envs:
            state, control, out = self._state, self._control, self._out
        else:
            state, control = self._state[rows], self._control[rows]
            out = np.empty((len(rows), *self._out.shape[1:]))
        control[:, 1:] = control[:, :1]
        models = [self._models[i] for i in rows]
        nstep = self._out.shape[1]
        self._pool.rollout(
            models, self._datas, state, control, control_spec=CONTROL, nstep=nstep, state=out, skip_checks=True
        )
        if out is not self._out:
            self._out[rows] = out

    def _rebind_if_needed(self) -> None:
        if any(env.model is not m for env, m in zip(self.envs, self._models, strict=True)):
            self._bind_models()

    def render(self):
        for env in self.envs:  # a written-back state has no derived quantities (body poses) yet
            mujoco.mj_forward(env.model, env.data)
        return tuple(env.render() for env in self.envs)

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """Call a method (or read an attribute) of every copy, e.g. ``call("theory_action")``."""
        out = []
        for env in self.envs:
            attr = getattr(env, name)
            out.append(attr(*args, **kwargs) if callable(attr) else attr)
        return tuple(out)

    def get_attr(self, name: str) -> tuple[Any, ...]:
        return tuple(getattr(env, name) for env in self.envs)

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()
        self._pool.close()
