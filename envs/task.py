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
    theory policy simulated from the same initial state on a copy of the MjData at reset, step by step, so
    ``sum(info["regret"])`` over an episode is the baseline's return minus the episode's.

A task env sets `env_id` (its own gymnasium id, `rigidbench.registry.env_classes`) and `scenario_cls`.
"""

from __future__ import annotations

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
        Compute ``info["regret"]`` (default). A closed-loop task simulates its theory policy at every reset for
        it; ``regret=False`` skips that (``info["regret"]`` is then NaN).
    **kwargs :
        ``profile``, ``integrator``, ``timestep``, ``frame_skip``, ``render_mode``, ``width``, ``height``
        (`ScenarioEnv`).

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

    def __init__(self, *, params: Mapping[str, Any] | None = None, regret: bool = True, **kwargs) -> None:
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
        self._reference = self._reference_rewards() if self._with_regret else None
        info = {"target": dict(self.target), "params": dict(self._actual), "settings": dict(self._settings_record)}
        return self.observe(), info

    def step(self, action):
        action = self._checked_action(action)
        reference = self._reference_reward() if self._with_regret else math.nan
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

    def _reference_rewards(self) -> np.ndarray | None:
        """Computed once per episode at reset (after `_start_episode`); None if `_reference_reward` needs none."""
        return None

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

    Regret: at reset the theory policy (`theory_action` every step) is simulated from the episode's initial
    state on a copy of the MjData, through the same `_advance` as the agent's steps; ``info["regret"]`` at step
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
        self._scratch = mujoco.MjData(self.model)

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

    def _reference_reward(self) -> float:
        return float(self._reference[self._k]) if self._k < len(self._reference) else 0.0

    def _reference_rewards(self) -> np.ndarray:
        own = self.data
        mujoco.mj_copyData(self._scratch, self.model, own)
        self.data = self._scratch
        rewards = np.zeros(self._nsteps)
        try:
            for k in range(self._nsteps):
                terms, outcome = self._advance(self._checked_action(self.theory_action()))  # as `step` applies it
                if outcome.get("diverged"):  # the episode would end here, scored as `step` scores it
                    rewards[k] = sum(self._diverged_terms()[name] for name in self.reward_terms)
                    break
                rewards[k] = sum(terms[name] for name in self.reward_terms)
        finally:
            self.data = own
            self._k = 0
        return rewards


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
