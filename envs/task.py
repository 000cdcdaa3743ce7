"""Control tasks on the scenarios: a target per episode, the theory's action, and the regret against it.

A validation env (`ScenarioEnv`) scores the state against theory at zero action. A task env is the same
scenario (model, parameters, initial state, predictions) with a job to do: reach a target sampled per episode
from ``self.np_random``. What makes these tasks special is that theory knows a good answer:
``env.unwrapped.theory_action()`` returns it for the current state, and every step reports in ``info``

* ``reward_<term>``: each reward term (they add up to the reward);
* ``regret``: the reward of the theory action minus the reward of the action taken. How the theory action's
  reward is obtained is the task family's business, and each family says which:

  - `ShotTask` (one action per episode: where and how hard to strike): the reward the closed form predicts
    for the theory action, so a policy's regret measures it against the textbook, and the theory action's own
    regret measures how far MuJoCo's physics (soft contact, finite pulse) is from the textbook's;
  - `ClosedLoopTask` (a torque every step, a baseline controller as the theory policy): the rewards of the
    theory policy simulated from the same initial state on a copy of the MjData taken at reset, step by step
    alongside the episode, so
    ``sum(info["regret"])`` over an episode is the baseline's return minus the episode's.

A task env sets `env_id` (its own gymnasium id, `rigidbench.registry.env_classes`) and `scenario_cls`.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench.envs.base import ScenarioEnv
from rigidbench.simulate import simulate, steps_for


class TaskEnv(ScenarioEnv):
    """Base of the control tasks. Subclasses set the class attributes and implement the hooks.

    Parameters
    ----------
    params : mapping, optional
        Scenario parameter overrides (SI); ``reset(options={"params": ...})`` overrides them for an episode.
    regret : bool
        Compute ``info["regret"]`` (default). A closed-loop task simulates its theory policy alongside the
        episode for it (one baseline step per step, none at reset); ``regret=False`` skips that (``info["regret"]``
        is then NaN).
    profile : str
        ``"task"`` (default): the task's own settings (`task_settings`, on the reference profile), chosen for the
        reward's resolution (issue 36); ``"reference"``: the validation reference, the task as it was before; or
        any settings profile of `ScenarioEnv`.
    integrator, timestep :
        Override the profile's.
    **kwargs :
        ``frame_skip``, ``render_mode``, ``width``, ``height`` (`ScenarioEnv`).

    Class attributes
    ----------------
    env_id : str
        Gymnasium id, e.g. ``"rigidbench/TopPrecession-v0"``.
    task_case : str or None
        The scenario case the task starts from (its initial conditions); None: the first case.
    target_names : tuple of str
        Keys of ``info["target"]``; ``reset(options={"target": {...}})`` fixes them instead of sampling.
    reward_terms : tuple of str
        Names of the reward terms, reported as ``info["reward_<name>"]``.
    """

    env_id: ClassVar[str]
    task_case: ClassVar[str | None] = None
    target_names: ClassVar[tuple[str, ...]]
    reward_terms: ClassVar[tuple[str, ...]]
    observables: ClassVar[tuple[str, ...]] = ()

    # Issue 36: the physics a task's reward needs, not the validation reference's. ``profile="task"`` (the default)
    # runs the task at these settings (``integrator``, ``timestep`` in s; a key left out keeps the reference's), chosen
    # from a sweep of integrators and steps (benchmarks/task_speed.py ``--sweep``) as the cheapest whose largest error
    # on the reward terms, against the reference settings over sampled targets and actions, stays below
    # `TASK_ERROR_BOUND`; `task_record` states the measured error and the theory action's regret there.
    # ``profile="reference"`` is the task as it was before (the model's own settings, `reference_timestep`).
    task_settings: ClassVar[dict[str, Any]] = {}
    task_record: ClassVar[dict[str, Any]] = {}
    reference_timestep: ClassVar[float | None] = None  # the reference profile's timestep where the task set one

    def __init__(
        self,
        *,
        params: Mapping[str, Any] | None = None,
        regret: bool = True,
        profile: str = "task",
        integrator: str | None = None,
        timestep: float | None = None,
        **kwargs,
    ) -> None:
        self.profile = profile
        if profile == "task":
            integrator = self.task_settings.get("integrator") if integrator is None else integrator
            timestep = self.task_settings.get("timestep", self.reference_timestep) if timestep is None else timestep
            profile = "reference"
        elif profile == "reference" and timestep is None:
            timestep = self.reference_timestep
        kwargs.update(profile=profile, integrator=integrator, timestep=timestep)
        self._with_regret = bool(regret)
        self._reward_keys = tuple(f"reward_{name}" for name in self.reward_terms)  # info's keys, built once
        self.target: dict[str, float] = {}
        super().__init__(case=self.task_case, params=params, **kwargs)

    # ---- hooks -------------------------------------------------------------------------------------------

    def _target_ranges(self) -> dict[str, tuple[float, float]]:
        """Valid interval of each target (SI), for the current parameters; targets are sampled uniformly in it."""
        raise NotImplementedError

    def _complete_target(self, target: dict[str, float]) -> dict[str, float]:
        """Derived targets (e.g. a precession rate from a tilt); by default the target as given."""
        return target

    def _start_episode(self) -> None:
        """Put `self.data` at the episode's initial state for `self.target` (the model is loaded)."""

    def theory_action(self) -> np.ndarray:
        """The theory's action for the current state and target: normalised, in the action space's bounds [-1, 1]
        (float64, as precise as the theory; a float32 copy moves it by up to 6e-8)."""
        raise NotImplementedError

    def theory_actions(self) -> list[np.ndarray]:
        """Every action the theory finds optimal (where the optimum is not unique); `theory_action` is one."""
        return [self.theory_action()]

    def _advance(self, action: np.ndarray) -> tuple[dict[str, float], dict[str, Any]]:
        """Apply `action` and simulate; return the reward terms and the outcome for ``info``.

        An outcome with ``"diverged": True`` ends the episode (the terms are then `_diverged_terms`).
        """
        raise NotImplementedError

    def _reference_reward(self) -> float:
        """Reward of the theory action at the current step (the regret's reference), before advancing."""
        raise NotImplementedError

    def _diverged_terms(self) -> dict[str, float]:
        """Reward terms of a step on which the simulation diverged: the worst the episode could still score,
        so that blowing up the simulation never pays."""
        raise NotImplementedError

    def _episode_end(self) -> tuple[bool, bool]:
        """(terminated, truncated) after a step."""
        raise NotImplementedError

    # ---- gymnasium API ----------------------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        gym.Env.reset(self, seed=seed)
        options = dict(options or {})
        unknown = set(options) - {"params", "target"}
        if unknown:
            raise ValueError(f"unknown reset option(s) {sorted(unknown)}; valid: 'params', 'target'")
        self._episode_params = {**self._params, **dict(options.get("params") or {})}
        self.load(self._case_name, self._episode_params)
        ranges = self._target_ranges()
        if "target" in options:
            self.target = self._complete_target(self._checked_target(options["target"], ranges))
        else:
            self.target = self._complete_target({n: float(self.np_random.uniform(*ranges[n])) for n in ranges})
        self._start_episode()
        if self._with_regret:
            self._begin_reference()
        info = {"target": dict(self.target), "params": dict(self._actual), "settings": dict(self._settings_record)}
        info["task_settings"] = self._task_info()
        return self.observe(), info

    def _task_info(self) -> dict[str, Any]:
        """The profile the task runs at and, at the task settings, what they were chosen for (`task_record`)."""
        out: dict[str, Any] = {"profile": self.profile}
        if self.profile == "task":
            out.update(copy.deepcopy(self.task_settings), **copy.deepcopy(self.task_record))
        return out

    def step(self, action):
        # The reference first: a closed-loop task's lazy baseline checks its own actions through the same buffer.
        reference = self._reference_reward() if self._with_regret else math.nan
        action = self._checked_action(action)
        return self._finish(reference, *self._advance(action))

    def _finish(self, reference: float, terms: dict[str, float], outcome: dict[str, Any]):
        """The step's (obs, reward, terminated, truncated, info) from its reward terms and outcome."""
        diverged = bool(outcome.get("diverged", False))
        if diverged:
            terms = self._diverged_terms()
        names = self.reward_terms
        reward = float(sum(terms[name] for name in names))
        info = {key: float(terms[name]) for key, name in zip(self._reward_keys, names)}  # noqa: B905 (same tuple)
        info.update(regret=reference - reward, target=dict(self.target), time=float(self.data.time), diverged=diverged)
        if outcome:
            info.update(outcome)
        terminated, truncated = (True, False) if diverged else self._episode_end()
        obs = self._observed()
        if diverged:
            obs = np.clip(
                np.nan_to_num(obs, nan=0.0, posinf=0.0, neginf=0.0),
                self.observation_space.low,
                self.observation_space.high,
            )
        return obs, reward, terminated, truncated, info

    # ---- internals --------------------------------------------------------------------------------------

    def _observed(self) -> np.ndarray:
        """The observation after `_advance` (the state it left); read afresh unless the task kept it."""
        return self.observe()

    def theory(self, t: np.ndarray) -> np.ndarray:
        return np.empty((len(t), 0))  # a task compares outcomes with its target, not a trajectory with theory

    def _begin_reference(self) -> None:
        """Prepare the episode's regret reference at reset (after `_start_episode`); nothing by default."""

    def _checked_target(self, target: Mapping[str, Any], ranges: Mapping[str, tuple[float, float]]) -> dict:
        unknown = set(target) - set(ranges)
        missing = set(ranges) - set(target)
        if unknown or missing:
            raise ValueError(f"target must give exactly {sorted(ranges)}; got {sorted(target)}")
        out = {}
        for name, (low, high) in ranges.items():
            value = float(target[name])
            if not (math.isfinite(value) and low <= value <= high):
                raise ValueError(f"target {name} = {target[name]!r} is outside the valid range [{low:g}, {high:g}]")
            out[name] = value
        return out


