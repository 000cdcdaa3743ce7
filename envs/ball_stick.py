"""A ball striking a resting free stick elastically (the stick-and-ball percussion shot): MuJoCo side and env.

Theory: docs/theory.md P5 (effective mass M_eff = (1/M + h^2/I)^-1, impulse Pi = (1 + e) m u M_eff / (m + M_eff);
the ball stops when m = M_eff), then P1 for the stick, implemented in `rigidbench.analytic.percussion`.
Model: ``models/ball_stick.xml``: a free stick along body y and a free ball approaching along +x at
``offset`` from the stick's centre, no gravity (frictionless ice). The blow is a real collision: an elastic
contact (`rigidbench.contact`: direct solref (-k, 0), restitution 1) lasting pi / sqrt(k) = 0.31 ms. Measured
after the contact has ended (velocities are constant from then on).

Conventions: docs/theory.md section 6; the ball hits the stick's -x face, pushing it along +x; omega_z = -Pi h / I.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import contact
from rigidbench.analytic import percussion
from rigidbench.contract import MAX_ACCELERATION, Case, Check, Derived, Domain, Scenario, Trajectory, round_step
from rigidbench.envs.hard_spheres import CONTACT_ROUNDOFF_RULE, ContactFloor
from rigidbench.envs.planar import BlowEnv, PlanarMotion, body_state, free_body_motion, has_nan
from rigidbench.params import Bound, Numeric, Param, Range, RodLength, ScaledBodyMass

_COMPLIANCE = (
    "the contact lasts t_c = pi / sqrt(k) = 0.31 ms, during which the stick turns by theta ~ |omega| t_c <~ 2e-3 "
    "rad: the struck face tilts and the contact point moves along it, errors ~3.5 (omega t_c)^2 (measured, "
    "converged in dt: 3e-6 for the light ball, 1.3e-5 for the heavy one; the theory's impact is instantaneous); "
    "plus the contact switching on and off between steps, <= 1e-5 at 314 steps per contact (RK4)"
)
_CONSERVED = (
    "MuJoCo's elastic contact is a spring in constraint space, delta'' = -k delta, so its force is k delta "
    "times the contact's effective mass, which changes as the stick turns under the ball (above): not exactly "
    "a potential force; measured 2e-6 to 4e-6, converged in dt"
)
CHECKS = (
    Check(
        "ball-velocity",
        "m/s",
        5e-5,
        "abs",
        _COMPLIANCE + " (times u: 2.5e-5 u, in m/s; 5e-5 at the default 2 m/s)",
        "P5: u' = u - Pi / m",
    ),
    Check("stick-velocity", "m/s", 5e-5, "rel", _COMPLIANCE, "P5 + P1: V = Pi / M"),
    Check(
        "stick-angular-velocity",
        "rad/s",
        5e-5,
        "abs",
        _COMPLIANCE + "; 5e-5 |omega| + 1e-12 u / L (the state's round-off), absolute so that a blow through the "
        "centre (omega = 0) is scored too",
        "P5 + P1: omega = -Pi h / I",
    ),
    Check(
        "momentum",
        "1",
        1e-12,
        "abs",
        "internal contact forces only: exact to roundoff; relative to m u",
        "P5: m u' + M V = m u (x component)",
    ),
    Check("energy", "1", 2e-5, "abs", _CONSERVED + "; relative to the initial energy", "P5, e = 1: energy conserved"),
)
_ALL = tuple(c.name for c in CHECKS)

# The model file's contact (k = 1e8 1/s^2: t_c = pi / sqrt(k) = 0.314 ms, 314 steps of 1 us) and approach (2 mm at
# 2 m/s: 1 ms, 3.18 contact times). The reference contact keeps the stick's turn during it, omega t_c, at most that
# of the fastest default case (heavy-ball, |omega| = 6 rad/s): t_c = min(0.314 ms, OMEGA_TC / |omega|).
CONTACT_TIME = np.pi / 1e4
CONTACT_STEPS = 314
APPROACH_CONTACTS = 1e-3 / CONTACT_TIME
OMEGA_TC = 6.0 * CONTACT_TIME
# The ball's radius and the stick's half-width per metre of stick (the model file's 1 cm and 2 mm at L = 1 m).
BALL_RADIUS = 0.01
STICK_HALF_WIDTH = 0.002
# Largest penetration of the ball into the stick, u t_c / pi, as a share of the stick's half-width.
PENETRATION = 0.1
# The contact's peak deceleration u sqrt(k) = u pi / t_c and the stick's angular acceleration ~ omega pi / (2 t_c)
# stay below settings.MAX_ACCELERATION (mjMAXVAL / 10).
# MuJoCo's default solver tolerance, kept down to the default's contact deceleration u / t_c (2 m/s over 0.314 ms),
# scaled below it.
SOLVER_TOLERANCE = 1e-8
DECELERATION_DEFAULT = 2.0 / CONTACT_TIME


def _contact_time(p: Mapping[str, Any]) -> float:
    """The reference contact time t_c (s): the model file's 0.314 ms, shorter where the stick turns faster than in
    the fastest default case (omega t_c <= OMEGA_TC) or the ball would sink more than a tenth of the stick's
    half-width into it (u t_c / pi <= PENETRATION w; 0.2 mm of 2 mm at the defaults)."""
    omega = abs(_omega(p))
    by_depth = np.pi * PENETRATION * STICK_HALF_WIDTH * p["length"] / p["ball_speed"]
    return float(min(CONTACT_TIME, OMEGA_TC / omega if omega > 0 else np.inf, by_depth))


def _too_fast(p: Mapping[str, Any]) -> str | None:
    """The acceleration domain's test: None inside, else a phrase naming the parameters."""
    t_c = _contact_time(p)
    decel = p["ball_speed"] * np.pi / t_c
    spin = abs(_omega(p)) * np.pi / (2 * t_c)
    if max(decel, spin) <= MAX_ACCELERATION:
        return None
    return (
        f"ball_speed = {p['ball_speed']:g} m/s, mass = {p['mass']:g} kg, ball_mass = {p['ball_mass']:g} kg, length = "
        f"{p['length']:g} m, offset = {p['offset']:g} m (contact time {t_c:.3g} s: deceleration {decel:.3g} m/s^2, "
        f"the stick's angular acceleration {spin:.3g} rad/s^2)"
    )


