"""Simple pendulum at any amplitude: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md O1 (exact period ``4 sqrt(l/g) K(sin(a/2))``) and O2 (physical pendulum: l -> I_O/(M h)),
implemented in `rigidbench.analytic.pendulum`. Model: ``models/pendulum.xml`` (one hinge about world y at
the origin, a point bob at ``length`` below it).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import signals
from rigidbench.analytic import pendulum as osc
from rigidbench.contract import Case, Check, Derived, Scenario, Trajectory
from rigidbench.envs import pendulums
from rigidbench.envs.pendulums import PendulumEnv, RodLength
from rigidbench.params import Gravity, Numeric, Param, Range

_RK4 = (
    "RK4 at dt = 6.26e-3 / omega_max (2 ms at the defaults; omega_max = sqrt(g/l) max(1, 2 sin(a/2)), the bob's "
    "largest rate): relative frequency error (omega dt)^4/120 ~ 1e-11; crossings cubic-interpolated, O(dt^4); 20 "
    "periods fitted"
)
CHECKS = (
    Check("period", "s", 1e-6, "rel", _RK4, "O1: T = 4 sqrt(l_eq/g) K(sin(a/2)), l_eq = I_O/(m l) (O2)"),
    Check(
        "turning-angle",
        "rad",
        1e-7,
        "rel",
        "energy conservation fixes the turning angle; RK4 energy error ~1e-13 here; the extremum is "
        "cubic-interpolated, error (omega dt)^4 ~ 1e-10 (omega dt fixed by the derived timestep)",
        "O1: released from rest, the pendulum turns at +-amplitude",
    ),
    Check(
        "energy-drift",
        "1",
        1e-8,
        "abs",
        "RK4 is not symplectic: relative drift ~ T (omega dt)^6/(72 dt) <~ 4e-11 over the run (20 periods at the "
        "derived omega dt); 1e-8 leaves 2 decades",
        "O1: E = 1/2 I_O th'^2 + m g l (1 - cos th) conserved (relative to m g l (1 - cos a))",
    ),
)
_ALL = ("period", "turning-angle", "energy-drift")


class Pendulum(Scenario):
    """A simple pendulum released from rest, from small amplitudes to 3 rad (docs/theory.md O1, O2)."""

    slug = "pendulum"
    title = "Simple pendulum at any amplitude (exact elliptic period)"
    env_id = "rigidbench/SimplePendulum-v0"  # gymnasium's own classic-control Pendulum-v1 is a different problem
    # The theory (O1) is exact at every amplitude and has no scale of its own: l and g only set the time scale
    # sqrt(l/g), which the derived timestep and run length follow. The bounds are generous: 1 mm to 100 m, a
    # microgravity 1e-6 m/s^2 to 100 g, a microradian to 0.04 rad short of upright.
    params = (
        Param("length", "m", "distance l from the pivot to the point bob", Range(1e-3, 100.0), RodLength()),
        Param(
            "amplitude",
            "rad",
            "release angle from the downward vertical (at rest); pi would balance upright",
            Range(1e-6, 3.1),
            Numeric("amplitude"),
        ),
        Param("g", "m/s^2", "gravitational acceleration (along -z)", Range(1e-6, 1e3), Gravity()),
    )
    cases = (
        Case("one-radian", "released at 1 rad: period 1.07 T0", {"amplitude": 1.0}, _ALL),
        Case(
            "small-amplitude", "released at 0.01 rad: the small-angle limit, T0 (1 + 6e-6)", {"amplitude": 0.01}, _ALL
        ),
        Case("large-amplitude", "released at 2.5 rad: period 1.78 T0", {"amplitude": 2.5}, _ALL),
        Case("near-inverted", "released at 3 rad, 0.14 rad from upright: period 2.55 T0", {"amplitude": 3.0}, _ALL),
    )
    checks = CHECKS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        """The timestep follows the fastest rate: sqrt(g/l), or the bob's rate at the bottom, 2 sqrt(g/l) sin(a/2),
        when larger (a near-inverted release swings through the bottom at up to twice sqrt(g/l))."""
        return {"timestep": pendulums.timestep_for(_omega_max(params), _rate0(type(self)), _OMEGA_MAX)}

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[0] = params["amplitude"]
        data.qvel[0] = 0.0

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        (p,) = pendulums.pendulums(model)
        g = pendulums.gravity(model)
        amplitude = float(data.qpos[0])
        length_eq = p.inertia_pivot / (p.mass * p.length)  # O2: equivalent simple-pendulum length
        return {
            "_length_eq": length_eq,
            "_g": g,
            "_amplitude": amplitude,
            "_scale": amplitude,
            "_energy_scale": 2 * p.mass * g * p.length * np.sin(amplitude / 2) ** 2,  # m g l (1 - cos a)
            "period": osc.pendulum_period(length_eq, g, amplitude),
            "turning-angle": amplitude,
            "energy-drift": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return 20.25 * prediction["period"]  # 20 periods: 40 zero crossings

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        t, theta, rate = traj.time, traj.qpos[:, 0], traj.qvel[:, 0]
        _, turning = signals.extrema(t, np.abs(theta), np.sign(theta) * rate, "max")
        turning = np.concatenate([[theta[0]], turning])
        return {
            "period": 2 * np.pi / pendulums.frequency(t, theta),
            "turning-angle": float(turning[np.argmax(np.abs(turning - prediction["turning-angle"]))]),
            "energy-drift": pendulums.energy_drift(
                pendulums.row_energy(model, traj.qpos, traj.qvel), prediction["_energy_scale"]
            ),
        }


_OMEGA_MAX = "sqrt(g/l) max(1, 2 sin(amplitude/2))"


def _omega_max(params: Mapping[str, Any]) -> float:
    """The pendulum's fastest rate (rad/s): sqrt(g/l), or its angular speed at the bottom if larger."""
    return float(np.sqrt(params["g"] / params["length"]) * max(1.0, 2 * np.sin(params["amplitude"] / 2)))


