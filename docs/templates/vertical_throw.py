"""Template scenario: a ball thrown straight up. Copy it to ``envs/<your_stem>.py`` (docs/scenarios.md).

Everything a scenario is, in one file: parameters with units and ranges, named cases, checks with tolerances and
the reasons for them, the hooks that set the initial state, predict from ``analytic/`` and measure from the
trajectory, and the gymnasium env. It imports the contract (`rigidbench.contract`), never the machinery that runs
it. Theory: uniform gravity, z(t) = v0 t - g t^2 / 2; apex v0^2 / (2 g) at v0 / g, back at z = 0 after 2 v0 / g.
(A real scenario puts the closed form in ``analytic/<family>.py`` and cites its docs/theory.md ID.)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import signals
from rigidbench.contract import Case, Check, Derived, Scenario, Trajectory, round_step
from rigidbench.envs.base import ScenarioEnv
from rigidbench.params import BodyMass, Gravity, Numeric, Param, Range

# Where each tolerance comes from (house rule 9): RK4 integrates a constant acceleration exactly, so the errors are
# double-precision round-off over ~1,250 steps (measured 1e-14), and the events are located by cubic interpolation,
# exact for a parabola. The tolerances leave three decades above that.
_RK4 = (
    "RK4 is exact for a constant acceleration: round-off ~1e-14 over the run (1e-11 leaves 3 decades); cubic "
    "interpolation is exact on a parabola"
)
CHECKS = (
    Check(
        "apex-height",
        "m",
        1e-9,
        "rel",
        _RK4,
        "uniform gravity (a real scenario cites its docs/theory.md ID here): apex v0^2 / (2 g)",
    ),
    Check("flight-time", "s", 1e-11, "rel", _RK4, "uniform gravity: back at the launch height after 2 v0 / g"),
    Check(
        "energy-drift", "1", 1e-10, "abs", _RK4, "uniform gravity: 1/2 m v^2 + m g z conserved (relative to 1/2 m v0^2)"
    ),
)
_ALL = tuple(c.name for c in CHECKS)


class VerticalThrow(Scenario):
    """A ball thrown straight up in uniform gravity, no drag."""

    slug = "vertical-throw"  # the model file is models/vertical_throw.xml
    title = "Ball thrown straight up (uniform gravity)"
    env_id = "rigidbench/VerticalThrow-v0"
    params = (
        Param("mass", "kg", "mass of the ball", Range(1e-3, 1e3), BodyMass("ball")),
        Param("speed", "m/s", "launch speed, upwards", Range(1e-2, 1e2), Numeric("speed")),
        Param("g", "m/s^2", "gravitational acceleration (along -z)", Range(1e-2, 1e3), Gravity()),
    )
    cases = (
        Case("default", "thrown at 3 m/s: apex 0.459 m after 0.306 s", {}, _ALL),
        Case("slow", "thrown at 0.3 m/s: apex 4.6 mm", {"speed": 0.3}, _ALL),
    )
    checks = CHECKS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        """The timestep follows the only time scale, the flight time 2 v0 / g: a thousandth of it (the model file's
        timestep is this rule's value at the defaults, so the file and the derived settings agree)."""
        flight = 2 * params["speed"] / params["g"]
        return {"timestep": Derived(round_step(flight / 1000), f"dt = T / 1000, T = 2 v0 / g = {flight:.4g} s")}

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[0] = 0.0
        data.qvel[0] = params["speed"]

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        # From the state MuJoCo holds and the gravity it compiled (house rule 4), not from the requested numbers.
        v0, g = float(data.qvel[0]), float(-model.opt.gravity[2])
        return {"_v0": v0, "_g": g, "apex-height": v0**2 / (2 * g), "flight-time": 2 * v0 / g, "energy-drift": 0.0}

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return 1.25 * prediction["flight-time"]  # past the landing, so the crossing is bracketed

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        t, z, v = traj.time, traj.qpos[:, 0], traj.qvel[:, 0]
        _, apex = signals.extrema(t, z, v, "max")
        landing = signals.crossings(t[1:], z[1:], direction=-1)  # the launch sample itself is z = 0
        g, v0 = prediction["_g"], prediction["_v0"]
        energy = 0.5 * v**2 + g * z  # per unit mass
        return {
            "apex-height": float(apex[0]),
            "flight-time": float(landing[0]),
            "energy-drift": float(np.max(np.abs(energy - energy[0])) / (0.5 * v0**2)),
        }


class VerticalThrowEnv(ScenarioEnv):
    """``rigidbench/VerticalThrow-v0``: a ball thrown straight up, scored against z(t) = v0 t - g t^2 / 2.

    Observation Space
        Box(-inf, inf, (2,)), float64: [0] height z (m), [1] its rate (m/s); qpos and qvel of the joint ``height``.

    Action Space
        Box(-1, 1, (1,)), float32, normalised: ``max_force = 0.1`` N times it, along z, through ``qfrc_applied``.
        Zero action = the textbook problem.

    Rewards
        ``-|z - z_theory(t)| / apex``, each step's deviation capped at ``DEVIATION_CAP``.

    Starting State
        ``z = 0``, ``dz/dt = speed``.

    Episode End
        Truncated after 1.25 flight times; terminated on divergence.
    """

    scenario_cls = VerticalThrow
    observables: ClassVar[tuple[str, ...]] = ("height",)
    max_force: ClassVar[float] = 0.1

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(2,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        # The physical bounds in SI units; the agent sees them normalised to Box(-1, 1) float32 (`ScenarioEnv`).
        return gym.spaces.Box(-self.max_force, self.max_force, shape=(1,), dtype=np.float64)

    def observe(self) -> np.ndarray:
        return np.array([self.data.qpos[0], self.data.qvel[0]])

    def apply_action(self, action: np.ndarray) -> None:
        self.data.qfrc_applied[0] = action[0]

    def theory(self, t: np.ndarray) -> np.ndarray:
        p = self.prediction
        return (p["_v0"] * t - 0.5 * p["_g"] * t**2)[:, None]

    def measured(self, obs: np.ndarray) -> list[float]:
        return [float(obs[0])]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        return abs(measured[0] - predicted[0]) / self.prediction["apex-height"]
