"""Gymnasium plumbing shared by every scenario env: loading, settings, frame skip, seeding, rendering.

A scenario env is a thin view of its `Scenario` (house rule 11): the scenario resolves parameters, builds the
model, sets the initial state and predicts; the env steps MuJoCo, applies the action, and scores the state
against the theory at every step. A subclass sets `scenario_cls` and `observables` and implements the hooks
under "hooks" below, each public and documented: `define_observation_space`, `define_action_space`, `observe`,
`apply_action`, `theory`, `measured`, `deviation` (and, where it needs them, `begin_episode`, `load` and
`bind_views`). Everything else here is plumbing a subclass does not touch. Model building, starting and
predicting are the harness's (`rigidbench.harness`, reached through `rigidbench.contract.harness`).
"""

from __future__ import annotations

import contextlib
import copy
import math
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench.contract import Scenario, harness

_FLOAT64 = np.dtype(np.float64)
# Smallest shadow map (pixels per side) the envs render with; see `ScenarioEnv.render`.
SHADOW_MAP_MIN = 1024
# Largest deviation a step's reward counts (rewards are >= -DEVIATION_CAP), as the control tasks cap their terms.
# A step on which the simulation diverges scores -DEVIATION_CAP for itself and for every step the episode had
# left: the worst the rest of the episode could have scored, so that blowing up the simulation never pays.
DEVIATION_CAP = 10.0


def capped_reward(deviation: float) -> float:
    """A step's reward for its `deviation`: ``-min(deviation, DEVIATION_CAP)`` (NaN counts as the cap)."""
    return -deviation if deviation <= DEVIATION_CAP else -DEVIATION_CAP