class ClosedLoopTask(TaskEnv):
    """A task driven every step (a bounded torque) for a fixed time, with a baseline controller as the theory.

    Regret: the theory policy (`theory_action` every step) is simulated from the episode's initial
    state on a copy of the MjData taken at reset, through the same `_advance` as the agent's steps, one baseline
    step ahead of each agent step (lazily: a reset costs a state copy, issue 36); ``info["regret"]`` at step
    k is that rollout's reward at step k minus the agent's. The theory policy therefore has regret 0 exactly
    (same code path, deterministic), which says nothing about its quality: each task's tests check what the
    baseline achieves against the theory's target state instead.

    Subclasses implement `_terms` (reward terms at the current state after a step, and the action).
    """

    # Simulated time of an episode (s); a constructor argument of the concrete tasks.
    episode_duration: float
    # Whether the horizon is the task's own end (gymnasium's `terminated`): its reward is paid there and the
    # observation shows the time left, so nothing follows it to bootstrap from. Otherwise the horizon is a time
    # limit on a task that goes on (`truncated`), and a learner rightly bootstraps past it.
    horizon_ends_task: ClassVar[bool] = False

    def _terms(self, action: np.ndarray) -> dict[str, float]:
        raise NotImplementedError

    def load(self, case: str, params: Mapping[str, Any]) -> None:
        super().load(case, params)
        self.episode_duration = self._task_duration
        self._nsteps = max(1, round(self._task_duration / self._env_dt))

    def _advance(self, action: np.ndarray) -> tuple[dict[str, float], dict[str, Any]]:
        self.apply_action(action)
        mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)
        return self._outcome(action)

    def _outcome(self, action: np.ndarray) -> tuple[dict[str, float], dict[str, Any]]:
        self._k += 1
        # Kept for `_finish` (issue 8): the step's observation is this one, not a second read of the same state.
        obs = self._last_observation = self.observe()
        if self._diverged(obs):
            return {}, {"diverged": True}
        return self._terms(action), {}

    def _observed(self) -> np.ndarray:
        return self._last_observation

    def _episode_end(self) -> tuple[bool, bool]:
        end = self._k >= self._nsteps
        return (end, False) if self.horizon_ends_task else (False, end)

    # Completed baseline rollouts kept per episode configuration (target and parameters), at most this many.
    REFERENCE_CACHE: ClassVar[int] = 64

    def _begin_reference(self) -> None:
        """Issue 36: a reset no longer simulates the baseline. It copies the episode's initial state into a scratch
        MjData and the baseline is stepped from there only as far as a step's regret needs it (`_reference_reward`,
        one baseline step per agent step), or all at once when `_reference` is read. The baseline runs the same
        calls on the same state in the same order as the whole rollout at reset did, so its rewards are the same
        bits. A completed rollout is kept per (target, parameters): a reset to a configuration seen before (a fixed
        evaluation target) reuses it."""
        self._ref_key = self._reference_key()
        cached = self._reference_cache.get(self._ref_key) if self._ref_key is not None else None
        if cached is not None:
            self._ref_rewards, self._ref_k, self._ref_done = cached, self._nsteps, True
            return
        if getattr(self, "_ref_model", None) is not self.model:
            self._ref_data = mujoco.MjData(self.model)  # one scratch MjData per model, not one per reset
            self._ref_model = self.model
        mujoco.mj_copyData(self._ref_data, self.model, self.data)
        self._ref_rewards = np.zeros(self._nsteps)
        self._ref_k = 0  # baseline steps simulated so far
        self._ref_done = False

    @property
    def _reference_cache(self) -> dict:
        cache = self.__dict__.get("_ref_cache")
        if cache is None:
            cache = self.__dict__["_ref_cache"] = {}
        return cache

    def _reference_key(self) -> tuple | None:
        """The episode's configuration as a key (None if a parameter cannot be hashed: no caching then)."""
        try:
            key = (
                tuple(sorted(self.target.items())),
                tuple(sorted((k, type(v), v) for k, v in self._episode_params.items())),
                self._nsteps,
            )
            hash(key)
        except TypeError:
            return None
        return key

    def _reference_upto(self, k: int) -> None:
        """Simulate the baseline until its reward at step k is known (or it has ended), on the scratch MjData."""
        if self._ref_done or self._ref_k > k:
            return
        own, own_k, own_obs = self._data, self._k, getattr(self, "_last_observation", None)
        self.data = self._ref_data
        self._k = self._ref_k
        rewards, names = self._ref_rewards, self.reward_terms
        try:
            while self._k <= k and self._k < self._nsteps:
                i = self._k
                terms, outcome = self._advance(self._checked_action(self.theory_action()))  # as `step` applies it
                if outcome.get("diverged"):  # the episode would end here, scored as `step` scores it
                    rewards[i] = sum(self._diverged_terms()[name] for name in names)
                    self._ref_done = True
                    break
                rewards[i] = sum(terms[name] for name in names)
            self._ref_k = self._k
            if self._ref_k >= self._nsteps:
                self._ref_done = True
        finally:
            self.data = own
            self._k = own_k
            self._last_observation = own_obs
        if self._ref_done and self._ref_key is not None:
            cache = self._reference_cache
            if len(cache) >= self.REFERENCE_CACHE:
                cache.pop(next(iter(cache)))
            cache[self._ref_key] = rewards

    @property
    def _reference(self) -> np.ndarray:
        """The baseline's reward at every step of the episode (completes the rollout if it is not yet)."""
        self._reference_upto(self._nsteps)
        return self._ref_rewards

    def _reference_reward(self) -> float:
        k = self._k
        if k >= len(self._ref_rewards):
            return 0.0
        self._reference_upto(k)
        return float(self._ref_rewards[k])


