"""A stick on a frictionless pivot at one end, struck perpendicularly: the pivot's reaction impulse, and the
sweet spot where it vanishes. The MuJoCo side, and its gymnasium env.

Theory: THEORY.md P4 (J = Pi (M d_cm d / I_O - 1), zero at d* = I_O / (M d_cm) = 2L/3 for a uniform rod: the centre
of percussion referred to the pivot, the equivalent length of the physical pendulum, Wilcox prob. 11.7),
implemented in `rigidbench.analytic.percussion`.
Model: ``models/pivoted_stick.xml``: a free stick pinned at its end to the world by a soft equality constraint
(MuJoCo computes the pin's force), no gravity (frictionless ice); the blow is a rectangular force pulse
(`rigidbench.pulse`) along world +x at ``strike`` from the pivot; measured right after the pulse.

Measurement: the pivot's reaction impulse along the blow is what the pin added to the stick's momentum,
J = M V_cm,x - Pi (the pulse's own impulse is exactly Pi), read once the soft pin has settled, 10 of its time
constants after the pulse; by then the stick has turned by omega t', so the rigid prediction for that instant,
M omega d_cm cos(omega t') - Pi, is what is compared (t' from the pulse's centroid).
Conventions: THEORY.md section 6 and P4: the stick lies along +y from the pivot; J > 0 along +x.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import pulse
from rigidbench.analytic import percussion
from rigidbench.envs.planar import BlowEnv, free_body_motion, wrap_angle
from rigidbench.params import Numeric, Param, Range, RodLength, ScaledBodyMass, SitePosition, positive
from rigidbench.scenario import Case, Check, Scenario
from rigidbench.simulate import Trajectory

_PIN = (
    "read 10 pin time constants (2 ms) after the 0.1 ms pulse, when the soft pin's response has decayed to "
    "~10 e^-10 ~ 5e-4 of its load and the pin yields only ~ a tc^2 ~ 1e-8 m (measured residuals <= 5e-8); "
    "the pulse's O(omega tau) share (THEORY.md F2 saw 5.3e-5 Pi with a 2 ms pulse read at its end) is "
    "O((omega tau)^2) ~ 1e-7 here, read after the pin has settled"
)
CHECKS = (
    Check(
        "reaction-impulse",
        "1",
        1e-6,
        "abs",
        _PIN + "; in units of Pi",
        "P4: J / Pi = M d_cm d / I_O - 1, zero at d* = I_O / (M d_cm) = 2L/3 (times cos(omega t') for the turn "
        "since the blow)",
    ),
    Check(
        "angular-velocity",
        "rad/s",
        1e-6,
        "rel",
        _PIN,
        "P4: omega = -Pi d / I_O (angular momentum about the pivot, conserved after the blow)",
    ),
    Check(
        "pivot-drift",
        "m",
        1e-6,
        "abs",
        "largest distance of the pinned end from the pivot over the run: the soft pin yields ~ a tc^2 under the "
        "centripetal acceleration a = omega^2 d_cm of the CM (tc = 0.2 ms: <~ 1e-7 m at |omega| <= 12 rad/s) "
        "and the pulse",
        "P4: frictionless fixed pivot",
    ),
)
_ALL = tuple(c.name for c in CHECKS)


class PivotedStick(Scenario):
    """A uniform stick pinned at one end, struck perpendicularly at ``strike`` from the pivot: the pivot's
    reaction impulse against the strike distance, zero at the sweet spot 2L/3 (THEORY.md P4)."""

    slug = "pivoted-stick"
    title = "Stick on a pivot struck perpendicularly: pivot reaction impulse, sweet spot at 2L/3"
    env_id = "rigidbench/PivotedStick-v0"
    params = (
        Param("mass", "kg", "mass M of the stick", Range(1e-6, 1e3), ScaledBodyMass("stick")),
        Param(
            "length",
            "m",
            "full length L of the uniform stick, pivoted at one end; I_O = M L^2 / 3",
            Range(1e-3, 100.0),
            RodLength("stick", "stick", from_origin=True),
        ),
        Param("impulse", "N s", "impulse Pi of the blow, along +x (world)", positive(1e3), Numeric("impulse")),
        Param(
            "strike",
            "m",
            "distance d from the pivot along the stick to the strike point, in (0, L]",
            positive(100.0),
            SitePosition("strike", 1),
        ),
    )
    cases = (
        Case(
            "sweet-spot",
            "struck at d* = I_O / (M d_cm) = 2L/3: no reaction at the pivot",
            {"strike": lambda p: 2 * p["length"] / 3},
            _ALL,
        ),
        Case(
            "centre",
            "struck at the centre of mass: the pivot pulls back, J = -Pi/4",
            {"strike": lambda p: p["length"] / 2},
            _ALL,
        ),
        Case(
            "end",
            "struck at the free end: the pivot pushes forward, J = +Pi/2",
            {"strike": lambda p: p["length"]},
            _ALL,
        ),
        Case("near-pivot", "struck at L/4: J = -5 Pi/8", {"strike": lambda p: p["length"] / 4}, _ALL),
    )
    checks = CHECKS

    def validate(self, params: Mapping[str, Any]) -> None:
        if params["strike"] > params["length"]:
            raise ValueError(
                f"parameter 'strike' = {params['strike']:g} m is outside the valid range (0, {params['length']:g}] m "
                "(the stick's length): the blow must hit the stick"
            )

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[:] = [0, 0, 0, 1, 0, 0, 0]
        data.qvel[:] = 0.0

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        body = model.body("stick")
        mass, d_cm = float(body.mass[0]), float(body.ipos[1])
        inertia_pivot = float(body.inertia[2]) + mass * d_cm**2  # parallel axes, THEORY.md R4
        strike = float(model.site("strike").pos[1])
        impulse = float(model.numeric("impulse").data[0])
        tau = pulse.duration(model)
        omega = -impulse * strike / inertia_pivot
        # Read when the pin has settled: 10 time constants of its constraint (solref[0], or 1/sqrt(k) if direct).
        solref = model.eq_solref[model.equality("pivot").id]
        time_constant = solref[0] if solref[0] > 0 else 1.0 / np.sqrt(-solref[0])
        n_read = pulse.steps(model) + int(np.ceil(10 * time_constant / model.opt.timestep))
        turned = omega * (n_read * model.opt.timestep - tau / 2)
        blow = percussion.pivot_reaction_impulse(mass, inertia_pivot, d_cm, strike, impulse)
        return {
            "_impulse": impulse,
            "_tau": tau,
            "_read": n_read,
            "_t_read": n_read * float(model.opt.timestep),
            "_sweet_spot": percussion.sweet_spot(mass, inertia_pivot, d_cm),
            "reaction-impulse": ((blow + impulse) * np.cos(turned) - impulse) / impulse,
            "angular-velocity": omega,
            "pivot-drift": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        # a one-radian swing, and at least until the reading time
        return max(prediction["_tau"] + 1.0 / abs(prediction["angular-velocity"]), 1.01 * prediction["_t_read"])

    def control(self, model: mujoco.MjModel, timestep: float, nstep: int) -> np.ndarray:
        return pulse.control(model, nstep, "strike", float(model.numeric("impulse").data[0]))

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        m = free_body_motion(model, traj, "stick")
        body = model.body("stick")
        n = min(prediction["_read"], len(m.time) - 1)
        v_cm = m.point_velocity_W(body.ipos)[n]
        return {
            "reaction-impulse": float((body.mass[0] * v_cm[0] - prediction["_impulse"]) / prediction["_impulse"]),
            "angular-velocity": float(m.omega_W[n, 2]),
            "pivot-drift": float(np.linalg.norm(m.com_W, axis=1).max()),
        }


class PivotedStickEnv(BlowEnv):
    """``rigidbench/PivotedStick-v0``: the pivoted stick struck off its sweet spot or on it, scored every step.

    Description
        A uniform stick (``mass``, ``length``) is pinned at one end to a frictionless pivot on the ice. ``reset``
        strikes it: a 0.1 ms force pulse of impulse ``impulse`` along +x at ``strike`` from the pivot. With zero
        action it then swings at omega = -Pi d / I_O about the pivot (THEORY.md P4), the pivot having given the
        reaction impulse J = Pi (M d_cm d / I_O - 1) (zero at d = 2L/3).

    Observation Space
        See `BlowEnv`: position (x, y) of the *pinned end* (the body origin) (m), heading of the stick (rad),
        velocity of the pinned end (m/s) and omega_z (rad/s), shape (6,), float64.

    Action Space
        Box(-0.1, 0.1, (3,)), float64: extra force (f_x, f_y) (N) at the stick's CM and torque tau_z (N m), world
        frame, through ``xfrc_applied``; clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|heading - omega t'| / pi - |r_pin| / L``, t' = t - tau/2: the negative deviation of the swing
        from the closed form, plus the pin's drift in stick lengths.
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        At rest along +y from the pivot, then struck during ``reset``.

    Episode End
        Truncated after a one-radian swing; terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (sweet-spot, centre, end, near-pivot), ``params`` (mass, length, impulse, strike), ``profile``,
        ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 0.2 ms), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = PivotedStick
    body = "stick"

    observables = ("heading", "pin_drift")

    def _theory(self, t: np.ndarray) -> np.ndarray:
        tp = np.asarray(t) - 0.5 * self.prediction["_tau"]
        return np.stack([self.prediction["angular-velocity"] * tp, np.zeros_like(tp)], axis=1)

    def _measure(self, obs: np.ndarray) -> list[float]:
        x, y, heading = obs.tolist()[:3]
        return [heading, math.hypot(x, y)]

    def _deviation(self, measured: list[float], predicted: list[float]) -> float:
        (heading, drift), (heading_theory, _) = measured, predicted
        return abs(wrap_angle(heading - heading_theory)) / math.pi + drift / self._length