def _omega(p: Mapping[str, Any]) -> float:
    """The stick's angular velocity after the impact (rad/s) from the requested parameters (P5 + P1)."""
    inertia = percussion.uniform_rod_inertia(p["mass"], p["length"])
    theory = percussion.ball_on_stick(p["mass"], inertia, p["offset"], p["ball_mass"], p["ball_speed"])
    return float(theory.stick.angular_velocity)


def _effective_mass(p: Mapping[str, Any]) -> float:
    inertia = percussion.uniform_rod_inertia(p["mass"], p["length"])
    return 1.0 / (1.0 / p["mass"] + p["offset"] ** 2 / inertia)


class BallStick(Scenario):
    """A ball hits the resting free stick elastically at ``offset`` from its centre: the velocities after the
    impact, momentum and energy, and the ball that stops when its mass equals the stick's effective mass (P5)."""

    slug = "ball-stick"
    title = "Ball striking a free stick elastically: effective mass, the ball that stops"
    env_id = "rigidbench/BallStick-v0"
    params = (
        Param("mass", "kg", "mass M of the stick", Range(1e-6, 1e3), ScaledBodyMass("stick")),
        Param(
            "length",
            "m",
            "full length L of the uniform stick; I = M L^2 / 12 about its centre",
            Range(1e-3, 100.0),
            RodLength("stick", "stick"),
        ),
        # Down to 1e-7 kg: the ball-stops case's ball is the stick's effective mass, >= M / 4.
        Param("ball_mass", "kg", "mass m of the ball", Range(1e-7, 1e3), ScaledBodyMass("ball")),
        Param(
            "ball_speed",
            "m/s",
            "speed u of the ball along +x before impact (it starts 3.18 contact times before it: reference settings)",
            Range(1e-6, 100.0),
            Numeric("ball_speed"),
            within=Bound(
                "u <= sqrt(1e9 m/s^2 x 0.1 w), w = 0.002 L the stick's half-width: a contact short enough to keep the "
                "ball within 0.1 w of the face decelerates it by u^2 / (0.1 w), below MuJoCo's divergence limit "
                "(mjMAXVAL = 1e10) by a decade",
                lambda p: Range(
                    1e-6, min(100.0, np.sqrt(MAX_ACCELERATION * PENETRATION * STICK_HALF_WIDTH * p["length"]))
                ),
                ("length",),
            ),
        ),
        Param(
            "offset",
            "m",
            "distance h along the stick from its centre to the ball's line of approach, in [0, L/2)",
            Range(0.0, 50.0),
            Numeric("offset"),
            within=Bound(
                "[0, L/2): the ball hits the stick",
                lambda p: Range(0.0, p["length"] / 2, high_open=True),
                ("length",),
            ),
        ),
    )
    cases = (
        Case("light-ball", "a 100 g ball at L/4 on a 250 g stick: the ball bounces forward", {"ball_mass": 0.1}, _ALL),
        Case(
            "ball-stops",
            "ball mass = the stick's effective mass at the impact point: the ball stops dead",
            {"ball_mass": _effective_mass},
            _ALL,
        ),
        Case("heavy-ball", "a 1 kg ball: it carries on after the impact", {"ball_mass": 1.0}, _ALL),
    )
    checks = CHECKS
    domains = (
        Domain(
            "mujoco-max-acceleration",
            "P5 (MuJoCo: mjMAXVAL = 1e10)",
            "the contact's peak deceleration u pi / t_c and the stick's angular acceleration |omega| pi / (2 t_c) <= "
            "1e9 (m/s^2, rad/s^2), t_c the reference contact time: MuJoCo treats an acceleration above mjMAXVAL = "
            "1e10 as a divergence and resets the state (an engine limit, not the theory's)",
            _too_fast,
        ),
    )

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        u = params["ball_speed"]
        omega = abs(_omega(params))
        t_c = _contact_time(params)
        gap = u * t_c * APPROACH_CONTACTS
        decel = u / t_c
        length = params["length"]
        return {
            "geometry_scale": Derived(
                length,
                f"ball radius {BALL_RADIUS:g} L and stick half-width {STICK_HALF_WIDTH:g} L, L = {length:.6g} m (the "
                "model file's 1 cm and 2 mm at L = 1 m): the point ball of P5 is a sphere whose contact point moves "
                "along the tilting face by ~ R omega t_c, a fixed share of the lever arm h at any size",
            ),
            "contact_stiffness": Derived(
                (np.pi / t_c) ** 2,
                f"k = (pi / t_c)^2, t_c = min({CONTACT_TIME:.4g}, {OMEGA_TC:.3g} / |omega|, pi {PENETRATION:g} w / u)"
                f" = {t_c:.4g} s (the stick turns by omega t_c <= {OMEGA_TC:.3g} rad during the contact, as in the "
                f"fastest default case, and the ball sinks at most {PENETRATION:g} of the stick's half-width w = "
                f"{STICK_HALF_WIDTH:g} L into it); |omega| = Pi h / I = {omega:.6g} rad/s",
            ),
            "timestep": Derived(
                round_step(t_c / CONTACT_STEPS),
                f"dt = t_c / {CONTACT_STEPS} rounded down to one digit (>= {CONTACT_STEPS} steps per contact: the "
                "contact's switching errors <= 1e-5, measured)",
            ),
            "approach_gap": Derived(
                gap,
                f"gap = u t_c x {APPROACH_CONTACTS:.4g} = {gap:.6g} m (the ball reaches the stick "
                f"{APPROACH_CONTACTS:.3g} contact times into the run, 1 ms at the defaults)",
            ),
            "solver_tolerance": Derived(
                SOLVER_TOLERANCE * min(1.0, decel / DECELERATION_DEFAULT),
                f"{SOLVER_TOLERANCE:g} x min(1, a / {DECELERATION_DEFAULT:.4g} m/s^2), a = u / t_c = {decel:.3g} m/s^2 "
                "(MuJoCo's solver stops when its scaled gradient, an acceleration, is below its tolerance: see "
                "pivoted-stick)",
            ),
        }

    def apply_derived(self, spec: mujoco.MjSpec, name: str, value: float) -> None:
        if name == "geometry_scale":
            spec.geom("ball").size = [BALL_RADIUS * value, 0.0, 0.0]
            spec.geom("stick").size = [STICK_HALF_WIDTH * value, value / 2, STICK_HALF_WIDTH * value]
        elif name == "approach_gap":
            spec.numeric("gap").data = [value]
        elif name == "contact_stiffness":
            for geom in ("ball", "stick"):
                spec.geom(geom).solref = [-value, 0.0]
        else:
            super().apply_derived(spec, name, value)

    def check_model(self, model: mujoco.MjModel) -> None:
        solref = model.geom("ball").solref
        if solref[0] < 0:  # direct format: MuJoCo's safety clamp is off; refuse an unresolvable contact
            contact.elastic_contact(timestep=float(model.opt.timestep), stiffness=float(-solref[0]))

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        half_width = float(model.geom("stick").size[0])
        radius = float(model.geom("ball").size[0])
        gap = float(model.numeric("gap").data[0])
        stick, ball = model.body("stick").jntadr[0], model.body("ball").jntadr[0]
        qs, qb = model.jnt_qposadr[stick], model.jnt_qposadr[ball]
        vb = model.jnt_dofadr[ball]
        data.qpos[qs : qs + 7] = [0, 0, 0, 1, 0, 0, 0]
        data.qpos[qb : qb + 7] = [-(half_width + radius + gap), params["offset"], 0, 1, 0, 0, 0]
        data.qvel[:] = 0.0
        data.qvel[vb] = params["ball_speed"]

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        stick, ball = body_state(model, data, "stick"), body_state(model, data, "ball")
        mass, m = float(model.body("stick").mass[0]), float(model.body("ball").mass[0])
        u = float(ball.v_W[0, 0])
        offset = float(ball.com_W[0, 1] - stick.com_W[0, 1])
        theory = percussion.ball_on_stick(mass, float(model.body("stick").inertia[2]), offset, m, u)
        gap = float(stick.com_W[0, 0] - model.geom("stick").size[0] - model.geom("ball").size[0] - ball.com_W[0, 0])
        solref = model.geom("ball").solref
        t_contact = np.pi / np.sqrt(-solref[0]) if solref[0] < 0 else 10 * solref[0]
        length = 2 * float(model.geom("stick").size[1])
        omega = theory.stick.angular_velocity
        # A float32 engine's floors (`Scenario._roundoff_check`): the elastic contact's, as for the hard spheres
        # (`hard_spheres.CONTACT_ROUNDOFF_RULE`): the penetration (deepest u t_c / pi) is computed from positions up
        # to a from the origin, and the ball's steady approach advances u dt a step on a grid of spacing eps |x|;
        # each check read from the impulse carries it relative to its size.
        a = float(np.abs(ball.com_W[0]).max())
        steady = (abs(u) * float(model.opt.timestep), abs(float(ball.com_W[0, 0])), abs(theory.impulse / (m * u)))
        floors = {
            "ball-velocity": abs(u),
            "stick-velocity": 1.0,
            "stick-angular-velocity": abs(omega),
            "energy": 1.0,
        }
        depth = abs(u) * t_contact / np.pi
        return {
            "_roundoff_eps": {name: ContactFloor(a, depth, steady, scale) for name, scale in floors.items()},
            "_roundoff_eps_rule": CONTACT_ROUNDOFF_RULE,
            "_tolerance": {
                "stick-angular-velocity": 5e-5 * abs(omega) + 1e-12 * abs(u) / length,
                "ball-velocity": 2.5e-5 * abs(u),
            },
            "_theory": theory,
            "_t_hit": gap / u,
            "_t_contact": float(t_contact),
            "ball-velocity": theory.ball_velocity,
            "stick-velocity": theory.stick.com_velocity,
            "stick-angular-velocity": theory.stick.angular_velocity,
            "momentum": 1.0,
            "energy": 1.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return prediction["_t_hit"] + 3 * prediction["_t_contact"]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        stick, ball = free_body_motion(model, traj, "stick"), free_body_motion(model, traj, "ball")
        mass, m = float(model.body("stick").mass[0]), float(model.body("ball").mass[0])
        inertia = model.body("stick").inertia
        u = ball.v_W[0, 0]

        def energy(b: PlanarMotion, mass_: float, inertia_: np.ndarray) -> np.ndarray:
            return 0.5 * mass_ * np.sum(b.v_W**2, axis=1) + 0.5 * np.sum(inertia_ * b.qvel[:, 3:6] ** 2, axis=1)

        e = energy(stick, mass, inertia) + energy(ball, m, model.body("ball").inertia)
        return {
            "ball-velocity": float(ball.v_W[-1, 0]),
            "stick-velocity": float(stick.v_W[-1, 0]),
            "stick-angular-velocity": float(stick.omega_W[-1, 2]),
            "momentum": float((m * ball.v_W[-1, 0] + mass * stick.v_W[-1, 0]) / (m * u)),
            "energy": float(e[-1] / e[0]),
        }


class BallStickEnv(BlowEnv):
    """``rigidbench/BallStick-v0``: a ball strikes the free stick elastically, scored against theory every step.

    Description
        A uniform stick (``mass``, ``length``) rests on frictionless ice along world y; a ball (``ball_mass``)
        slides at ``ball_speed`` along +x toward it, on the line ``offset`` from the stick's centre, and hits it
        elastically 1 ms into the episode (a real collision, elastic contact of 0.31 ms). With zero action the
        stick then moves as docs/theory.md P5 + P1 say: V = Pi / M, omega = -Pi h / I.

    Observation Space
        See `BlowEnv`: the *stick's* CM position (x, y) (m), heading (rad), CM velocity (v_x, v_y) (m/s) and
        omega_z (rad/s), shape (6,), float64.

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = 0.1`` times it is an extra force (f_x, f_y) (N)
        at the stick's CM and torque tau_z (N m), world frame, through ``xfrc_applied``; clipped.
        Zero action = the textbook problem.

    Rewards
        ``reward = -|v_x - V_theory(t)| / V - |omega_z - omega_theory(t)| / |omega|`` (0 before the impact,
        after it the P5 values; during the 0.31 ms contact the stick's velocity is in between and the deviation
        is not scored, and ``info["predicted"]`` holds NaN): the negative deviation of the stick's velocities from
        the closed form.
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        Stick at rest at the origin along y; ball 2 mm from its face moving at ``ball_speed``.

    Episode End
        Truncated after the scenario's duration (impact + 3 contact times); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (light-ball, ball-stops, heavy-ball), ``params`` (mass, length, ball_mass, ball_speed, offset),
        ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 10 us), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = BallStick
    body = "stick"

    observables = ("v_x", "omega_z")

    def theory(self, t: np.ndarray) -> np.ndarray:
        stick = self.prediction["_theory"].stick
        t = np.asarray(t)
        hit = self.prediction["_t_hit"]
        after = (t >= hit).astype(float)
        out = np.stack([stick.com_velocity * after, stick.angular_velocity * after], axis=1)
        out[(t > hit) & (t < hit + self.prediction["_t_contact"])] = np.nan  # inside the contact: not scored
        return out

    def load(self, case: str, params) -> None:
        super().load(case, params)
        stick = self.prediction["_theory"].stick  # the deviation's scales, read every step: cached per episode
        self._v_scale, self._omega_scale = stick.com_velocity, abs(stick.angular_velocity)

    def measured(self, obs: np.ndarray) -> list[float]:
        _, _, _, v_x, _, omega_z = obs.tolist()
        return [v_x, omega_z]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        if has_nan(predicted):
            return 0.0
        (v_x, omega_z), (v_x_theory, omega_z_theory) = measured, predicted
        return abs(v_x - v_x_theory) / self._v_scale + abs(omega_z - omega_z_theory) / self._omega_scale

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        return obs[:, [3, 5]]

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        (v_x, omega_z), (v_x_theory, omega_z_theory) = measured.T, predicted.T
        deviation = np.abs(v_x - v_x_theory) / self._v_scale + np.abs(omega_z - omega_z_theory) / self._omega_scale
        return np.where(np.isnan(predicted).any(axis=1), 0.0, deviation)
