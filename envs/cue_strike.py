"""A billiard ball struck by a cue at a height above its centre, skidding to rolling: the MuJoCo side, and its env.

Theory: THEORY.md B1 (Harter, Unit 6 Ch. 2 "practical poolhall application": h = I/(MR) = 2R/5, no skid) and B2
(skid to roll under Coulomb friction), implemented in `rigidbench.analytic.percussion`.
Model: ``models/cue_strike.xml``: a free solid ball on a plane with Coulomb friction ``mu``; the cue is a
rectangular force pulse (`rigidbench.pulse`) of impulse M ``speed`` along world +x, on the world line at
``height`` above the centre; measured from the end of the pulse on.

Conventions: motion along +x, omega_y the spin about +y, slip u = v_x - R omega_y of the contact point (rolling is
u = 0). Time is counted from the start of the pulse: with Coulomb friction sliding from the first instant, the
motion after a rectangular pulse of any length is exactly that after an impulse at t = 0 (u(t) = u0 - 7/2 mu g t).

What MuJoCo does with the sliding ball (the contact findings, THEORY.md B2 "Measure")
    MuJoCo solves each contact's normal and friction rows as one soft constraint, so it may trade normal
    residual for friction: while the ball slides the friction demand exceeds the cone, the normal force rises
    above M g and the ball is kicked off the table at each touchdown. It hops along, in contact for only ~1-2%
    of the sliding steps at the reference settings (lift <= 5e-4 R) and 20-40% with MuJoCo's default contact
    (lift 0.2 R for a 2 m/s centre shot, 1.1 R for a 4.5 m/s backspin draw). Friction acts only at
    touchdowns, but their impulses average to mu M g, so the skid obeys B2 on average. MuJoCo's default contact
    (0.02 s time constant) also makes friction viscous near zero slip: the slip decays exponentially instead of
    reaching zero, so rolling arrives late (+5.8 % for the centre shot) and a residual slip remains. The
    `lift-height`, `time-to-roll` and `residual-slip` checks measure these; README.md has the numbers.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import contact, frames, pulse, signals
from rigidbench.analytic import percussion
from rigidbench.envs.planar import BlowEnv, PlanarMotion, dot, free_body_motion
from rigidbench.params import (
    ActuatorGear,
    Bound,
    GeomFriction,
    Gravity,
    Numeric,
    Param,
    Range,
    ScaledBodyMass,
    SphereRadius,
)
from rigidbench.scenario import Case, Check, Domain, Scenario
from rigidbench.simulate import Trajectory

# Rolling is declared when the slip has fallen to this fraction of its initial value; under B2 that happens at
# (1 - ROLLED) t_r, which is what is predicted.
ROLLED = 1e-3

_HOPS = (
    "MuJoCo's soft cone kicks the sliding ball off the table at each touchdown (lift <= 5e-4 R at reference): "
    "friction acts in impulses at touchdowns, every ~10-50 us, that average to mu M g"
)
CHECKS = (
    Check(
        "initial-slip",
        "m/s",
        5e-5,
        "abs",
        "intercept at t = 0 of a straight line fitted to the slip over the sliding phase (for the no-skid blow: "
        "the largest |slip|): " + _HOPS + "; the staircase of touchdown impulses scatters the fit by ~1e-5 m/s",
        "B1: u0 = v0 (1 - h M R / I) = v0 (1 - 5h / (2R)) ([H] poolhall application)",
    ),
    Check(
        "time-to-roll",
        "s",
        1e-3,
        "abs",
        f"time for |slip| to fall to {ROLLED:g} |u0|, cubic-interpolated. MuJoCo's friction is a velocity-level "
        "constraint: below u_c = (7/2) mu g / b the friction is no longer saturated and the slip decays "
        "exponentially at rate b = 2 sqrt(k) = 6.3e3 1/s instead of reaching zero, which delays the crossing by "
        f"(ln(u_c / ({ROLLED:g} |u0|)) - 1) / b <= 0.7 ms for |u0| >= 0.02 m/s and mu <= 0.5; " + _HOPS,
        f"B2: u(t) = u0 - (7/2) mu g t, zero at t_r = 2 |u0| / (7 mu g); predicted at (1 - {ROLLED:g}) t_r",
    ),
    Check(
        "final-speed",
        "m/s",
        1e-5,
        "rel",
        "CoM speed at the end of the run: angular momentum about the contact point is conserved whatever the "
        "contact does, up to the table friction's vertical lever arm (the lift, <= 5e-4 R, times the hop duty)",
        "B2: v_f = v0 - (2/7) u0 = (5/7) v0 (1 + h/R)",
    ),
    Check(
        "skid-distance",
        "m",
        1e-6,
        "rel",
        "CoM travel by the predicted rolling time t_r: " + _HOPS + ", which shifts the position by far less than "
        "the speed (measured <= 2e-7)",
        "B2: s = v0 t_r - 1/2 sgn(u0) mu g t_r^2, less v0 tau / 2 (a rectangular pulse of length tau "
        "accelerates the ball gradually; exact)",
    ),
    Check(
        "energy-lost",
        "1",
        1e-6,
        "abs",
        "fraction of the ideal blow's kinetic energy (1/2 M v0^2 + 1/2 I omega0^2) missing at the end: final "
        "speed to 1e-5 (above); the vertical bouncing energy of the hops is included (<= M g 5e-4 R)",
        "B2: lost fraction 1 - (1 + gamma) v_f^2 / (v0^2 + gamma R^2 omega0^2); 2/7 for a centre strike",
    ),
    Check(
        "residual-slip",
        "m/s",
        1e-5,
        "abs",
        "largest |slip| from 1.2 t_r to the end: Coulomb friction holds u = 0 once rolling; MuJoCo's friction is "
        "a stiff velocity-level constraint at reference (creep ~ g / b ~ 1e-6 m/s for b = 2 sqrt(k) = 6.3e3 1/s)",
        "B2: rolling without slip after t_r (no rolling resistance)",
    ),
    Check(
        "lift-height",
        "1",
        1e-3,
        "abs",
        "largest height of the ball above its resting height, over R: B2 assumes it stays on the table; "
        + _HOPS
        + "; 1e-3 R keeps the friction's lever arm R within 1e-3",
        "B2 validity: point contact on a horizontal table (no vertical motion)",
    ),
)
_SKID = tuple(c.name for c in CHECKS)
_NO_SKID = ("initial-slip", "final-speed", "energy-lost", "residual-slip", "lift-height")


# The skid checks need a sliding phase the run can see after the pulse: B2's roll time at least SKID_PULSES pulses.
SKID_PULSES = 5
# Longest skid a run follows (s): the reference run lasts 1.5 roll times at 10 us steps, <= 1e6 steps.
MAX_ROLL_TIME = 6.0
# The cue's (and the cushion's) pulse duration in the model files (s).
MODEL_PULSE = 1e-3


def skid_outside(slip: float, mu: float, g: float, tau: float, what: str) -> str | None:
    """The skid domain's test on the slip u0 (m/s) a blow leaves: None when B2's roll time 2 |u0| / (7 mu g) is at
    least SKID_PULSES pulses of `tau` (s), else a phrase naming the parameters (`what`) and the numbers. (The roll
    time alone, not `percussion.skid_to_roll`, whose skid distance overflows at mu ~ 1e-200.)"""
    decel = mu * g * (1.0 + 1.0 / percussion.SOLID_SPHERE)
    t_r = abs(slip) / decel if decel > 0 else math.inf
    if SKID_PULSES * tau <= t_r <= MAX_ROLL_TIME:
        return None
    return f"{what} (slip u0 = {slip:.3g} m/s, roll time {t_r:.3g} s against a {tau:g} s pulse)"


SKID_DOMAIN_TEXT = (
    f"B2's roll time 2 |u0| / (7 mu g) >= {SKID_PULSES} pulses and <= {MAX_ROLL_TIME:g} s (a run of <= 1e6 steps, "
    "and 1.5 roll times long): the skid checks (initial slip, time to roll, skid "
    "distance) measure a sliding phase after the blow; a blow near the no-skid height leaves a slip that rolls out "
    "within the pulse (there the no-skid case's checks apply)"
)


def _no_skid(p: Mapping[str, Any]) -> float:
    return percussion.no_skid_height(p["radius"])


def settle(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Put the ball at rest at the origin at the resting penetration of its soft contact (which depends on the
    profile's solref/solimp): let it settle for 30 time constants of the contact (solref[0] s, or 1/sqrt(k) in
    the direct format), then reset the time."""
    radius = float(model.geom("ball").size[0])
    data.qpos[:] = [0, 0, radius, 1, 0, 0, 0]
    data.qvel[:] = 0.0
    solref = model.geom("ball").solref
    time_constant = solref[0] if solref[0] > 0 else 1.0 / np.sqrt(-solref[0])
    mujoco.mj_step(model, data, nstep=max(1, round(30 * time_constant / model.opt.timestep)))
    data.qpos[:] = [0, 0, data.qpos[2], 1, 0, 0, 0]
    data.qvel[:] = 0.0
    data.time = 0.0


