"""Batched vector envs: N copies of a scenario env stepped as one engine batch (issue 15).

``gymnasium.make_vec("rigidbench/HeavyTop-v0", num_envs=N, vectorization_mode="vector_entry_point")`` builds a
`VectorScenarioEnv`: one template env resolves the case, builds the model, sets the initial state and tabulates the
theory (`ScenarioEnv.load`), and the N copies' physics run as one batch on an engine (`rigidbench.engines.worlds`:
C MuJoCo's `mujoco.batch`, MJX or MuJoCo Warp). Observations, measurements, deviations and rewards are computed
for the whole batch in arrays (the env's batched hooks, `batched_hooks`), not by N
Python calls.

On the C engine a batched env equals gymnasium's `SyncVectorEnv` of the same env bit for bit (observations,
rewards, terminations, truncations and the numbers in ``info``; `tests/test_vector.py`); on MJX and Warp it equals
it to within the engine's precision. One difference is deliberate: ``reset(options=...)`` sets the case and
parameters of the whole batch, and an autoreset restarts that configuration (a `SyncVectorEnv` sub-env's autoreset
returns to its constructor's arguments).
"""

from __future__ import annotations

import copy
import functools
import math
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from rigidbench.engines import registry as engine_registry
from rigidbench.engines.vector import Worlds, worlds
from rigidbench.envs.base import DEVIATION_CAP, ScenarioEnv, capped_reward