@functools.cache
def _rate0(cls: type[Pendulum]) -> float:
    return pendulums.default_rate(cls(), _omega_max)


class SimplePendulumEnv(PendulumEnv):
    """``rigidbench/SimplePendulum-v0``: the simple pendulum at any amplitude, scored against the exact solution.

    Description
        A point bob on a massless rod, hinged about the world y axis, released from rest at ``amplitude``. With
        zero action it is the textbook pendulum (docs/theory.md O1): ``sin(th/2) = k cd(omega0 t, k)``, ``k =
        sin(amplitude/2)``, period ``4 K(k)/omega0``. (The id avoids gymnasium's ``Pendulum-v1``, a torque-
        limited swing-up task.)

    Observation Space
        Box(-inf, inf, (2,)), float64: [0] ``hinge`` angle from the downward vertical (rad, positive turns the
        bob towards -x), [1] its rate (rad/s); qpos and qvel of the joint ``hinge``.

    Action Space
        Box(-1, 1, (1,)), float32, normalised: ``action_scale = 0.1`` N m times it is a torque about the hinge
        axis, through ``qfrc_applied``; out-of-range
        actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|th - th_theory(t)| / amplitude``; ``info["measured"]["angles"]`` and
        ``info["predicted"]["angles"]`` hold both (rad).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        ``th = amplitude``, at rest.

    Episode End
        Truncated after 20.25 periods; terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (one-radian, small-amplitude, large-amplitude, near-inverted), ``params`` (length, amplitude,
        g), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10: ten derived steps, 20 ms at the
        defaults), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = Pendulum

    def theory(self, t: np.ndarray) -> np.ndarray:
        p = self.prediction
        return osc.pendulum_angle(t, p["_length_eq"], p["_g"], p["_amplitude"])[:, None]