BALL_RADIUS = Param(
    "radius", "m", "radius R of the solid ball (I = 2/5 M R^2)", Range(1e-3, 1.0), SphereRadius("ball", "ball")
)
BALL_MASS = Param("mass", "kg", "mass M of the ball", Range(1e-6, 100.0), ScaledBodyMass("ball"))
# Coulomb friction from nearly frictionless (a skid of 2 m/s lasts ~60 s on Earth at mu = 1e-3) to rubber on rubber.
FRICTION = Param(
    "mu",
    "1",
    "Coulomb friction coefficient between ball and cloth (sliding = static)",
    Range(1e-3, 2.0),
    GeomFriction(("ball", "table")),
)
# From the Moon's surface gravity / 100 to 10 g.
TABLE_GRAVITY = Param("g", "m/s^2", "gravitational acceleration (along -z)", Range(1e-2, 100.0), Gravity())


def skid_speeds(slip_per_speed: tuple[float, float]) -> Bound:
    """The speed's dependent range for blows whose slip is `slip_per_speed` = (smallest, largest) |u0| / v of the
    cases: the skid lasts at least SKID_PULSES pulses and at most MAX_ROLL_TIME (B2: t_r = |u0| / (3.5 mu g))."""
    low, high = slip_per_speed
    return Bound(
        f"[{3.5 * SKID_PULSES * MODEL_PULSE / low:.3g} mu g, {3.5 * MAX_ROLL_TIME / high:.3g} mu g] (s^2 mu g, "
        f"m/s): the skid to rolling lasts >= {SKID_PULSES} pulses (measurable after the blow) and <= "
        f"{MAX_ROLL_TIME:g} s (a run of <= 1e6 steps)",
        lambda p: Range(
            max(1e-3, 3.5 * SKID_PULSES * MODEL_PULSE * p["mu"] * p["g"] / low),
            min(20.0, 3.5 * MAX_ROLL_TIME * p["mu"] * p["g"] / high),
        ),
        ("mu", "g"),
    )