class ShotTask(TaskEnv):
    """A task of one action per episode (where and how hard to strike): the step simulates the whole event.

    Regret: the reward the closed form predicts for the theory action (`_theory_reward`, computed from the
    scenario's predictions, no simulation) minus the simulated reward of the action taken. A policy's regret
    therefore measures it against the textbook; the theory action's own regret is how far MuJoCo's physics
    (soft contact, finite pulse, integration) is from the textbook's, and each task's test bounds it with the
    scenario's tolerances.

    Subclasses implement `_shot` (simulate the action from the episode's initial state; return the reward
    terms and the outcome) and `_theory_reward`; the observation is the target (`target_names`, in order).

    Recording a shot: one step is the whole shot, so a per-step video has two frames. With
    ``render_mode="rgb_array_list"``, ``render()`` after a step returns `SHOT_FRAMES` frames spread over the shot's
    simulated time (after a reset: the one frame of the start), to be played at ``metadata["render_fps"]`` (30: a
    3 s slow-motion clip), e.g. ``gymnasium.utils.save_video.save_video(env.render(), "videos",
    fps=env.metadata["render_fps"])``.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array", "rgb_array_list"], "render_fps": 30}
    SHOT_FRAMES: ClassVar[int] = 90

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(len(self.target_names),), dtype=np.float64)

    def observe(self) -> np.ndarray:
        return np.array([self.target.get(name, 0.0) for name in self.target_names])

    def _shot(self, action: np.ndarray) -> tuple[dict[str, float], dict[str, Any]]:
        raise NotImplementedError

    def _theory_reward(self) -> float:
        raise NotImplementedError

    def _advance(self, action: np.ndarray) -> tuple[dict[str, float], dict[str, Any]]:
        return self._shot(action)

    def load(self, case: str, params: Mapping[str, Any]) -> None:
        super().load(case, params)
        self.metadata = {**type(self).metadata}  # a shot is replayed in slow motion, not in real time
        self._shot_states: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def render(self):
        if self.render_mode != "rgb_array_list":
            return super().render()
        shot, self._shot_states = self._shot_states, None
        if shot is None:
            return [self._frame()]
        time, qpos, qvel = shot
        final = (self.data.qpos.copy(), self.data.qvel.copy(), float(self.data.time))
        frames = []
        try:
            for i in np.unique(np.linspace(0, len(time) - 1, self.SHOT_FRAMES).round().astype(int)):
                self._show(qpos[i], qvel[i], float(time[i]))
                frames.append(self._frame())
        finally:
            self._show(*final)
        return frames

    def _reference_reward(self) -> float:
        return self._theory_reward()

    def _episode_end(self) -> tuple[bool, bool]:
        return True, False

    def _run_scenario(
        self, overrides: Mapping[str, Any], measure=None, max_duration: float = math.inf
    ) -> dict[str, float] | None:
        """Simulate the scenario with `overrides` on the episode's parameters, exactly as its validation run does
        (`Scenario.run`: compile, initial state, predict, duration, open-loop control, `measure`), leave
        `self.data` at the final state and `self.prediction` at the action's closed-form prediction.

        `measure` (model, trajectory, prediction) -> dict replaces the scenario's `measure` where a task needs
        only part of it; `max_duration` (s) caps the scenario's run. Returns the measured observables, or None if
        the simulation diverged.
        """
        self.load(self._case_name, {**self._episode_params, **overrides})
        scenario, model = self.scenario, self.model
        duration = min(float(scenario.duration(self.prediction)), max_duration)
        nstep = steps_for(duration, model.opt.timestep)
        traj = simulate(model, self.data, duration, control=scenario.control(model, model.opt.timestep, nstep))
        self._shot_states = (traj.time, traj.qpos, traj.qvel)
        self._show(traj.qpos[-1], traj.qvel[-1], float(traj.time[-1]))
        if traj.diverged_at is not None:
            return None
        return (measure or scenario.measure)(model, traj, self.prediction)

    def _show(self, qpos: np.ndarray, qvel: np.ndarray, time: float) -> None:
        """Leave `self.data` at a simulated state (the end of the shot), for rendering."""
        self.data.qpos[:] = qpos
        self.data.qvel[:] = qvel
        self.data.time = time
        mujoco.mj_forward(self.model, self.data)
