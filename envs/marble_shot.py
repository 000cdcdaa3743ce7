"""The meter stick on ice with two marbles (docs/theory.md P6): struck so that its centre of percussion is at marble A,
it leaves A alone and knocks C away; struck elsewhere, it pushes A. The MuJoCo side, and its gymnasium env.

Theory: docs/theory.md P6 (Harter, Unit 6 Ch. 2: the "Zamboni ice shot"; the figure is lost, this is docs/theory.md's
reconstruction, rule 2: a marble at the stick's end is undisturbed if the stick is struck at h = l/3 from the
centre, l = L/2), P1-P2 for the stick's velocity field after the blow, and P5 for each marble's collision with
the moving stick (`rigidbench.analytic.percussion.stick_hits_ball`).
Model: ``models/marble_shot.xml``: a free stick along y, marbles A at y = -L/2 and C at y = +L/2 in front of its
+x face, each ``gap`` (1 mm) away; the blow is a 5 us force pulse (`rigidbench.pulse`) along +x at ``offset``
on C's side; the marbles are real bodies hit through elastic, frictionless contacts (`rigidbench.contact`).

The prediction follows the events in order: the blow (P1), then the marble whose stick point arrives first (the
faster one; with equal gaps, C), then the other with the stick's velocities after the first collision. A marble
whose stick point does not approach it (at or beyond the centre of percussion) is not hit.

What this shows about P6: the blow itself leaves A's end at rest (the ``stick-speed-at-a`` check), but C's recoil
impulse J (at s = +l) sets A's end (s = -l) moving forward at -J (1/M - l^2 / I) = 2J/M for the uniform stick
(I = M l^2 / 3), and A is then pushed after all: with 5 g marbles on a 250 g stick, A leaves at ~1.1 m/s while C
flies off at 14.8 m/s. "A undisturbed" holds for the blow, or for marbles much lighter than the stick.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import contact, pulse
from rigidbench.analytic import percussion
from rigidbench.contract import MAX_ACCELERATION, Case, Check, Derived, Scenario, Trajectory
from rigidbench.envs.planar import BlowEnv, body_state, free_body_motion, require_strike_on_stick, similar_settings
from rigidbench.params import Bound, Numeric, Param, Range, RodLength, ScaledBodyMass, SitePosition, positive

_C_HIT = (
    "C is hit ~0.1 ms after the blow, when the stick has turned by ~1e-3 rad: face tilt and contact-point "
    "shift O(theta^2), ~w theta / L (w = 2 mm half-thickness); contact switching between RK4 steps ~1e-5 at 200 "
    "steps per contact (measured <= 3e-6)"
)
_A_HIT = (
    "A is hit after C (by C's recoil alone at the centre of percussion, ~1.7 ms after the blow): by then the "
    "stick has turned by theta_A ~ 0.014 rad and its end approaches A faster than the unturned closed form "
    "says by ~V theta_A^2 / 2, ~5e-4 relative (converged in dt and k); ~1e-5 in the near-centre case (theta_A "
    "~ 2e-3)"
)
CHECKS = (
    Check(
        "stick-speed-at-a",
        "m/s",
        1e-6,
        "abs",
        "the stick point at A's end right after the 5 us pulse, V - omega s_A from the measured V and omega: the "
        "pulse turns the stick by <= |omega| tau / 2 ~ 2e-5 rad, torque error ~ (omega tau)^2 ~ 1e-9. 1e-6 m/s at the "
        "default shot (V = Pi / M = 4 m/s), in units of V elsewhere (the settings follow T = L / V)",
        "P2: v(s) = (Pi/M)(1 + s h / rho^2), zero at s = -p; P6 rule 2: p = l at h = l/3",
    ),
    Check(
        "marble-a-speed",
        "m/s",
        1e-3,
        "rel",
        _A_HIT,
        "P6 + P5: A is not pushed by the blow at the centre of percussion, but C's recoil impulse J sets A's end "
        "moving at 2J/M (uniform stick); A then leaves at (1 + e) M_eff v_A / (m + M_eff)",
    ),
    Check(
        "marble-c-speed",
        "m/s",
        5e-5,
        "rel",
        _C_HIT,
        "P6 + P5: C is hit by the stick's end at v_C = V - omega s_C: (1 + e) M_eff v_C / (m + M_eff)",
    ),
)
_ALL = tuple(c.name for c in CHECKS)

# ---- settings that follow the parameters (issue 13) ----------------------------------------------------------
#
# The shot has one length, the stick's L, one speed, V = Pi / M, and so one time scale T = L / V (0.25 s for the
# model file's 250 g meter stick struck with 1 N s). The model's geometry (marble radius 8 mm, gap 1 mm, the stick's
# half-thickness 2 mm), its marbles' mass (5 g = M / 50: marbles much lighter than the stick, as in P6) and its
# settings (contact stiffness 1e9 1/s^2, RK4 at 0.5 us, a 5 us blow) are kept in units of L, M and T, so every shot
# is the default one to scale and keeps its accuracy; only MuJoCo's absolute limits bound the impulse.
DEFAULT_LENGTH = 1.0
DEFAULT_MASS = 0.25
DEFAULT_SPEED = 4.0  # Pi / M at the defaults (m/s)
DEFAULT_TIME_SCALE = DEFAULT_LENGTH / DEFAULT_SPEED
MARBLE_RADIUS = 0.008  # in units of L
MARBLE_GAP = 0.001
STICK_HALF_WIDTH = 0.002
MARBLE_MASS = 0.02  # in units of M
MODEL_STIFFNESS = 1e9
MODEL_TIMESTEP = 5e-7
PULSE_STEPS = 10
SOLVER_TOLERANCE = 1e-8  # MuJoCo's default, the model file's
# Largest accelerations of the default shot: the blow's, V / tau = 8e5 m/s^2 and omega / tau = 1.6e6 rad/s^2 (the
# marbles' contacts ~2.3e5 m/s^2). They scale as V^2 / L and V^2 / L^2; the rounded step can halve tau.
BLOW_ACCELERATION = 8e5
BLOW_ANGULAR_ACCELERATION = 1.6e6
# How far beyond the centre of percussion (in units of L/6) case cop-at-a's closed form holds (its regime): the shot is
# self-similar (geometry, masses and settings in units of L, M and T), so the bound is one number of offset / L.
COP_AT_A_REACH = 1.05
# The nearest to the centre (in units of L) that a blow leaves the two marbles' impacts apart: the closed form (P6 +
# P5) takes them one after the other, and a blow near the centre moves both ends alike, so they come Delta t =
# (gap / V) (1 / (1 - 6 h/L) - 1 / (1 + 6 h/L)) apart, less than one contact time t_c = pi / sqrt(k) below h ~ 0.032 L
# (t_c = 4e-4 T, gap = 1e-3 L: the shot is self-similar). Measured (defaults): A's speed 5.3e-3, 1.3e-3, 2.6e-4 off at
# h = 0.026, 0.030, 0.032 L (overlapping impacts); 8.8e-7 .. 4.2e-6 from 0.034 L on.
IMPACTS_APART = 0.035


def _speeds(p: Mapping[str, Any]) -> Range:
    """The dependent range of V = Pi / M (m/s) for a stick of length L: the blow's accelerations (x 2 for the step's
    rounding) below MAX_ACCELERATION, and a step of at most 0.5 s (V >= 1e-6 L / s)."""
    ratio = p["length"] / DEFAULT_LENGTH
    high = DEFAULT_SPEED * min(
        math.sqrt(MAX_ACCELERATION / (2 * BLOW_ACCELERATION) * ratio),
        math.sqrt(MAX_ACCELERATION / (2 * BLOW_ANGULAR_ACCELERATION)) * ratio,
    )
    return Range(1e-6 * p["length"], high)


def _impulses(p: Mapping[str, Any]) -> Range:
    speeds = _speeds(p)
    return Range(p["mass"] * speeds.low, min(1e3, p["mass"] * speeds.high))


def marble_settings(params: Mapping[str, Any]) -> dict[str, Derived]:
    """The reference settings of a stick of mass M and length L struck with impulse Pi (`DEFAULT_*` at the model's)."""
    length, mass = params["length"], params["mass"]
    speed = params["impulse"] / mass
    scale = (length / speed) / DEFAULT_TIME_SCALE
    accel = (speed / DEFAULT_SPEED) ** 2 / (length / DEFAULT_LENGTH)
    why = f"T = L / (Pi / M) = {length / speed:.6g} s, {scale:.6g} times the default shot's"
    return {
        "geometry_scale": Derived(
            length,
            f"marble radius {MARBLE_RADIUS:g} L, gap {MARBLE_GAP:g} L, stick half-thickness {STICK_HALF_WIDTH:g} L, "
            f"L = {length:.6g} m (the model file's 8 mm, 1 mm and 2 mm at L = 1 m)",
        ),
        "marble_mass": Derived(
            MARBLE_MASS * mass,
            f"m = M / {1 / MARBLE_MASS:g} = {MARBLE_MASS * mass:.6g} kg (the model file's 5 g marbles on a 250 g "
            "stick: marbles much lighter than the stick, as P6 has them)",
        ),
        **similar_settings(
            scale,
            why,
            stiffness=MODEL_STIFFNESS,
            timestep=MODEL_TIMESTEP,
            pulse_steps=PULSE_STEPS,
            pulse_default="5 us",
        ),
        "solver_tolerance": Derived(
            SOLVER_TOLERANCE * min(1.0, accel),
            f"{SOLVER_TOLERANCE:g} x min(1, (V / V_0)^2 / (L / L_0)) (accelerations scale as V^2 / L; MuJoCo's solver "
            "stops when its scaled gradient, an acceleration, is below its tolerance: see pivoted-stick)",
        ),
    }


class MarbleShot(Scenario):
    """The meter stick on ice between marbles A (one end) and C (the other): struck at offset L/6 toward C, its
    centre of percussion sits at A and A stays put while C flies off (docs/theory.md P6)."""

    slug = "marble-shot"
    title = "Meter stick on ice with marbles: struck so the centre of percussion is at A, A stays, C flies"
    env_id = "rigidbench/MarbleShot-v0"
    params = (
        Param("mass", "kg", "mass M of the stick", Range(1e-6, 1e3), ScaledBodyMass("stick")),
        Param(
            "length",
            "m",
            "full length L of the uniform stick; I = M L^2 / 12; the marbles sit at its ends",
            Range(1e-3, 100.0),
            RodLength("stick", "stick"),
        ),
        Param(
            "impulse",
            "N s",
            "impulse Pi of the blow, along +x (toward the marbles)",
            positive(1e3),
            Numeric("impulse"),
            within=Bound(
                f"Pi / M in [1e-6 L, min({DEFAULT_SPEED * math.sqrt(MAX_ACCELERATION / (2 * BLOW_ACCELERATION)):.4g} "
                f"sqrt(L), {DEFAULT_SPEED * math.sqrt(MAX_ACCELERATION / (2 * BLOW_ANGULAR_ACCELERATION)):.4g} L)] "
                "(m/s, L in m): the blow's accelerations, V^2 / (2e-5 L) and 2 V^2 / (2e-5 L^2) with the pulse at "
                "2e-5 L / V, stay below 1e9 (MuJoCo: mjMAXVAL = 1e10 is a divergence) at twice the rounded step; the "
                "reference step, 2e-6 L / V, stays below 2 s",
                _impulses,
                ("mass", "length"),
            ),
        ),
        Param(
            "offset",
            "m",
            "distance h from the centre to the strike point, toward C's end, in (0, L/2]",
            positive(50.0),
            SitePosition("strike", 1),
            within=Bound("(0, L/2]: on the stick", lambda p: Range(0.0, p["length"] / 2, low_open=True), ("length",)),
        ),
    )
    cases = (
        Case(
            "cop-at-a",
            "struck at h = L/6 (= l/3): the centre of percussion is at A's end, A is not pushed, C is",
            {"offset": lambda p: p["length"] / 6},
            _ALL,
            ranges={
                "offset": Bound(
                    "[0.035 L, 1.05 L/6]: impacts apart, up to just beyond the centre of percussion",
                    lambda p: Range(IMPACTS_APART * p["length"], COP_AT_A_REACH * p["length"] / 6),
                    ("length",),
                )
            },
            regime="A is reached by C's recoil: struck beyond L/6 the end at A first moves away, and the recoil "
            "brings it back ever later, after the stick has turned further than the closed form's unturned stick "
            "allows (A's speed 4.2e-4 off at 1.02 L/6, 3.0e-4 at 1.06, 2.1e-3 at 1.08: measured, tolerance 1e-3), "
            "or never (A stays at rest from ~1.17 L/6); nearer the centre than 0.035 L the two impacts overlap in time "
            "and the closed form, one impact after the other, does not hold (A's speed 1.3e-3 off at 0.030 L)",
        ),
        Case(
            "near-centre",
            "struck at h = L/12: A's end moves forward at V/2 and pushes A too",
            {"offset": lambda p: p["length"] / 12},
            _ALL,
            ranges={
                "offset": Bound(
                    "[0.035 L, L/6): between impacts that overlap and the centre of percussion, where A's end moves "
                    "toward A",
                    lambda p: Range(IMPACTS_APART * p["length"], p["length"] / 6, high_open=True),
                    ("length",),
                )
            },
            regime="A is pushed: the end at A moves toward it only for a blow nearer the centre than L/6 (P2); "
            "beyond, A stays at rest and its speed, 0, has no relative error. Nearer the centre than 0.035 L both ends "
            "move alike and the two impacts overlap in time (Delta t < pi / sqrt(k)): the closed form takes them one "
            "after the other (A's speed 5.3e-3 off at 0.026 L, 1.3e-3 at 0.030 L; 8.8e-7 from 0.034 L on, measured)",
        ),
    )
    checks = CHECKS

    def validate(self, params: Mapping[str, Any]) -> None:
        require_strike_on_stick(params["offset"], params["length"])

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        return marble_settings(params)

    def apply_derived(self, spec: mujoco.MjSpec, name: str, value: float) -> None:
        if name == "geometry_scale":
            spec.geom("stick").size = [STICK_HALF_WIDTH * value, value / 2, STICK_HALF_WIDTH * value]
            spec.numeric("gap").data = [MARBLE_GAP * value]
            for marble in ("marble_a", "marble_c"):
                spec.geom(marble).size = [MARBLE_RADIUS * value, 0.0, 0.0]
        elif name == "marble_mass":
            for marble in ("marble_a", "marble_c"):
                body = spec.body(marble)
                radius = float(spec.geom(marble).size[0])
                body.mass = value
                # 2/5 m r^2 (the spin never enters: frictionless contacts), at least 1e-14 (MuJoCo's floor, 1e-15)
                body.inertia = [max(0.4 * value * radius**2, 1e-14)] * 3
        elif name == "contact_stiffness":
            for geom in ("stick", "marble_a", "marble_c"):
                spec.geom(geom).solref = [-value, 0.0]
        else:
            super().apply_derived(spec, name, value)

    def check_model(self, model: mujoco.MjModel) -> None:
        solref = model.geom("stick").solref
        if solref[0] < 0:
            contact.elastic_contact(timestep=float(model.opt.timestep), stiffness=float(-solref[0]))

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        size = model.geom("stick").size
        gap = float(model.numeric("gap").data[0])
        data.qvel[:] = 0.0
        for body, y in (("stick", 0.0), ("marble_a", -size[1]), ("marble_c", size[1])):
            x = 0.0 if body == "stick" else size[0] + model.geom(body).size[0] + gap
            adr = model.jnt_qposadr[model.body(body).jntadr[0]]
            data.qpos[adr : adr + 7] = [x, y, 0, 1, 0, 0, 0]

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        stick = model.body("stick")
        mass, inertia = float(stick.mass[0]), float(stick.inertia[2])
        impulse = float(model.numeric("impulse").data[0])
        offset = float(model.site("strike").pos[1])
        blow = percussion.struck_stick(mass, inertia, impulse, offset)
        s = {name: float(body_state(model, data, name).com_W[0, 1]) for name in ("marble_a", "marble_c")}
        v, w = blow.com_velocity, blow.angular_velocity
        order = sorted(s, key=lambda name: -(v - w * s[name]))  # the faster-approached marble is hit first
        speeds = {}
        for name in order:
            hit = percussion.stick_hits_ball(mass, inertia, v, w, s[name], float(model.body(name).mass[0]))
            speeds[name], v, w = hit.ball_velocity, hit.com_velocity, hit.angular_velocity
        gap = float(model.numeric("gap").data[0])
        fastest = max(blow.point_velocity(s["marble_a"]), blow.point_velocity(s["marble_c"]))
        return {
            # 1e-6 m/s at the default shot's V = 4 m/s: in units of V elsewhere (the settings follow T = L / V)
            "_tolerance": {
                "stick-speed-at-a": self.check("stick-speed-at-a").tolerance * abs(blow.com_velocity) / DEFAULT_SPEED
            },
            "_theory": blow,
            "_tau": pulse.duration(model),
            "_t_first_hit": pulse.duration(model) / 2 + gap / fastest,
            # 3 ms at the default shot, in units of T = L / V (both collisions are over within ~2 ms there)
            "_t_min": 3e-3 * (2 * float(model.geom("stick").size[1]) / abs(blow.com_velocity)) / DEFAULT_TIME_SCALE,
            "_s_a": s["marble_a"],
            "stick-speed-at-a": float(blow.point_velocity(s["marble_a"])),
            "marble-a-speed": speeds["marble_a"],
            "marble-c-speed": speeds["marble_c"],
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        # both collisions are over within ~2 ms at the defaults; run until the stick has turned by 0.05 rad
        return prediction["_tau"] + max(0.05 / abs(prediction["_theory"].angular_velocity), prediction["_t_min"])

    def control(self, model: mujoco.MjModel, timestep: float, nstep: int) -> np.ndarray:
        return pulse.control(model, nstep, "strike", float(model.numeric("impulse").data[0]))

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        stick = free_body_motion(model, traj, "stick")
        n = pulse.steps(model)
        at_a = stick.point_velocity_W(np.array([0.0, prediction["_s_a"], 0.0]))[n]
        return {
            "stick-speed-at-a": float(at_a[0]),
            "marble-a-speed": float(np.linalg.norm(free_body_motion(model, traj, "marble_a").v_W[-1])),
            "marble-c-speed": float(np.linalg.norm(free_body_motion(model, traj, "marble_c").v_W[-1])),
        }


class MarbleShotEnv(BlowEnv):
    """``rigidbench/MarbleShot-v0``: the meter stick and two marbles on ice, scored against theory every step.

    Description
        A uniform stick (``mass``, ``length``) lies on frictionless ice along world y with marble A 1 mm in front
        of one end and marble C 1 mm in front of the other. ``reset`` strikes it toward the marbles (a 5 us
        pulse of impulse ``impulse`` at ``offset`` from its centre, on C's side). With zero action, struck at L/6
        (docs/theory.md P6), its centre of percussion is at A's end: A stays put while C is knocked away.

    Observation Space
        See `BlowEnv`: the *stick's* CM position (x, y) (m), heading (rad), CM velocity (v_x, v_y) (m/s) and
        omega_z (rad/s), shape (6,), float64.

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = 0.1`` times it is an extra force (f_x, f_y) (N)
        at the stick's CM and torque tau_z (N m), world frame, through ``xfrc_applied``; clipped.
        Zero action = the textbook problem.

    Rewards
        ``reward = -(|x - V t'| + |y|) / L - |heading - omega t'| / pi`` until the first marble is hit (t' from
        the pulse's centroid; as `StruckStickEnv`), 0 afterwards (no closed form for the stick's motion through
        the collisions; ``info["predicted"]`` then holds NaN): the negative deviation of the stick's pose
        from P1.
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        Stick at rest at the origin, marbles at rest 1 mm in front of its ends, then struck during ``reset``.

    Episode End
        Truncated when the stick has turned by 0.05 rad (at least 3 ms); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (cop-at-a, near-centre), ``params`` (mass, length, impulse, offset), ``profile``, ``integrator``,
        ``timestep``, ``frame_skip`` (default 10, i.e. 10 us), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = MarbleShot
    body = "stick"

    observables = ("x", "y", "heading")

    def theory(self, t: np.ndarray) -> np.ndarray:
        pose = self._stick_pose_theory(t)
        pose[np.asarray(t) >= self.prediction["_t_first_hit"]] = np.nan  # not scored after the first collision
        return pose

    def measured(self, obs: np.ndarray) -> list[float]:
        return obs.tolist()[:3]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        return self._pose_deviation(measured, predicted)

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        return obs[:, :3]

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        return self._pose_deviations(measured, predicted)
