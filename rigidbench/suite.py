"""dm_control view: `rigidbench.suite.load(scenario, task)` mirrors `dm_control.suite.load(domain, task)`.

Returns a `dm_control.rl.control.Environment` whose `Physics` is built from the scenario's compiled model (the
same MjSpec path as every other view) and whose `base.Task` delegates initial state, observation, action and
reward to the scenario and its gymnasium env's hooks: nothing is re-implemented here.

Needs the ``dm`` extra (``pip install -e ".[dm]"``). dm-control 1.0.50 was generated against MuJoCo 3.17: its table
of array sizes (``dm_control/mujoco/wrapper/mjbindings/sizes.py``) lists nine flexvert fields MuJoCo 4.0 removed
(``flex_vertedge``, ``flex_vertedgeadr``, ``flex_vertedgenum``, ``flex_vertmetric``, ``flexvert_J_rownnz``,
``flexvert_J_rowadr``, ``flexvert_J_colind`` on the model; ``flexvert_length``, ``flexvert_J`` on the data), and
building a `Physics` calls ``getattr`` on every entry. `fit_dm_control_to_mujoco` drops exactly the entries the
installed MuJoCo lacks, before any dm_control Physics is built or `dm_control.mjcf` is imported (importing this
module does it): with MuJoCo 3.17, or once dm_control catches up, it drops nothing.
"""

from __future__ import annotations

import collections
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import registry
from rigidbench.settings import profile as _profile


def fit_dm_control_to_mujoco() -> dict[str, list[str]]:
    """Drop from dm_control's generated table of array sizes the fields the installed MuJoCo does not have.

    Returns
    -------
    dict of str to list of str
        The dropped fields, by struct (``mjmodel``, ``mjdata``); empty lists when dm_control matches MuJoCo.
    """
    from dm_control.mujoco.wrapper.mjbindings import sizes

    model = mujoco.MjModel.from_xml_string("<mujoco/>")
    structs = {"mjmodel": model, "mjdata": mujoco.MjData(model)}
    dropped: dict[str, list[str]] = {}
    for struct, instance in structs.items():
        fields = sizes.array_sizes.get(struct, {})
        dropped[struct] = [name for name in fields if not hasattr(instance, name)]
        for name in dropped[struct]:
            del fields[name]
    return dropped


try:
    DROPPED = fit_dm_control_to_mujoco()
    from dm_control import mujoco as dm_mujoco  # noqa: E402 - after the size table is fitted
    from dm_control.rl import control
    from dm_control.suite import base
    from dm_env import specs
except ImportError as exc:  # pragma: no cover - exercised without the extra
    raise ImportError("rigidbench.suite needs dm-control: pip install -e '.[dm]'") from exc


class Physics(dm_mujoco.Physics):
    """A scenario's physics: the compiled model plus named quantities from the scenario's own hooks."""


class ScenarioTask(base.Task):
    """A dm_control task for one case of a scenario: the validation problem (zero action = textbook)."""

    def __init__(self, scenario: str, case: str | None, params: Mapping[str, Any] | None, env, random=None):
        super().__init__(random=random)
        self.scenario = registry.get(scenario)
        self.case = self.scenario.case(case).name
        self.params = self.scenario.resolve(self.scenario.case(case), params)
        self._env = env  # the gymnasium env whose hooks define observation, action and reward

    def initialize_episode(self, physics: Physics) -> None:
        model, data = physics.model.ptr, physics.data.ptr
        with physics.reset_context():
            self.scenario.initial_state(model, data, self.scenario.read_params(model))
        self._bind(physics)
        self._env._prediction = self.scenario.predict(model, data)

    def _bind(self, physics: Physics) -> None:
        self._env.model, self._env.data = physics.model.ptr, physics.data.ptr

    def action_spec(self, physics: Physics) -> specs.BoundedArray:
        space = self._env.action_space
        return specs.BoundedArray(space.shape, np.float64, space.low, space.high, name="action")

    def before_step(self, action, physics: Physics) -> None:
        self._bind(physics)
        self._env.apply_action(self._env._checked_action(np.asarray(action, dtype=float)))

    def get_observation(self, physics: Physics) -> collections.OrderedDict:
        self._bind(physics)
        return collections.OrderedDict(observation=self._env.observe())

    def get_reward(self, physics: Physics) -> float:
        self._bind(physics)
        deviation, _measured, _predicted = self._env._compare()
        return -float(deviation)

    def get_termination(self, physics: Physics) -> float | None:
        data = physics.data.ptr
        if not (np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()):
            return 0.0
        if data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0:
            return 0.0
        return None