class CueStrike(Scenario):
    """A billiard ball struck by a horizontal cue at ``height`` above its centre: the slip the blow leaves
    (B1), the skid under Coulomb friction to rolling (B2), and how MuJoCo's contact does it."""

    slug = "cue-strike"
    title = "Billiard ball struck by a cue: no-skid height 2R/5, skid to roll under Coulomb friction"
    env_id = "rigidbench/CueStrike-v0"
    params = (
        BALL_RADIUS,
        BALL_MASS,
        FRICTION,
        Param(
            "speed",
            "m/s",
            "CoM speed v0 right after the strike (impulse M v0)",
            Range(1e-3, 20.0),
            Numeric("speed"),
            # |u0| / v0 = |1 - 5h / (2R)|: 0.5 (topspin) .. 2.25 (backspin) over the skidding cases.
            within=skid_speeds((0.5, 2.25)),
        ),
        Param(
            "height",
            "m",
            "height h of the cue's line above the ball's centre (negative: below), |h| < R",
            Range(-1.0, 1.0, low_open=True, high_open=True),
            ActuatorGear("cue", 4),
            within=Bound(
                "(-R, R): the cue hits the ball",
                lambda p: Range(-p["radius"], p["radius"], low_open=True, high_open=True),
                ("radius",),
            ),
        ),
        TABLE_GRAVITY,
    )
    cases = (
        Case("centre", "struck through the centre (h = 0): skids, loses 2/7 of its energy", {"height": 0.0}, _SKID),
        Case("no-skid", "struck at h = 2R/5 (H = 7/10 of the diameter): rolls at once", {"height": _no_skid}, _NO_SKID),
        Case(
            "topspin",
            "struck at h = 3R/5, above the no-skid height: overspin, friction speeds it up",
            {"height": lambda p: 0.6 * p["radius"]},
            _SKID,
        ),
        Case(
            "backspin",
            "struck at h = -R/2 (draw shot): backspin, a long skid",
            {"height": lambda p: -0.5 * p["radius"]},
            _SKID,
        ),
    )
    checks = CHECKS
    domains = (
        Domain(
            "skid",
            "B2 (skid to roll)",
            SKID_DOMAIN_TEXT,
            lambda p: skid_outside(
                p["speed"] * (1 - p["height"] / (percussion.SOLID_SPHERE * p["radius"])),
                p["mu"],
                p["g"],
                MODEL_PULSE,
                f"height = {p['height']:g} m (R = {p['radius']:g} m), mu = {p['mu']:g}, speed = {p['speed']:g} m/s",
            ),
            cases=("centre", "topspin", "backspin"),
        ),
    )

    def check_model(self, model: mujoco.MjModel) -> None:
        solref = model.geom("ball").solref
        if solref[0] < 0:  # direct format (-k, -b): MuJoCo's safety clamp is off; refuse an unresolvable contact
            contact.elastic_contact(timestep=float(model.opt.timestep), stiffness=float(-solref[0]))

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        settle(model, data)

    def after_blow(self, model: mujoco.MjModel, data: mujoco.MjData) -> tuple[percussion.SkidToRoll, float]:
        """B2's motion from the instant of an ideal blow on, and the CoM velocity (m/s) just before the blow."""
        p = self.read_params(model)
        gamma = float(model.body("ball").inertia[1] / (p["mass"] * p["radius"] ** 2))
        return percussion.cue_strike(p["radius"], p["mu"], p["g"], p["speed"], p["height"], gamma), 0.0

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        theory, v_before = self.after_blow(model, data)
        tau = pulse.duration(model)
        # A rectangular pulse changes the velocity linearly over tau, so the ball lags the impulsive motion by
        # dv tau / 2 (exact); the slip and velocities after the pulse are those of an impulse at t = 0, since
        # Coulomb friction slides with the final slip's sign from the first instant.
        x_offset = -0.5 * (theory.speed - v_before) * tau
        return {
            "_theory": theory,
            "_rest_height": float(data.qpos[2]),
            "_tau": tau,
            "_x_offset": x_offset,
            "initial-slip": theory.slip,
            "time-to-roll": (1 - ROLLED) * theory.time_to_roll,
            "final-speed": theory.final_speed,
            "skid-distance": theory.skid_distance + x_offset,
            "energy-lost": theory.energy_lost,
            "residual-slip": 0.0,
            "lift-height": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        theory = prediction["_theory"]
        return prediction["_tau"] + max(1.5 * theory.time_to_roll, 0.05)

    def control(self, model: mujoco.MjModel, timestep: float, nstep: int) -> np.ndarray:
        return pulse.control(model, nstep, "cue", float(model.body("ball").mass[0] * model.numeric("speed").data[0]))

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        theory: percussion.SkidToRoll = prediction["_theory"]
        m = free_body_motion(model, traj, "ball")
        t, tau = m.time, prediction["_tau"]
        slip = self.slip(model, m)
        after = t >= tau
        u0 = theory.slip
        out = {
            "final-speed": float(m.v_W[-1, 0]),
            "lift-height": float((m.com_W[:, 2].max() - prediction["_rest_height"]) / theory.radius),
            "energy-lost": 1.0 - self._energy(model, m)[-1] / self._ideal_energy(model, theory),
        }
        if abs(u0) <= 1e-9 * abs(theory.speed):  # a blow at the no-skid height: no sliding phase at all
            out["initial-slip"] = float(np.abs(slip[after]).max())
            out["residual-slip"] = float(np.abs(slip[after]).max())
            return out
        rolled = signals.crossings(t[after], np.abs(slip[after]) - ROLLED * abs(u0), direction=-1)
        t_roll = float(rolled[0]) if len(rolled) else np.nan
        sliding = after & (t <= 0.8 * t_roll)
        out["initial-slip"] = float(np.polyfit(t[sliding], slip[sliding], 1)[1]) if sliding.sum() > 2 else np.nan
        out["time-to-roll"] = t_roll
        out["skid-distance"] = float(signals.interpolate(t, m.com_W[:, 0], np.array([theory.time_to_roll]))[0])
        late = t >= 1.2 * theory.time_to_roll
        out["residual-slip"] = float(np.abs(slip[late]).max()) if late.any() else np.nan
        return out

    @staticmethod
    def slip(model: mujoco.MjModel, m: PlanarMotion) -> np.ndarray:
        """Slip u = v_x - R omega_y (m/s) of the ball's contact point, along x."""
        return m.v_W[:, 0] - float(model.geom("ball").size[0]) * m.omega_W[:, 1]

    @staticmethod
    def _energy(model: mujoco.MjModel, m: PlanarMotion) -> np.ndarray:
        """Kinetic energy (J): translation plus rotation (isotropic inertia)."""
        body = model.body("ball")
        return 0.5 * body.mass[0] * np.sum(m.v_W**2, axis=1) + 0.5 * np.sum(body.inertia * m.qvel[:, 3:6] ** 2, axis=1)

    @staticmethod
    def _ideal_energy(model: mujoco.MjModel, theory: percussion.SkidToRoll) -> float:
        body = model.body("ball")
        return 0.5 * body.mass[0] * theory.speed**2 + 0.5 * body.inertia[1] * theory.spin**2


class CueStrikeEnv(BlowEnv):
    """``rigidbench/CueStrike-v0``: the cue ball skidding to rolling, scored against theory every step.

    Description
        A solid ball (radius ``radius``, mass ``mass``) rests on a cloth with Coulomb friction ``mu``. ``reset``
        strikes it with the cue: a 1 ms force pulse along +x on the line ``height`` above its centre, of impulse
        M ``speed``. With zero action it then skids and rolls as THEORY.md B1-B2 say: slip u0 = v0 (1 - 5h/2R),
        decreasing at (7/2) mu g until it rolls at v_f = (5/7) v0 (1 + h/R).

    Observation Space
        float64, shape (6,):

        ==== ================================================ ======= ==============================
        idx  quantity                                         unit    MuJoCo source
        ==== ================================================ ======= ==============================
        0    x, distance of the centre along the shot         m       free joint qpos[0]
        1    height of the centre above its resting height    m       free joint qpos[2]
        2    v_x, CoM velocity along the shot                 m/s     free joint qvel[0]
        3    v_z, vertical CoM velocity                       m/s     free joint qvel[2]
        4    omega_y, spin about +y (world; topspin > 0)      rad/s   qvel[3:6] rotated to world
        5    slip u = v_x - R omega_y of the contact point    m/s     derived
        ==== ================================================ ======= ==============================

    Action Space
        Box(-0.1, 0.1, (2,)), float64: extra horizontal force f_x (N) at the centre and torque tau_y (N m), world
        frame, through ``xfrc_applied``; clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|x - x_theory(t)| / max(s, R)``: the negative deviation of the ball's distance from B2's
        skid-then-roll path (less v0 tau / 2 for the pulse), relative to the skid distance s (the radius R for a
        ball that does not skid). ``info["measured"]`` and ``info["predicted"]`` hold x (m), v_x (m/s) and slip
        (m/s). The hops (see the module docstring) are visible in observation 1.
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        At rest on the cloth at its resting penetration, then struck during ``reset``: the first observation is
        just after the 1 ms pulse.

    Episode End
        Truncated after the scenario's duration (pulse + 1.5 t_r, at least 50 ms); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (centre, no-skid, topspin, backspin), ``params`` (radius, mass, mu, speed, height, g),
        ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 0.1 ms), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = CueStrike
    body = "ball"

    def _observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(6,), dtype=np.float64)

    def _action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_force, self.max_force, shape=(2,), dtype=np.float64)

    def _load(self, case: str, params) -> None:
        super()._load(case, params)
        # Read every step: cached per episode (a MuJoCo attribute or a mapping look-up costs ~0.1 us each).
        self._radius = float(self.model.geom("ball").size[0])
        self._rest_height = self.prediction["_rest_height"]
        theory = self.prediction["_theory"]
        self._x_scale = max(abs(theory.skid_distance), theory.radius)  # the length scale of the problem

    def _observation(self) -> np.ndarray:
        # PlanarMotion.omega_W and CueStrike.slip for one state, in Python floats (as BlowEnv._observation).
        (x, _, z, q_w, q_x, q_y, q_z), (v_x, _, v_z, w_x, w_y, w_z) = self._free_joint()
        omega_y = dot(frames.matrix_rows(q_w, q_x, q_y, q_z)[1], (w_x, w_y, w_z))
        return np.array([x, z - self._rest_height, v_x, v_z, omega_y, v_x - self._radius * omega_y])

    def _wrench(self, action: list[float]) -> tuple[float, ...]:
        f_x, tau_y = action
        return f_x, 0.0, 0.0, 0.0, tau_y, 0.0

    observables = ("x", "v_x", "slip")

    def _theory(self, t: np.ndarray) -> np.ndarray:
        x, v, u = self.prediction["_theory"].state(t)
        return np.stack([x + self.prediction["_x_offset"], v, u], axis=1)

    def _measure(self, obs: np.ndarray) -> list[float]:
        x, _, v_x, _, _, slip = obs.tolist()
        return [x, v_x, slip]

    def _deviation(self, measured: list[float], predicted: list[float]) -> float:
        return abs(measured[0] - predicted[0]) / self._x_scale