class ScenarioEnv(gym.Env):
    """Base class of the validation environments (zero action = the textbook problem).

    Reward: ``-min(deviation, DEVIATION_CAP)`` per step, the deviation of the state from the closed form (each env
    says how it is normalised). A step on which the simulation diverges ends the episode (``terminated``) and
    pays ``-DEVIATION_CAP`` for itself and each step left: the worst the rest of the episode could have scored.
    Reaching the scenario's duration ends it with ``truncated`` (a time limit: the system goes on).

    ``metadata["render_fps"]`` is ``1 / (timestep * frame_skip)``: a recorded video plays in real time. Copies
    (`copy.deepcopy`, `pickle`) of an env mid-episode continue exactly as the original would.

    Parameters
    ----------
    case : str, optional
        Named case of the scenario (default: its first case). ``reset(options={"case": ...})`` overrides it.
    params : mapping, optional
        Parameter overrides (SI units) applied on top of the case; ``reset(options={"params": ...})``
        overrides them for that episode.
    profile : str
        Settings profile, ``"reference"`` (the model file's own settings) or ``"mujoco-default"``.
    integrator : {"Euler", "RK4", "implicit", "implicitfast"}, optional
        Overrides the profile's integrator.
    timestep : float, optional
        Overrides the profile's physics timestep (s).
    frame_skip : int
        Physics steps per ``env.step`` (>= 1).
    render_mode : {"rgb_array"}, optional
    width, height : int
        Render size in pixels.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 30}
    scenario_cls: ClassVar[type[Scenario]]
    default_frame_skip: ClassVar[int] = 10
    # Whether the case's regime (`Case.ranges`, where its checks' closed forms hold) binds the env's parameters. A
    # control task whose action moves a parameter over its whole range, and whose reward reads its own measurement
    # rather than the case's checks, sets False; parameter ranges and the theory's domains still apply.
    case_regime: ClassVar[bool] = True
    # Attributes a copy or a pickle leaves out because the env recomputes them when it needs them (caches that
    # may hold what cannot be pickled, e.g. a solver's dense output).
    _recomputed: ClassVar[tuple[str, ...]] = ()

    def __init__(
        self,
        *,
        case: str | None = None,
        params: Mapping[str, Any] | None = None,
        profile: str = "reference",
        integrator: str | None = None,
        timestep: float | None = None,
        frame_skip: int | None = None,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
    ) -> None:
        self.scenario = self.scenario_cls()
        self._settings = harness().settings_for(profile, integrator=integrator, timestep=timestep)
        self.frame_skip = self.default_frame_skip if frame_skip is None else int(frame_skip)
        if self.frame_skip < 1:
            raise ValueError(f"frame_skip = {frame_skip!r} must be an integer >= 1")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self._width, self._height = int(width), int(height)
        self._case_name = self.scenario.case(case).name
        self._params = dict(params or {})
        self._resolved: dict[tuple, dict[str, Any]] = {}  # per case and user parameters: `Scenario.resolve`'s values
        self._resolve(self._case_name, self._params)  # fail now, not at reset (and kept for the first reset)
        self._models: dict[tuple, mujoco.MjModel] = {}
        self._starts: dict[tuple, tuple] = {}  # per model: its episode's start (`load`)
        self._data_key: tuple | None = None  # the configuration the last reset installed `_episode_data` for
        self._episode_data: mujoco.MjData | None = None
        self._renderer: mujoco.Renderer | None = None
        self.load(self._case_name, self._params)
        self.observation_space = self.define_observation_space()
        if len(self.observation_space.shape) != 1:
            raise TypeError(f"{type(self).__name__}: observations must be 1-D, not {self.observation_space.shape}")
        # The action an agent sends is normalised, float32 in [-1, 1] per component (gymnasium's MuJoCo envs and
        # SB3's convention, issue 17); the env's physical action (SI) is that times `action_scale`, the bound
        # `define_action_space` states in SI units. The hooks see the physical action only.
        physical = self.define_action_space()
        if not np.array_equal(physical.low, -physical.high) or not np.all(physical.high > 0):
            raise TypeError(
                f"{type(self).__name__}: the physical action bounds must be symmetric, +-high with high > 0"
            )
        self.action_scale = np.array(physical.high, dtype=np.float64)  # SI units of one unit of action
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=physical.shape, dtype=np.float32)
        self._action_shape = self.action_space.shape
        self._unit_scale = bool(np.all(self.action_scale == 1.0))  # a unit box: the physical action is the action
        self._scale_values = self.action_scale.tolist()
        self._physical_out = np.empty(physical.shape)  # `_checked_action`'s output buffer

    # ---- the MjData and the views into it ---------------------------------------------------------------

    _views_ready = False  # True once the episode's views are bound: from then on a new `data` rebinds them
    # The float precision the model and state are stored in (`rigidbench.engines.stored_model`): float64 for the env
    # itself; a batched vector env on a float32 engine sets its template's to float32 before its first reset, so
    # the theory is the body that engine simulates.
    _precision = "float64"
    # The engine stepping it (a batched vector env's), named where its precision refuses a start.
    _engine_name = "mujoco"

    @property
    def data(self) -> mujoco.MjData:
        """The MjData being stepped. Assigning another one (a new episode, `ClosedLoopTask`'s scratch rollout, the
        dm_control view) rebinds the views a step reads and writes (`bind_views`), so no hook has to check.
        Per-step code may read `self._data` directly: the same object, without the property's ~40 ns.

        A reset of the configuration the env ran last puts the start back into the MjData that configuration's last
        reset installed (`load`): copy an episode's final state (``copy.copy(env.data)``) to keep it past a reset.
        An MjData assigned from outside is never written by a reset."""
        return self._data

    @data.setter
    def data(self, data: mujoco.MjData) -> None:
        self._data = data
        if self._views_ready:
            self.bind_views()

    def bind_views(self) -> None:
        """Build the views into `self.data` that a step reads or writes (none by default; numpy views save the
        ~0.2 us of slicing a MuJoCo array afresh every step)."""

    def start_views(self) -> None:
        """Bind the views for a new episode: a subclass calls it at the end of its `load`, once it has cached
        what `bind_views` needs (addresses and ids of the compiled model)."""
        self._views_ready = True
        self.bind_views()

    # ---- hooks -------------------------------------------------------------------------------------------

    # Names of the observables compared with theory every step (keys of info["measured"] / info["predicted"]).
    observables: ClassVar[tuple[str, ...]]

    def define_observation_space(self) -> gym.spaces.Box:
        """The observation space: a 1-D Box, its components and units listed in the env's docstring. Called once,
        by the constructor, after the first `load`."""
        raise NotImplementedError

    def define_action_space(self) -> gym.spaces.Box:
        """The physical action's bounds in SI units, symmetric (``-high .. high``). The agent sees a normalised
        float32 Box(-1, 1); `apply_action` receives the physical action (normalised action times ``high``)."""
        raise NotImplementedError

    def observe(self) -> np.ndarray:
        """The observation of the current state ``self.data`` (float64, shape of the observation space)."""
        raise NotImplementedError

    def apply_action(self, action: np.ndarray) -> None:
        """Write the physical action (SI, clipped to the bounds) into ``self.data`` (ctrl, qfrc_applied or
        xfrc_applied) before the frame skip's steps. Zero action must be the textbook problem."""
        raise NotImplementedError

    def theory(self, t: np.ndarray) -> np.ndarray:
        """The observables predicted by theory (zero action) at times `t` (s), shape (len(t), len(observables)).
        Tabulated once per episode on the env's time grid; a step looks its row up as a list of floats."""
        raise NotImplementedError

    def measured(self, obs: np.ndarray):
        """The same observables measured from an observation: an ndarray of shape (len(observables),) or a
        sequence of floats (cheaper per step where the hook computes in Python floats)."""
        raise NotImplementedError

    def deviation(self, measured, predicted: list[float]) -> float:
        """Normalised deviation of `measured` (as `measured` returns it) from the theory's row `predicted`
        (documented per env); the reward is its negative."""
        raise NotImplementedError

    def begin_episode(self) -> None:
        """Advance the fresh episode before its first observation (e.g. deliver a blow); nothing by default.

        Called by ``reset`` after the initial state is set and before the theory is tabulated from
        ``data.time`` on, so an episode may start at t > 0.
        """

    # ---- batched hooks ------------------------------------------------------------------------------------
    #
    # A batched vector env (`rigidbench.envs.vector`) asks for the same four hooks for N copies' states at once:
    # ``observe_batch(worlds)``, ``apply_actions(actions, worlds)``, ``measured_batch(obs)``,
    # ``deviation_batch(measured, predicted)``. An env that does not define them gets per-copy fallbacks that run the
    # hooks above once per copy (`rigidbench.envs.vector.PerCopyHooks`); a family defines them with array code doing
    # the same arithmetic in the same order, so a batched env equals N single envs bit for bit (tests/test_vector.py).

    @contextlib.contextmanager
    def _scratch(self):
        """A scratch MjData of the model bound as `data` for the block (the episode's data put back after)."""
        scratch, model = getattr(self, "_scratch_data", (None, None))
        if model is not self.model:
            scratch = mujoco.MjData(self.model)
            self._scratch_data = (scratch, self.model)
        saved = self._data
        self.data = scratch
        try:
            yield scratch
        finally:
            self.data = saved

    # ---- gymnasium API ----------------------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = set(options) - {"case", "params"}
        if unknown:
            raise ValueError(f"unknown reset option(s) {sorted(unknown)}; valid: 'case', 'params'")
        case = self.scenario.case(options.get("case", self._case_name)).name
        params = {**self._params, **dict(options.get("params") or {})}
        self.load(case, params)
        obs = self.observe()
        info = self._step_info(obs, 0)
        info.update(case=self._case, params=dict(self._actual), settings=dict(self._settings_record))
        return obs, info

    def step(self, action):
        obs, k, time, finite = self._physics_step(action)
        if not finite:
            return self._diverged_step(obs, k, time)
        info = self._step_info(obs, k, time)
        return obs, info["reward_deviation"], False, time >= self._end, info

    def _physics_step(self, action) -> tuple[np.ndarray, int, float, bool]:
        """The physics half of `step`, shared with a batched vector env of one (`VectorScenarioEnv`): the action
        applied, the frame skip's steps taken; the observation, step count, time, and whether the step is sound."""
        # Every line here runs once per step (issue 8): look-ups that are not free (model.opt, data.time, the
        # observable names, the episode's end) are cached by `load` or read once, and each hook is called once.
        self.apply_action(self._checked_action(action))
        data = self._data
        self._advance(data)
        k = self._k = self._k + 1
        obs = self.observe()
        time = data.time
        # `_diverged`, inlined: time fell behind (MuJoCo reset a blown-up state) or the observation is not finite.
        return obs, k, time, not time < self._behind + k * self._env_dt and math.isfinite(sum(obs.tolist()))  # 1-D obs

    def _advance(self, data: mujoco.MjData) -> None:
        """The physics of one env step: `frame_skip` steps of `data` with the inputs the action wrote into it.
        A batched vector env of one copy on MJX or Warp replaces it on its template (`VectorScenarioEnv`), so the
        engine steps and the rest of `step` is the same code."""
        mujoco.mj_step(self.model, data, self.frame_skip)  # positional: a keyword costs pybind11 ~0.2 us

    def _diverged_step(self, obs: np.ndarray, k: int, time: float):
        """The step on which the simulation diverged: it ends the episode and pays the worst the rest of the
        episode could have scored (`DEVIATION_CAP` for it and for each step left); ``info`` has the same keys as
        any step's, the measurement NaN."""
        left = max(0, math.ceil((self.episode_duration - (self._time0 + k * self._env_dt)) / self._env_dt))
        reward = -DEVIATION_CAP * (1 + left)
        names = self._observable_names
        predicted = self._rows[k] if k < self._table_len else [math.nan] * len(names)
        info = {
            "time": float(time),
            "measured": dict.fromkeys(names, math.nan),
            "predicted": dict(zip(names, predicted)),  # noqa: B905 (checked in `load`)
            "deviation": math.inf,
            "reward_deviation": reward,
            "diverged": True,
        }
        obs = np.clip(
            np.nan_to_num(obs, nan=0.0, posinf=0.0, neginf=0.0), self.observation_space.low, self.observation_space.high
        )
        return obs, reward, True, False, info

    def _checked_action(self, action) -> np.ndarray:
        """The physical action (float64, SI) of a normalised `action`: clipped to [-1, 1], times `action_scale`.

        Raises
        ------
        ValueError
            If the shape is wrong or a component is not finite.
        """
        if not (type(action) is np.ndarray and action.dtype is _FLOAT64):  # dtypes of builtin types are singletons
            action = np.asarray(action, dtype=np.float64)
        if action.shape != self._action_shape:
            raise ValueError(f"action shape {action.shape} != {self._action_shape}")
        # Fast path: every component inside [-1, 1] (NaN fails the comparison and takes the slow path). A loop,
        # not all(...): each costs ~0.3 us a step; the shape was checked above.
        values = action.tolist()
        for v in values:
            if not -1.0 <= v <= 1.0:
                if not np.isfinite(action).all():
                    raise ValueError(f"action {action} is not finite")
                # Out-of-range actions are clipped to the action space (gymnasium's MuJoCo convention).
                action = np.clip(action, -1.0, 1.0)
                values = action.tolist()
                break
        if self._unit_scale:
            return action
        # The product written into the env's own buffer, one float at a time: 0.13 us against 0.52 us for
        # `action * action_scale` (a new array). The buffer is the next step's too: a hook uses it at once.
        out, scale = self._physical_out, self._scale_values
        for i, v in enumerate(values):
            out[i] = v * scale[i]
        return out

    def physical_action(self, action) -> np.ndarray:
        """The physical action (SI: the torque or force the env applies) of a normalised `action`, as a step
        applies it (clipped to [-1, 1], times `action_scale`)."""
        return np.array(self._checked_action(action))

    def normalised_action(self, physical) -> np.ndarray:
        """The normalised action of a `physical` one (SI), in float64: inside the action space's bounds, and as
        precise as the physical action (a float32 copy would move it by up to 6e-8 of the bound)."""
        return np.asarray(physical, dtype=np.float64) / self.action_scale

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        return self._frame()

    def _frame(self) -> np.ndarray:
        """One RGB frame (height, width, 3) of the current state."""
        if self._renderer is None or self._renderer.model is not self.model:
            self.close()
            # Headless GL without a GPU (EGL/OSMesa on llvmpipe) spends most of a frame on the shadow map:
            # MuJoCo's default 4096^2 map makes a 480x480 frame ~3x slower than a 1024^2 one, which looks the
            # same at these sizes (0.03% of pixels differ). A map twice the frame's size, at least 1024^2.
            quality = self.model.vis.quality
            quality.shadowsize = min(quality.shadowsize, max(SHADOW_MAP_MIN, 2 * max(self._width, self._height)))
            self._renderer = mujoco.Renderer(self.model, height=self._height, width=self._width)
        self._renderer.update_scene(self.data, camera=self._camera())
        return self._renderer.render()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ---- copies ------------------------------------------------------------------------------------------

    def __getstate__(self) -> dict[str, Any]:
        """What a copy or a pickle keeps: everything but the renderer (a GL context) and the per-step views, which
        point into this env's MjData and are rebound to the copy's (`__setstate__`)."""
        state = self.__dict__.copy()
        state["_renderer"] = None
        state["_starts"] = {}  # initial states of this env's models: a copy's models are new objects, so are these
        state["_data_key"] = state["_episode_data"] = None
        for name in self._recomputed:
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        # A copied model is a new MjModel: the forces MuJoCo has no element for (`rigidbench.forces`) must be attached
        # to it as to the original, or the copy steps without them.
        for model in (*([self.model] if "model" in state else []), *state.get("_models", {}).values()):
            harness().attach_forces(model)
        if self._views_ready:
            self.bind_views()  # the copied views are arrays of their own: point them into the copied MjData

    # ---- internals --------------------------------------------------------------------------------------

    def _resolve(self, case: str, params: Mapping[str, Any]) -> dict[str, Any]:
        """`Scenario.resolve` of `case` with the user's `params`, kept for the next reset that asks for the same
        (a pure function of them; parameters that cannot be hashed, such as arrays, are resolved every time)."""
        try:
            ask = (case, tuple(sorted((k, type(v), v) for k, v in params.items())))
            resolved = self._resolved.get(ask)
        except TypeError:
            return self.scenario.resolve(self.scenario.case(case), params, regime=self.case_regime)
        if resolved is None:
            resolved = self.scenario.resolve(self.scenario.case(case), params, regime=self.case_regime)
            if len(self._resolved) >= 16:
                self._resolved.pop(next(iter(self._resolved)))
            self._resolved[ask] = resolved
        return dict(resolved)

    @property
    def params(self) -> dict[str, Any]:
        """Parameters as compiled into the current model."""
        return self._actual

    @property
    def prediction(self) -> Mapping[str, Any]:
        """The theory's prediction for the current configuration, computed once and shared by every episode of it
        (`load`): read it, do not change it."""
        return self._prediction

    def load(self, case: str, params: Mapping[str, Any]) -> None:
        """Install case `case` with the user's `params` for a new episode: its model (built once per configuration
        and kept), its initial state, prediction and theory table, then `begin_episode`.

        A subclass that caches what its per-step hooks need (ids and addresses in the compiled model) overrides it:
        ``super().load(case, params)``, then its caching, then ``self.start_views()``.
        """
        resolved = self._resolve(case, params)
        # The precision is part of the key: a batched vector env on a float32 engine sets its template's after the
        # template's constructor has loaded (and kept) the float64 model of the same parameters.
        key = (case, tuple(sorted((k, v) for k, v in resolved.items())), self._precision, self._engine_name)
        if key not in self._models:
            if len(self._models) >= 16:
                self._starts.pop(next(iter(self._models)), None)
                self._models.pop(next(iter(self._models)))
            self._models[key] = harness().env_model(self.scenario, resolved, self._settings, self._precision)
        self._views_ready = False  # the views of the last episode may not fit this model: `start_views` rebinds
        self.model = self._models[key]
        harness().attach_forces(self.model)  # cheap and idempotent; a copied env's models are new objects
        start = self._starts.get(key)
        if start is None:
            start = harness().env_start(self.scenario, self.model, self._precision, self._engine_name)
            self._starts[key] = start
            data = copy.copy(start[1])
        elif self._data_key == key:  # the last episode's configuration: the MjData it installed, back at the start
            data = self._episode_data  # not `self._data`, which may be a caller's own by now (`rigidbench.suite`)
            mujoco.mj_copyData(data, self.model, start[1])
        else:
            data = copy.copy(start[1])
        # Every reset of one configuration starts the same (the scenarios draw nothing at random): its parameters,
        # initial state and prediction are computed once and kept with its model, and the state is copied into the
        # episode's MjData (an autoreset cost a HeavyTop env 2.1 ms, 5 us a step of its 426-step episode: `resolve`
        # and `predict`, and a new MjData, whose 13.6 MB arena took 0.5 ms to allocate; `mj_copyData` takes 5 us).
        self._data_key, self._episode_data = key, data
        actual, _, self._prediction, self.episode_duration, settings_record = start
        # Each episode's own copies: `params` hands one out, and the reset's info both (gymnasium's checker asks that
        # no two resets' infos share an object; the settings hold a dict).
        self._actual, self._settings_record = copy.deepcopy(actual), copy.deepcopy(settings_record)
        self.data = data
        self._observable_names = tuple(self.observables)  # may be a property of the model: read once, not per step
        self._case = case
        self.begin_episode()
        # Theory on the env's time grid, evaluated once (vectorised) so a step costs a table lookup.
        self._env_dt = env_dt = self.model.opt.timestep * self.frame_skip
        self.metadata = {**type(self).metadata, "render_fps": _fps(env_dt)}
        self._time0 = float(self.data.time)
        self._behind = self._time0 - 0.5 * env_dt  # step k has fallen behind (diverged) before time _behind + k env_dt
        n = int(np.ceil(self.episode_duration / env_dt)) + 2
        self._k = 0
        table = self.theory(self._time0 + env_dt * np.arange(n))
        if table.shape[1:] != (len(self._observable_names),):
            raise ValueError(
                f"{type(self).__name__}: the theory gives {table.shape[1:]} values a step for the "
                f"{len(self._observable_names)} observables {self._observable_names}"
            )
        # Rows as lists of floats: a step indexes a list and builds its info from floats, no ndarray per step.
        self._rows = table.tolist()
        self._table_len = len(self._rows)
        self._end = self.episode_duration - 0.5 * self.model.opt.timestep  # truncate from this time on

    def _step_info(self, obs: np.ndarray, k: int, time: float | None = None) -> dict[str, Any]:
        """The info of step `k` (0: reset), at simulated `time` (s; default ``data.time``)."""
        if time is None:
            time = self.data.time
        measured_values, predicted, deviation = self._score(obs, k, time)
        names = self._observable_names
        if len(names) == 1:  # one observable: a dict display costs a quarter of dict(zip(...)) (~0.15 us each)
            name = names[0]
            measured_dict, predicted_dict = {name: measured_values[0]}, {name: predicted[0]}
        else:
            measured_dict = dict(zip(names, measured_values))  # noqa: B905 (lengths checked at reset)
            predicted_dict = dict(zip(names, predicted))  # noqa: B905 (checked in `load`)
        return {
            "time": time,
            "measured": measured_dict,
            "predicted": predicted_dict,
            "deviation": deviation,
            "reward_deviation": capped_reward(deviation),
            "diverged": False,
        }

    def _score(self, obs: np.ndarray, k: int, time: float) -> tuple[list[float], list[float], float]:
        """Step `k`'s measured and predicted observables (Python floats, in `_observable_names`' order) and the
        deviation between them (`_step_info`'s numbers, before any dict is built)."""
        predicted = self._rows[k] if k < self._table_len else self.theory(np.array([time]))[0].tolist()
        measured = self.measured(obs)
        deviation = self.deviation(measured, predicted)
        # The hook returns an ndarray or Python floats, one per observable: checked at reset (k = 0), trusted after.
        measured_values = measured.tolist() if type(measured) is np.ndarray else measured
        if not k and (not _all_floats(measured_values) or len(measured_values) != len(self._observable_names)):
            names = self._observable_names
            raise TypeError(
                f"{type(self).__name__}.measured returned {measured!r}: an ndarray or a sequence of Python floats, "
                f"one for each of the {len(names)} observables {names}, is required"
            )
        return measured_values, predicted, deviation

    def _compare(self) -> tuple[float, np.ndarray, np.ndarray]:
        """Deviation, measured and predicted observables at the current state (any time, no table)."""
        measured = self.measured(self.observe())
        predicted = self.theory(np.array([self.data.time]))[0]
        return self.deviation(measured, predicted.tolist()), np.asarray(measured, dtype=float), predicted

    def _diverged(self, obs: np.ndarray) -> bool:
        """MuJoCo resets a blown-up state (bad qpos, qvel or qacc): time jumps back to ~0, and NaN never
        persists. So a step that did not advance time by the expected amount, or a non-finite observation,
        means the simulation diverged."""
        time = self.data.time
        expected = self._time0 + self._k * self._env_dt
        # Python's sum over a list is ~10x cheaper than ndarray.sum() on a handful of values (same verdict).
        return time < expected - 0.5 * self._env_dt or not math.isfinite(sum(obs.ravel().tolist()))

    def _camera(self) -> int | str:
        return "side" if mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, "side") >= 0 else -1


def _all_floats(values) -> bool:
    """Whether `values` is a sequence of Python floats (what ``info`` may hold as it is, e.g. for JSON)."""
    return all(type(v) is float for v in values)


def _fps(env_dt: float) -> float | int:
    """Frames per second of real-time playback at `env_dt` simulated seconds per step (an int when whole)."""
    fps = 1.0 / env_dt
    return round(fps) if abs(fps - round(fps)) <= 1e-9 * fps else fps