class ControlTask(base.Task):
    """A dm_control task for a closed-loop control task env (`rigidbench.envs.task.ClosedLoopTask`): the target
    is sampled from the task's own random state at each episode, and the env's hooks give the initial state,
    observation, action and reward terms. ``theory_action(physics)`` is the env's theory policy."""

    def __init__(self, env, random=None):
        super().__init__(random=random)
        self._env = env  # the gymnasium task env; its model is the physics' model
        self._action = np.zeros(env.action_space.shape)

    def _bind(self, physics: Physics) -> None:
        self._env.data = physics.data.ptr

    def initialize_episode(self, physics: Physics) -> None:
        self._env.reset(seed=int(self.random.randint(2**31)))  # samples the target, sets the initial state
        with physics.reset_context():
            mujoco.mj_copyData(physics.data.ptr, physics.model.ptr, self._env.data)
        self._bind(physics)

    def action_spec(self, physics: Physics) -> specs.BoundedArray:
        space = self._env.action_space
        return specs.BoundedArray(space.shape, np.float64, space.low, space.high, name="action")

    def before_step(self, action, physics: Physics) -> None:
        self._bind(physics)
        self._action = self._env._checked_action(np.asarray(action, dtype=float))
        self._env.apply_action(self._action)

    def after_step(self, physics: Physics) -> None:
        self._env._k += 1  # the env's step counter: its reward terms and theory policy may depend on it

    def get_observation(self, physics: Physics) -> collections.OrderedDict:
        self._bind(physics)
        return collections.OrderedDict(observation=self._env.observe())

    def get_reward(self, physics: Physics) -> float:
        self._bind(physics)
        terms = self._env._terms(self._action)
        return float(sum(terms[name] for name in self._env.reward_terms))

    def get_termination(self, physics: Physics) -> float | None:
        """0 (terminal) on divergence; 1 (a truncation) at the episode's end, which a task may sample per episode."""
        diverged = ScenarioTask.get_termination(self, physics)
        if diverged is not None:
            return diverged
        return 1.0 if self._env._k >= self._env._nsteps else None

    def theory_action(self, physics: Physics) -> np.ndarray:
        """The task's theory action (baseline) at the physics' current state."""
        self._bind(physics)
        return self._env.theory_action()


def load(
    scenario: str,
    task: str | None = None,
    *,
    task_kwargs: Mapping[str, Any] | None = None,
    environment_kwargs: Mapping[str, Any] | None = None,
) -> control.Environment:
    """Load a scenario as a dm_control environment, like ``dm_control.suite.load(domain_name, task_name)``.

    Parameters
    ----------
    scenario : str
        Scenario slug (the "domain"), e.g. ``"heavy-top"``; or the gymnasium id of a closed-loop control task,
        e.g. ``"rigidbench/TopPrecession-v0"`` (`ControlTask`; its target is sampled per episode from
        ``task_kwargs["random"]``). One-shot tasks (one action per episode) have the dm_env view only
        (`rigidbench.dm.load`): a dm_control task steps the physics itself, a fixed number of sub-steps.
    task : str, optional
        Case name (the "task"), e.g. ``"nutation"``; default: the scenario's first case. None for a task id.
    task_kwargs : mapping, optional
        ``params`` (parameter overrides, SI), ``profile`` (settings profile), ``random`` (seed).
    environment_kwargs : mapping, optional
        Passed to `control.Environment` (e.g. ``time_limit``, ``n_sub_steps``); the default time limit is the
        case's validation duration and ``n_sub_steps`` the gymnasium env's frame skip.

    Raises
    ------
    ValueError
        For an unknown scenario, case or parameter.
    """
    import gymnasium as gym

    task_kwargs = dict(task_kwargs or {})
    params = task_kwargs.pop("params", None)
    profile_name = task_kwargs.pop("profile", "reference")
    if "/" in scenario:
        return _load_task(scenario, task, params, profile_name, task_kwargs, environment_kwargs)
    sc = registry.get(scenario)
    if sc.env_id is None:
        raise ValueError(f"scenario '{scenario}' has no stepping environment (a batch scenario): no dm_control view")
    env = gym.make(sc.env_id, case=task, params=params, profile=profile_name).unwrapped
    model = sc.build(sc.resolve(sc.case(task), params), _profile(profile_name))
    physics = Physics.from_model(dm_mujoco.wrapper.MjModel(model))
    dm_task = ScenarioTask(scenario, task, params, env, random=task_kwargs.pop("random", None))
    if task_kwargs:
        raise ValueError(f"unknown task_kwargs {sorted(task_kwargs)}; valid: params, profile, random")
    kwargs = {"time_limit": env.episode_duration, "n_sub_steps": env.frame_skip, **dict(environment_kwargs or {})}
    return control.Environment(physics, dm_task, **kwargs)


def _load_task(env_id, task, params, profile_name, task_kwargs, environment_kwargs) -> control.Environment:
    import gymnasium as gym

    from rigidbench.envs.task import ClosedLoopTask

    cls = registry.env_classes().get(env_id)
    if cls is None or not issubclass(cls, ClosedLoopTask):
        tasks = sorted(i for i, c in registry.env_classes().items() if issubclass(c, ClosedLoopTask))
        raise ValueError(f"{env_id!r} is not a closed-loop control task; valid: {', '.join(tasks)}")
    if task is not None:
        raise ValueError(f"a control task takes no case (task = {task!r}): its target is sampled per episode")
    env = gym.make(env_id, params=params, profile=profile_name, regret=False).unwrapped
    physics = Physics.from_model(dm_mujoco.wrapper.MjModel(env.model))
    dm_task = ControlTask(env, random=task_kwargs.pop("random", None))
    if task_kwargs:
        raise ValueError(f"unknown task_kwargs {sorted(task_kwargs)}; valid: params, profile, random")
    # The task ends its own episodes (get_termination): their length may be sampled per episode.
    kwargs = {"time_limit": float("inf"), "n_sub_steps": env.frame_skip, **dict(environment_kwargs or {})}
    return control.Environment(physics, dm_task, **kwargs)
