"""Gymnasium plumbing shared by every scenario env: loading, settings, frame skip, seeding, rendering.

A scenario env is a thin view of its `Scenario` (house rule 11): the scenario resolves parameters, builds the
model, sets the initial state and predicts; the env steps MuJoCo, applies the action, and scores the state
against the theory at every step. A subclass sets `scenario_cls` and implements four small hooks.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench.scenario import Scenario
from rigidbench.settings import Settings, profile, read_settings


class ScenarioEnv(gym.Env):
    """Base class of the validation environments (zero action = the textbook problem).

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
        self._settings = _settings(profile, integrator, timestep)
        self.frame_skip = self.default_frame_skip if frame_skip is None else int(frame_skip)
        if self.frame_skip < 1:
            raise ValueError(f"frame_skip = {frame_skip!r} must be an integer >= 1")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self._width, self._height = int(width), int(height)
        self._case_name = self.scenario.case(case).name
        self._params = dict(params or {})
        self.scenario.resolve(self.scenario.case(case), self._params)  # fail now, not at reset
        self._models: dict[tuple, mujoco.MjModel] = {}
        self._renderer: mujoco.Renderer | None = None
        self._load(self._case_name, self._params)
        self.observation_space = self._observation_space()
        self.action_space = self._action_space()

    # ---- hooks -------------------------------------------------------------------------------------------

    def _observation_space(self) -> gym.spaces.Box:
        raise NotImplementedError

    def _action_space(self) -> gym.spaces.Box:
        raise NotImplementedError

    def _observation(self) -> np.ndarray:
        raise NotImplementedError

    def _apply_action(self, action: np.ndarray) -> None:
        raise NotImplementedError

    def _compare(self) -> tuple[float, dict[str, Any], dict[str, Any]]:
        """(normalised deviation from theory, measured observables, predicted observables) at this instant."""
        raise NotImplementedError

    # ---- gymnasium API ----------------------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = set(options) - {"case", "params"}
        if unknown:
            raise ValueError(f"unknown reset option(s) {sorted(unknown)}; valid: 'case', 'params'")
        case = self.scenario.case(options.get("case", self._case_name)).name
        params = {**self._params, **dict(options.get("params") or {})}
        self._load(case, params)
        return self._observation(), self._info(0.0)

    def step(self, action):
        action = np.asarray(action, dtype=np.float64)
        if action.shape != self.action_space.shape:
            raise ValueError(f"action shape {action.shape} != {self.action_space.shape}")
        if not np.all(np.isfinite(action)):
            raise ValueError(f"action {action} is not finite")
        # Out-of-range actions are clipped to the action space (gymnasium's MuJoCo convention).
        self._apply_action(np.clip(action, self.action_space.low, self.action_space.high))
        mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)
        diverged = self._diverged()
        if diverged:
            obs = np.nan_to_num(self._observation(), nan=0.0, posinf=0.0, neginf=0.0)
            obs = np.clip(obs, self.observation_space.low, self.observation_space.high)
            return obs, 0.0, True, False, {"diverged": True, "time": float(self.data.time)}
        deviation, measured, predicted = self._compare()
        reward = -deviation
        truncated = self.data.time >= self.episode_duration - 0.5 * self.model.opt.timestep
        info = self._info(reward, measured, predicted, deviation)
        return self._observation(), reward, False, bool(truncated), info

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None or self._renderer.model is not self.model:
            self.close()
            self._renderer = mujoco.Renderer(self.model, height=self._height, width=self._width)
        self._renderer.update_scene(self.data, camera=self._camera())
        return self._renderer.render()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ---- internals --------------------------------------------------------------------------------------

    @property
    def params(self) -> dict[str, Any]:
        """Parameters as compiled into the current model."""
        return self._actual

    @property
    def prediction(self) -> Mapping[str, Any]:
        return self._prediction

    def _load(self, case: str, params: Mapping[str, Any]) -> None:
        resolved = self.scenario.resolve(self.scenario.case(case), params)
        key = (case, tuple(sorted((k, v) for k, v in resolved.items())))
        if key not in self._models:
            if len(self._models) >= 16:
                self._models.pop(next(iter(self._models)))
            self._models[key] = self.scenario.build(resolved, self._settings)
        self.model = self._models[key]
        self._actual = self.scenario.read_params(self.model)
        self.data = self.scenario.start(self.model, self._actual)
        self._prediction = self.scenario.predict(self.model, self.data)
        self.episode_duration = float(self.scenario.duration(self._prediction))
        self._settings_record = read_settings(self.model)
        self._case = case
        self._warnings0 = int(self.data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number)

    def _diverged(self) -> bool:
        bad_acc = self.data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > self._warnings0
        return bool(bad_acc or not (np.isfinite(self.data.qpos).all() and np.isfinite(self.data.qvel).all()))

    def _camera(self) -> int | str:
        return "side" if mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, "side") >= 0 else -1

    def _info(self, reward: float, measured=None, predicted=None, deviation: float = 0.0) -> dict[str, Any]:
        return {
            "time": float(self.data.time),
            "case": self._case,
            "measured": measured or {},
            "predicted": predicted or {},
            "reward_deviation": float(reward),
            "deviation": float(deviation),
            "diverged": False,
            "params": dict(self._actual),  # fresh dicts of immutable values: callers may keep them
            "settings": dict(self._settings_record),
        }


def _settings(profile_name: str, integrator: str | None, timestep: float | None) -> Settings:
    return profile(profile_name).merged(Settings(integrator=integrator, timestep=timestep))