class VectorScenarioEnv(gym.vector.VectorEnv):
    """N copies of a validation env on one engine batch (autoreset: next step, as gymnasium's default).

    Parameters
    ----------
    env_cls : type of ScenarioEnv
        The single env (`rigidbench.registry.env_classes`).
    num_envs : int
        Number of copies (>= 1).
    engine : {"mujoco", "warp", "mjx"}
        What steps the batch (default C MuJoCo; `rigidbench.engines`).
    device : str, optional
        The engine's device (``"cpu"``, ``"cuda:0"``); C MuJoCo runs on the CPU.
    precision : {"float32", "float64"}, optional
        MJX's float precision (Warp: float32 only; C MuJoCo: float64 only).
    nthread : int, optional
        C MuJoCo's threads (default: every CPU).
    **env_kwargs :
        The single env's arguments (``case``, ``params``, ``profile``, ``integrator``, ``timestep``,
        ``frame_skip``); ``render_mode`` is not supported by the batch.

    Raises
    ------
    ValueError
        For ``num_envs < 1``, a render mode, an unknown or uninstalled engine, or a model the engine cannot simulate
        (`rigidbench.engines.EngineRefused`, naming the engine and the feature).
    """

    def __init__(
        self,
        env_cls: type[ScenarioEnv],
        num_envs: int,
        *,
        engine: str | None = None,
        device: str | None = None,
        precision: str | None = None,
        nthread: int | None = None,
        **env_kwargs: Any,
    ) -> None:
        if not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs = {num_envs!r} must be an integer >= 1")
        if env_kwargs.get("render_mode") is not None:
            raise ValueError("render_mode: a batched vector env does not render (render one copy with gymnasium.make)")
        env_kwargs.pop("render_mode", None)
        if env_cls.step is not ScenarioEnv.step:  # a control task (`TaskEnv`): its own step, reward and outcome
            raise TypeError(
                f"{env_cls.__name__} has its own step(): a batched vector env steps and scores a validation env's "
                "physics itself (`ScenarioEnv._physics_step`, `_score` and their batched hooks); run it under "
                'gymnasium\'s sync or async vector env (vectorization_mode="sync")'
            )
        self.num_envs = int(num_envs)
        self._engine = engine_registry.engine_for(engine, device=device, precision=precision)
        self._nthread = nthread
        self.env = env_cls(**env_kwargs)  # the template: resolves, builds, predicts and scores through its hooks
        self._hooks = batched_hooks(self.env)
        # Its model and state as the engine stores them (float32 on Warp and MJX float32), from the first reset on.
        self.env._precision = self._engine.precision if self._engine is not None else "float64"
        self.env._engine_name = self._engine.name if self._engine is not None else "mujoco"
        self.single_observation_space = self.env.observation_space
        self.single_action_space = self.env.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.metadata = {**self.env.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
        self.render_mode = None
        self.worlds: Worlds | None = None  # the batch of the template's current model
        self._options: dict[str, Any] = {}
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._k = np.zeros(self.num_envs, dtype=np.int64)
        self._every = np.ones(self.num_envs, dtype=bool)
        self._ready = False
        # One copy: the template env's own step (`_step_one`), its physics on the engine's one world (`_advance_one`;
        # on C MuJoCo the template's own `mj_step`, no batch built).
        self._single = self.num_envs == 1
        if self._single and self._engine is not None:
            self.env._advance = self._advance_one

    # ---- the episode's configuration, from the template --------------------------------------------------------

    def _start_episode(self, seed: int | None) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset the template for the batch's configuration; its state, theory table and reset info."""
        env = self.env
        obs, info = env.reset(seed=seed, options=self._options)
        if self._single and self._engine is None:
            return obs, info
        if self.worlds is None or self.worlds.model is not env.model:  # a new case or parameters: a new batch
            if self.worlds is not None:
                self.worlds.close()
            self.worlds = worlds(self._engine, env.model, self.num_envs, nthread=self._nthread)
        if self._single:
            self.worlds.load(_ONE, env.data)
            return obs, info
        self._table = np.array(env._rows, dtype=float)
        self._obs0, self._info0 = obs, info
        self._data0 = copy.copy(env.data)  # the episode's initial state, for every copy's (auto)reset
        self._frame_skip = env.frame_skip
        return obs, info

    def reset(self, *, seed: int | list[int] | None = None, options: Mapping[str, Any] | None = None):
        """Reset every copy to the configuration ``options`` names (``case``, ``params``; kept for autoresets).

        A list of seeds is accepted as gymnasium's vector envs take it; the validation envs draw nothing at random,
        so the copies start alike whatever their seeds.
        """
        if isinstance(seed, list | tuple):
            if len(seed) != self.num_envs:
                raise ValueError(f"{len(seed)} seeds for {self.num_envs} envs")
            seed = seed[0]
        self._options = dict(options or {})
        obs, info = self._start_episode(seed)
        ids = np.arange(self.num_envs)
        if not self._single:
            self.worlds.load(ids, self._data0)
        self._k[:] = 0
        self._autoreset[:] = False
        self._ready = True
        return np.tile(obs, (self.num_envs, 1)), _put({}, info, ids, self.num_envs)

    # ---- a step of every copy -------------------------------------------------------------------------------

    def step(self, actions):
        if not self._ready:
            raise RuntimeError("call reset() before step()")
        if self._single:
            return self._step_one(actions)
        env, worlds = self.env, self.worlds
        actions = self._checked(actions)
        restart = np.flatnonzero(self._autoreset)
        hooks = self._hooks
        hooks.apply_actions(actions, worlds)
        worlds.step(self._frame_skip)
        self._k += 1
        k = self._k
        obs = hooks.observe_batch(worlds)
        time = worlds.time.copy()
        table = self._table
        inside = k < len(table)
        if inside.all():
            predicted = table[k]
        else:
            predicted = np.array(
                [table[i] if inside[j] else env.theory(np.array([time[j]]))[0] for j, i in enumerate(k.tolist())]
            )
        measured = np.asarray(hooks.measured_batch(obs), dtype=float)
        deviation = np.asarray(hooks.deviation_batch(measured, predicted), dtype=float)
        reward = np.where(deviation <= DEVIATION_CAP, -deviation, -DEVIATION_CAP)
        # `ScenarioEnv.step`'s divergence test, for every copy: time fell behind (MuJoCo reset a blown-up state) or
        # the observation is not finite.
        diverged = (time < env._behind + k * env._env_dt) | ~np.isfinite(obs.sum(axis=1))
        terminated = diverged.copy()
        truncated = (time >= env._end) & ~diverged
        infos = self._step_infos(time, measured, predicted, deviation, reward, diverged)
        for j in np.flatnonzero(diverged):
            self._diverged(j, obs, reward, infos)
        if restart.size:
            self._restart(restart, obs, reward, terminated, truncated, infos)
        self._autoreset = terminated | truncated
        return obs, reward, terminated, truncated, infos

    def _step_one(self, actions):
        """One copy: the template env's step, in its two halves (`ScenarioEnv._physics_step` and `_score`: its
        physics, then the scalar hooks), its outputs as the batch's. A batch of one paid ~40-50 us of array work per
        step for what the scalar hooks do in a few (docs/engines.md); the numbers are the same (the batch path's equal
        the single env's bit for bit, `tests/test_vector.py`). The physics is one `mj_step` call for the frame skip on
        C MuJoCo, the engine's one world on MJX and Warp (`_advance_one`).

        The step's numbers go into one float64 array, and the reward and each number of ``info`` is a one-element
        view of it: 0.1 us a view against 0.4 us a new array, ~6 us a step of StruckStick's 14 us of Python
        (docs/engines.md). Each view is its own element: writing one changes no other output."""
        actions = np.asarray(actions)
        shape = (1, *self.single_action_space.shape)
        if actions.shape != shape:
            raise ValueError(f"actions shape {actions.shape} != {shape}")
        env = self.env
        if self._autoreset[0]:  # gymnasium's next-step autoreset: the step is not taken, the episode starts again
            obs, info = self._start_episode(None)
            self._autoreset[0] = False
            return obs[None], np.zeros(1), np.zeros(1, dtype=bool), np.zeros(1, dtype=bool), _put({}, info, _ONE, 1)
        obs, k, time, sound = env._physics_step(actions[0])
        if not sound:
            obs, reward, terminated, truncated, info = env._diverged_step(obs, k, time)
            self._autoreset[0] = True
            return obs[None], np.array([reward]), np.array([terminated]), np.array([truncated]), _one(info)
        measured, predicted, deviation = env._score(obs, k, time)
        reward = capped_reward(deviation)
        v = np.array((time, *measured, *predicted, deviation, reward, reward))
        truncated = time >= env._end
        self._autoreset[0] = truncated
        measured_info, predicted_info = {}, {}
        for name, mask, i in self._one_layout(env._observable_names):
            measured_info[name], measured_info[mask] = v[i : i + 1], _MASK
            predicted_info[name], predicted_info[mask] = v[i + len(measured) : i + len(measured) + 1], _MASK
        d = len(v) - 3
        info = {
            "time": v[0:1],
            "_time": _MASK,
            "measured": measured_info,
            "_measured": _MASK,
            "predicted": predicted_info,
            "_predicted": _MASK,
            "deviation": v[d : d + 1],
            "_deviation": _MASK,
            "reward_deviation": v[d + 1 : d + 2],
            "_reward_deviation": _MASK,
            "diverged": np.zeros(1, dtype=bool),
            "_diverged": _MASK,
        }
        return obs[None], v[d + 2 :], np.zeros(1, dtype=bool), np.array((truncated,)), info

    @staticmethod
    @functools.cache
    def _one_layout(names: tuple[str, ...]) -> tuple[tuple[str, str, int], ...]:
        """Each observable's info key, its mask's key, and its measured value's index in `_step_one`'s array."""
        return tuple((name, f"_{name}", 1 + i) for i, name in enumerate(names))

    def _advance_one(self, data) -> None:
        """The template's physics on the engine's one world (its `ScenarioEnv._advance`): the inputs its action
        wrote into `data` go to the world, the frame skip's steps run there, and the state comes back into `data`
        (qpos, qvel, and the step count as the clock, `rigidbench.engines.clock`)."""
        self.worlds.advance(data, self.env.frame_skip)

    def _checked(self, actions) -> np.ndarray:
        actions = np.asarray(actions, dtype=np.float64)
        shape = (self.num_envs, *self.single_action_space.shape)
        if actions.shape != shape:
            raise ValueError(f"actions shape {actions.shape} != {shape}")
        if not np.isfinite(actions).all():
            bad = int(np.flatnonzero(~np.isfinite(actions).reshape(self.num_envs, -1).all(axis=1))[0])
            raise ValueError(f"action of env {bad} {actions[bad]} is not finite")
        # As the single env's `_checked_action`: out-of-range actions clipped to [-1, 1], then the physical (SI)
        # action, the same product for each copy.
        actions = np.clip(actions, -1.0, 1.0)
        return actions if self.env._unit_scale else actions * self.env.action_scale

    def _step_infos(self, time, measured, predicted, deviation, reward, diverged) -> dict[str, Any]:
        """The infos of a step, as gymnasium's vector envs merge the single envs' (each key with its ``_key`` mask)."""
        names = self.env._observable_names
        every = self._every  # each key gets a mask of its own, as gymnasium's are: copies of one

        def columns(values: np.ndarray) -> dict[str, Any]:
            out: dict[str, Any] = {}
            for i, name in enumerate(names):
                out[name], out[f"_{name}"] = values[:, i].copy(), every.copy()
            return out

        infos: dict[str, Any] = {}
        for key, value in (
            ("time", time),
            ("measured", columns(measured)),
            ("predicted", columns(predicted)),
            ("deviation", deviation),
            ("reward_deviation", reward.copy()),
            ("diverged", diverged.copy()),
        ):
            infos[key], infos[f"_{key}"] = value, every.copy()
        return infos

    def _diverged(self, j: int, obs: np.ndarray, reward: np.ndarray, infos: dict[str, Any]) -> None:
        """Copy `j` diverged: `ScenarioEnv._diverged_step`'s observation, reward and info, in place."""
        obs[j], reward[j], _, _, info = self.env._diverged_step(obs[j], int(self._k[j]), float(infos["time"][j]))
        for key in ("deviation", "reward_deviation"):
            infos[key][j] = info[key]
        for name in self.env._observable_names:
            infos["measured"][name][j] = math.nan

    def _restart(self, ids, obs, reward, terminated, truncated, infos) -> None:
        """Copies whose episode ended on the last step start again (gymnasium's next-step autoreset): their step
        was not taken; they return the first observation, reward 0, and the reset's info."""
        self.worlds.load(ids, self._data0)
        self._k[ids] = 0
        obs[ids] = self._obs0
        reward[ids] = 0.0
        terminated[ids] = truncated[ids] = False
        _put(infos, self._info0, ids, self.num_envs)

    def close_extras(self, **kwargs) -> None:
        if self.worlds is not None:
            self.worlds.close()
            self.worlds = None
        self._ready = False  # a step after close asks for a reset, which builds the batch again
        self.env.close()


_ONE = np.zeros(1, dtype=np.int64)
_MASK = np.ones(1, dtype=bool)
_MASK.flags.writeable = False  # shared by every key of every step of a batch of one: read-only, so none can change it


def _one(info: Mapping[str, Any]) -> dict[str, Any]:
    """`_put` of a step's info (floats and bools, nested dicts of floats) into a batch of one: the same arrays, made
    directly, and one read-only mask for every key (a new mask per key cost a third of this function)."""
    out: dict[str, Any] = {}
    for key, value in info.items():
        out[key] = _one(value) if type(value) is dict else np.array((value,))
        out["_" + key] = _MASK
    return out


def _put(infos: dict[str, Any], info: Mapping[str, Any], ids: np.ndarray, n: int) -> dict[str, Any]:
    """`gymnasium.vector.VectorEnv._add_info` for the same `info` at several copies `ids` at once: each key an array
    over the copies (dtype as gymnasium chooses it) and a ``_key`` mask; nested dicts recursively."""
    for key, value in info.items():
        if isinstance(value, dict):
            array = _put(infos.get(key, {}), value, ids, n)
        else:
            array = infos.get(key)
            if array is None:
                if type(value) in (int, float, bool) or isinstance(value, np.number):
                    array = np.zeros(n, dtype=type(value))
                elif isinstance(value, np.ndarray):
                    array = np.zeros((n, *value.shape), dtype=value.dtype)
                else:
                    array = np.full(n, None, dtype=object)
            if array.dtype == object:
                for i in ids:
                    array[i] = value
            else:
                array[ids] = value
        mask = infos.get(f"_{key}")
        if mask is None:
            mask = np.zeros(n, dtype=bool)
        mask[ids] = True
        infos[key], infos[f"_{key}"] = array, mask
    return infos


def vector_entry_point(env_cls: type[ScenarioEnv]) -> functools.partial:
    """The callable gymnasium's ``vector_entry_point`` holds for `env_cls` (`rigidbench.registry.register_envs`): a
    partial of module-level names, so an env's spec (which holds it) can be pickled."""
    return functools.partial(VectorScenarioEnv, env_cls)


class PerCopyHooks:
    """The batched hooks of an env that defines none (`rigidbench.envs.base.ScenarioEnv`, "batched hooks"): its
    single-state hooks run once per copy, through a scratch MjData for the state and the inputs."""

    def __init__(self, env) -> None:
        self.env = env

    def observe_batch(self, worlds) -> np.ndarray:
        """Observations of every copy, shape (nworld, obs_dim), from ``worlds.qpos``, ``worlds.qvel``,
        ``worlds.time`` (`rigidbench.engines.Worlds`)."""
        out = np.empty((worlds.nworld, *self.env.observation_space.shape))
        with self.env._scratch() as data:
            for i in range(worlds.nworld):
                data.qpos[:], data.qvel[:], data.time = worlds.qpos[i], worlds.qvel[i], worlds.time[i]
                out[i] = self.env.observe()
        return out

    def apply_actions(self, actions: np.ndarray, worlds) -> None:
        """Write every copy's (clipped) action, shape (nworld, *action_shape), into ``worlds.ctrl``,
        ``worlds.qfrc_applied`` or ``worlds.xfrc_applied``."""
        with self.env._scratch() as data:
            for i in range(worlds.nworld):
                data.ctrl[:], data.qfrc_applied[:], data.xfrc_applied[:] = (
                    worlds.ctrl[i],
                    worlds.qfrc_applied[i],
                    worlds.xfrc_applied[i],
                )
                self.env.apply_action(actions[i])
                worlds.ctrl[i], worlds.qfrc_applied[i], worlds.xfrc_applied[i] = (
                    data.ctrl,
                    data.qfrc_applied,
                    data.xfrc_applied,
                )

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        """`measured` of every row of `obs`, shape (nworld, len(observables))."""
        return np.array([np.asarray(self.env.measured(row), dtype=float) for row in obs]).reshape(len(obs), -1)

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        """`deviation` of every copy, shape (nworld,), from (nworld, len(observables)) arrays."""
        return np.array([self.env.deviation(m, p) for m, p in zip(measured.tolist(), predicted.tolist(), strict=True)])


BATCHED_HOOKS = ("observe_batch", "apply_actions", "measured_batch", "deviation_batch")


def batched_hooks(env) -> PerCopyHooks:
    """An object with `env`'s four batched hooks: its own where its class defines them, else the per-copy ones."""
    hooks = PerCopyHooks(env)
    for name in BATCHED_HOOKS:
        if hasattr(type(env), name):
            setattr(hooks, name, getattr(env, name))
    return hooks
