"""A billiard ball struck by a cue at a height above its centre, skidding to rolling: the MuJoCo side, and its env.

Theory: docs/theory.md B1 (Harter, Unit 6 Ch. 2 "practical poolhall application": h = I/(MR) = 2R/5, no skid) and B2
(skid to roll under Coulomb friction), implemented in `rigidbench.analytic.percussion`.
Model: ``models/cue_strike.xml``: a free solid ball on a plane with Coulomb friction ``mu``; the cue is a
rectangular force pulse (`rigidbench.pulse`) of impulse M ``speed`` along world +x, on the world line at
``height`` above the centre; measured from the end of the pulse on.

Conventions: motion along +x, omega_y the spin about +y, slip u = v_x - R omega_y of the contact point (rolling is
u = 0). Time is counted from the start of the pulse: with Coulomb friction sliding from the first instant, the
motion after a rectangular pulse of any length is exactly that after an impulse at t = 0 (u(t) = u0 - 7/2 mu g t).

What MuJoCo does with the sliding ball (the contact findings, docs/theory.md B2 "Measure")
    MuJoCo solves each contact's normal and friction rows as one soft constraint, so it may trade normal
    residual for friction: while the ball slides the friction demand exceeds the cone, the normal force rises
    above M g and the ball is kicked off the table at each touchdown. It hops along, in contact for only ~1-2%
    of the sliding steps at the reference settings (lift <= 5e-4 R) and 20-40% with MuJoCo's default contact
    (lift 0.2 R for a 2 m/s centre shot, 1.1 R for a 4.5 m/s backspin draw). Friction acts only at
    touchdowns, and always mu times the table's normal impulse, which vertical momentum makes M (g t + v_z -
    v_z(0)): the checks read the slip, the roll time and the skid on that friction clock (the hops' impulse put
    back), and `lift-height` reports the hop. MuJoCo's default contact
    (0.02 s time constant) also makes friction viscous near zero slip: the slip decays exponentially instead of
    reaching zero, so rolling arrives late (+5.8 % for the centre shot) and a residual slip remains. The
    `lift-height`, `time-to-roll` and `residual-slip` checks measure these; docs/findings.md has the numbers.

Settings that follow the parameters (issue 13): the cloth's stiffness, the step and the pulse keep the default
ball's values in units of T = sqrt(R / g) (`billiard_settings`); where a threshold of PGS's friction QCQP would act
(a heavy ball at low mu, or mu M g ~ 1e-5 N) the solver is Newton's (docs/findings.md).
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
from rigidbench.contract import Case, Check, Derived, Domain, Scenario, Trajectory
from rigidbench.envs.planar import BlowEnv, PlanarMotion, dot, free_body_motion, similar_settings, similar_step
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
        "mean over the sliding phase of the slip with the hops' friction impulse put back, u + sgn(u0) (1 + 1/gamma) "
        "mu (g t + v_z - v_z(0)): under Coulomb's law the slip loses (1 + 1/gamma) mu per unit of the table's normal "
        "impulse, which vertical momentum makes M (g t + v_z - v_z(0)) whatever " + _HOPS + "; measured <= 1e-6 m/s. "
        "5e-5 m/s at the default ball, in units of sqrt(g R) elsewhere (the settings follow T = sqrt(R / g))",
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
        f"(ln(u_c / ({ROLLED:g} |u0|)) - 1) / b <= 0.7 ms for |u0| >= 0.02 m/s and mu <= 0.5. The crossing is read on "
        "the friction clock t + (v_z - v_z(0)) / g (see initial-slip), which puts back the hops' normal impulse. "
        "1 ms at the default ball, in units of T = sqrt(R / g) elsewhere",
        f"B2: u(t) = u0 - (7/2) mu g t, zero at t_r = 2 |u0| / (7 mu g); predicted at (1 - {ROLLED:g}) t_r",
    ),
    Check(
        "final-speed",
        "m/s",
        1e-5,
        "rel",
        "CoM speed at the end of the run: angular momentum about the contact point is conserved whatever the "
        "contact does, up to the table friction's vertical lever arm (the lift, <= 5e-4 R, times the hop duty); "
        "relative to max(|v_f|, 0.1 v0), v0 the blow's speed (a cushion's: the speed the ball came in with): the "
        "error comes with the friction impulse from v0 to v_f, and a blow near the bottom, or a plastic cushion at "
        "the no-skid height, leaves v_f -> 0",
        "B2: v_f = v0 - (2/7) u0 = (5/7) v0 (1 + h/R)",
    ),
    Check(
        "skid-distance",
        "m",
        1e-6,
        "rel",
        "CoM travel by the predicted rolling time t_r (the hops' share, mu (z - z_rest), put back as for the "
        "initial slip; measured <= 2e-7 at the defaults), plus MuJoCo's viscous friction near zero slip (velocity-"
        "level friction, damping b: below u_c = (1 + 1/gamma) mu g / b the slip decays over 1/b and the CoM overshoots "
        "B2's path by ~0.13 mu g / b^2): + 2 (mu g / b)^2 / (v0 |u0|) relative",
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
        "slip-deceleration",
        "m/s^2",
        3.1e-7,
        "rel",
        "least-squares slope of the slip over the sliding phase (from the pulse's end to 0.8 t_r), with the hops' "
        "normal impulse put back (u + sgn(u0) (1 + 1/gamma) mu (v_z - v_z(0)), see initial-slip): Coulomb friction "
        "on the cone's surface is exact in MuJoCo's elliptic cone, so what remains is RK4's resolution of the "
        "touchdowns (a bias that falls as dt^1.7 and grows with the hop: measured -3.8e-8, -1.2e-7, -4.4e-7 at dt/2, "
        "dt, 2 dt for the centre shot; -7e-8 .. -1.3e-7 for V = |u0| / sqrt(g R) = 1 .. 3 over mu = 0.01 .. 2, "
        "-2.3e-7 for the backspin's V = 8.5; up to 1.2e-7 at V -> 0 for a heavy ball at mu ~ 1e-3 under Newton, "
        "census seeds 1-2); tolerance 2e-7 + 3e-8 V per run (3.1e-7 at the centre shot's V = 3.78, listed)",
        "B2: du/dt = -(1 + 1/gamma) mu g sgn(u0) = -(7/2) mu g while sliding",
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
_TOLERANCE = {c.name: c.tolerance for c in CHECKS}
_NO_SKID = ("initial-slip", "final-speed", "energy-lost", "residual-slip", "lift-height")


# ---- settings that follow the parameters (issue 13) ----------------------------------------------------------
#
# The ball's motion has one length R and one acceleration g, so one time scale T = sqrt(R / g) and one speed
# U = sqrt(g R). The model files' settings are those of the default ball (R = 28.575 mm, g = 9.81 m/s^2): cloth
# stiffness k = 1e7 1/s^2 (critically damped), RK4 at 10 us, a 1 ms blow. The reference settings keep them in units
# of T at any R and g (k T^2, dt / T, tau / T fixed), so MuJoCo solves the same dimensionless contact problem
# everywhere, and what is left to vary is mu, the case, and the slip in units of U, V = |u0| / U (bounded below).
DEFAULT_RADIUS = 0.028575
DEFAULT_G = 9.81
MODEL_STIFFNESS = 1e7
MODEL_TIMESTEP = 1e-5
# The cue's (and the cushion's) pulse duration in the model files (s), and in steps.
MODEL_PULSE = 1e-3
PULSE_STEPS = 100
# The skid checks need a sliding phase the run can see after the pulse: B2's roll time at least SKID_PULSES pulses.
SKID_PULSES = 5
# Longest skid a run follows, in units of T (6 s at the default ball): the run lasts 1.5 roll times, <= 1e6 steps.
MAX_ROLL_TIME = 6.0
# MuJoCo's elliptic-cone PGS solves each contact's friction as a small QCQP (mju_QCQP2, engine_util_solve.c) with two
# absolute thresholds, found by the census (docs/findings.md): (1) "check SPD, with 1e-10 threshold": it zeroes the
# friction when the determinant of the friction block of A + R, scaled by mu^2, is below 1e-10; for a ball on a
# plane that block is ((1 + 1/gamma) / M) mu^2 I, so friction vanishes when (1 + 1/gamma) mu^2 / M < 1e-5 kg^-1 (a
# heavy ball at low mu); (2) "initial solution inside constraint set" when |f_t / mu|^2 - f_n^2 < 1e-10 N^2: any
# friction force below 1e-5 mu N passes unprojected, so a ball whose Coulomb limit mu M g is below ~1e-5 N is held
# by more than mu M g as its slip falls (it sticks early). Within QCQP_MARGIN of either, the reference settings use
# Newton's solver, which has neither test.
QCQP_DET = 1e-5  # kg^-1
QCQP_FORCE = 1e-5  # N
QCQP_MARGIN = 10.0
# MuJoCo's soft cone lifts the sliding ball (module docstring): the touchdowns kick it up at a vertical speed of a
# few 1e-3 |u0|, a hop that grows like V^2, V = |u0| / sqrt(g R). Measured at the reference settings (issue 13,
# docs/findings.md) over mu = 0.003 .. 2 and the three skidding cases: at most 9.3e-4 R at V = 10 (mu = 0.5), 5.2e-4 R
# at mu = 0.2, 7.8e-5 R at mu = 0.05; Newton's (used only for mu <= 0.053, `uses_newton`) 5.6e-4 R at V = 8. The slip
# is bounded to V <= MAX_SLIP_NUMBER, where the worst hop is ~7.5e-4 R, inside the lift-height tolerance (1e-3 R).
MAX_SLIP_NUMBER = 9.0
# Newton's solver lifts it more: 1.3e-4 R at V = 2 and 1.9e-3 R at V = 4 for mu = 0.5, so V <= 2.5 keeps it below
# ~7e-4 R; at mu <= 0.05 (every heavy ball it is used for) 5.6e-4 R at V = 8 and 1.1e-3 R at V = 12, so V <= 8 there.
MAX_SLIP_NUMBER_NEWTON = 2.5
MAX_SLIP_NUMBER_NEWTON_LOW_MU = 8.0
NEWTON_LOW_MU = 0.05


def time_scale(radius: float, g: float) -> float:
    """T = sqrt(R / g) (s): the time a ball of radius R takes to fall ~R/2 under g."""
    return math.sqrt(radius / g)


DEFAULT_TIME_SCALE = time_scale(DEFAULT_RADIUS, DEFAULT_G)


def uses_newton(mass: float, mu: float, g: float, gamma: float = percussion.SOLID_SPHERE) -> bool:
    """Whether a threshold of PGS's QCQP would act on this ball's friction (within QCQP_MARGIN): then the reference
    solver is Newton."""
    return (1 + 1 / gamma) * mu**2 / mass < QCQP_MARGIN * QCQP_DET or mu * mass * g < QCQP_MARGIN * QCQP_FORCE


def max_slip_number(mass: float, mu: float, g: float) -> float:
    """Largest V = |u0| / sqrt(g R) a reference run keeps within the lift tolerance (MAX_SLIP_NUMBER, or
    MAX_SLIP_NUMBER_NEWTON where the reference solver is Newton's) and the step budget (t_r = |u0| / (3.5 mu g) <=
    MAX_ROLL_TIME T / T_0)."""
    hop = MAX_SLIP_NUMBER
    if uses_newton(mass, mu, g):
        hop = MAX_SLIP_NUMBER_NEWTON_LOW_MU if mu <= NEWTON_LOW_MU else MAX_SLIP_NUMBER_NEWTON
    return min(hop, 3.5 * mu * MAX_ROLL_TIME / DEFAULT_TIME_SCALE)


def billiard_settings(params: Mapping[str, Any]) -> dict[str, Derived]:
    """The reference settings of a ball of radius R on a cloth under g (`DEFAULT_*` at the model's defaults)."""
    radius, g = params["radius"], params["g"]
    scale = time_scale(radius, g) / DEFAULT_TIME_SCALE
    why = f"T = sqrt(R / g) = {time_scale(radius, g):.6g} s, {scale:.6g} times the default ball's; critically damped"
    derived = similar_settings(
        scale,
        why,
        stiffness=MODEL_STIFFNESS,
        timestep=MODEL_TIMESTEP,
        pulse_steps=PULSE_STEPS,
        pulse_default=f"{MODEL_PULSE:g} s",
    )
    mass, mu = params["mass"], params["mu"]
    if uses_newton(mass, mu, g):
        derived["solver"] = Derived(
            float(mujoco.mjtSolver.mjSOL_NEWTON),
            f"Newton: (1 + 1/gamma) mu^2 / M = {3.5 * mu**2 / mass:.3g} kg^-1 (PGS's QCQP zeroes friction below "
            f"{QCQP_DET:g}) or mu M g = {mu * mass * g:.3g} N (it lets friction below {QCQP_FORCE:g} mu N pass "
            f"unprojected) is within {QCQP_MARGIN:g}x of a threshold of PGS's elliptic-cone QCQP",
        )
    return derived


def apply_billiard_setting(spec: mujoco.MjSpec, name: str, value: float) -> bool:
    """Write a derived cloth setting into `spec`; False for a name that is not one."""
    if name == "contact_stiffness":
        for geom in ("ball", "table"):
            spec.geom(geom).solref = [-value, -2 * math.sqrt(value)]
    elif name == "solver":
        spec.option.solver = mujoco.mjtSolver(int(value))
    else:
        return False
    return True


# The slip deceleration's bias from RK4's resolution of the hops' touchdowns, relative: a floor and its growth with
# the slip number V = |u0| / sqrt(g R) (the slip-deceleration check's reason has the measurements).
DECELERATION_BIAS = 2e-7
DECELERATION_BIAS_PER_V = 3e-8


# MuJoCo's friction is a velocity-level soft constraint with damping b (solref): below u_c = (1 + 1/gamma) mu g / b
# it is no longer saturated and the slip decays exponentially over 1/b instead of reaching zero at t_r, so the CoM
# overshoots B2's path by ~0.13 mu g / b^2 by t_r: relative to the skid s ~ v0 t_r / 2, ~0.9 (mu g / b)^2 / (v0 u0).
# The skid-distance tolerance adds twice that (5e-8 at the default cases; up to ~3e-5 for a short skid at mu = 2).
VISCOUS_OVERSHOOT = 2.0


def friction_damping(model: mujoco.MjModel) -> float:
    """The damping b (1/s) of the ball's contact: -solref[1] in the direct format (-k, -b), else 2 zeta / T."""
    solref = model.geom("ball").solref
    return float(-solref[1]) if solref[0] < 0 else float(2 * solref[1] / solref[0])


def skid_outside(slip: float, p: Mapping[str, Any], what: str) -> str | None:
    """The skid domain's test on the slip u0 (m/s) a blow leaves: None when B2's roll time 2 |u0| / (7 mu g) is
    at least SKID_PULSES reference pulses, else a phrase naming the parameters (`what`) and the numbers. (The roll
    time alone, not `percussion.skid_to_roll`, whose skid distance overflows at mu ~ 1e-200.)"""
    mu, g = p["mu"], p["g"]
    scale = time_scale(p["radius"], g) / DEFAULT_TIME_SCALE
    tau = PULSE_STEPS * similar_step(MODEL_TIMESTEP, scale)
    decel = mu * g * (1.0 + 1.0 / percussion.SOLID_SPHERE)
    t_r = abs(slip) / decel if decel > 0 else math.inf
    if SKID_PULSES * tau <= t_r <= MAX_ROLL_TIME * scale:
        return None
    return f"{what} (slip u0 = {slip:.3g} m/s, roll time {t_r:.3g} s against a {tau:g} s pulse)"


SKID_DOMAIN_TEXT = (
    f"B2's roll time 2 |u0| / (7 mu g) >= {SKID_PULSES} pulses and <= {MAX_ROLL_TIME:g} T / T_0 (a run of <= 1e6 "
    "steps, and 1.5 roll times long): the skid checks (initial slip, time to roll, skid distance) measure a sliding "
    "phase after the blow; a blow near the no-skid height leaves a slip that rolls out within the pulse (there the "
    "no-skid case's checks apply)"
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


def skid_speed_param(doc: str, slip_per_speed: tuple[float, float]) -> Param:
    """The ball's speed (m/s) `doc`, within `skid_speeds(slip_per_speed)` (the cases' smallest and largest |u0| / v)."""
    return Param("speed", "m/s", doc, Range(1e-3, 20.0), Numeric("speed"), within=skid_speeds(slip_per_speed))


def skid_speeds(slip_per_speed: tuple[float, float]) -> Bound:
    """The speed's dependent range for blows whose slip is `slip_per_speed` = (smallest, largest) |u0| / v of the
    cases: the skid lasts at least SKID_PULSES pulses (tau = 0.0185 T) and at most MAX_ROLL_TIME T / T_0 (B2: t_r =
    |u0| / (3.5 mu g)), and the slip number V = |u0| / sqrt(g R) stays below MuJoCo's hop limit (`max_slip_number`)."""
    low, high = slip_per_speed
    pulse_share = MODEL_PULSE / DEFAULT_TIME_SCALE

    def speeds(p: Mapping[str, Any]) -> Range:
        u = math.sqrt(p["g"] * p["radius"])
        return Range(
            max(1e-3, 3.5 * SKID_PULSES * pulse_share * p["mu"] * u / low),
            min(20.0, max_slip_number(p["mass"], p["mu"], p["g"]) * u / high),
        )

    return Bound(
        f"[{3.5 * SKID_PULSES * pulse_share / low:.3g} mu, min({3.5 * MAX_ROLL_TIME / DEFAULT_TIME_SCALE / high:.4g} "
        f"mu, {MAX_SLIP_NUMBER / high:.3g} (under Newton: {MAX_SLIP_NUMBER_NEWTON_LOW_MU / high:.3g} for mu <= "
        f"{NEWTON_LOW_MU:g}, {MAX_SLIP_NUMBER_NEWTON / high:.3g} above))] x sqrt(g R) (m/s): "
        f"the skid to rolling lasts >= {SKID_PULSES} pulses "
        f"(measurable after the blow) and <= {MAX_ROLL_TIME:g} T / T_0 (T = sqrt(R / g); a run of <= 1e6 steps), and "
        f"the slip |u0| <= {MAX_SLIP_NUMBER:g} sqrt(g R) ({MAX_SLIP_NUMBER_NEWTON_LOW_MU:g} or "
        f"{MAX_SLIP_NUMBER_NEWTON:g} where the reference solver is Newton's: heavy balls at low mu, or mu M g < 1e-4 "
        "N), where MuJoCo's soft cone lifts the sliding ball by < 1e-3 R",
        speeds,
        ("radius", "mass", "mu", "g"),
    )


def _sliding_floors(theory: percussion.SkidToRoll, dt: float) -> dict[str, Any]:
    """A float32 engine's floors of the slide (`Scenario._roundoff_check`'s ``_roundoff_eps``, in units of eps): the
    friction's steady change of v and omega each step is rounded alike every step, a relative bias q of the
    deceleration (`engines.steady_change_error`: the larger of v's and omega's). t_r and the skid distance carry
    q relatively; the slip read with the friction clock q |u0| (the clock's correction is (1 + 1/gamma) mu g t,
    |u0| at t_r); the final speed q |v0 - v_f|; the energy lost q times itself, or, where larger, what the final
    speed's floor moves it by: 1 - E_f / E_0 with E_f ~ v_f^2 moves by 2 (1 - lost) dv_f / v_f (an MJX float32 census
    draw at mu = 0.0011 lost 0.0244 of its energy against 0.0307, its final speed 3.3e-3 off within its floor of
    9.7e-3: twice that relative error, where q times the energy lost allowed only 2.7e-3)."""
    from rigidbench.engines import STEADY_CHANGE_RULE, steady_change_error

    decel = theory.mu * theory.g
    if decel == 0 or theory.slip == 0:
        return {}
    spin = (theory.speed - theory.slip) / theory.radius
    q = max(
        steady_change_error(theory.speed, decel * dt),
        steady_change_error(spin, decel * dt / (theory.gamma * theory.radius)),
    )
    final = q * abs(theory.speed - theory.final_speed) / abs(theory.final_speed) if theory.final_speed else 0.0
    floors = {
        "time-to-roll": q * (1 - ROLLED) * theory.time_to_roll,
        "skid-distance": q,
        "slip-deceleration": q,
        "initial-slip": q * abs(theory.slip),
        "energy-lost": max(q * abs(theory.energy_lost), 2 * (1 - theory.energy_lost) * final),
        "final-speed": final,
    }
    rule = f"the slide's deceleration bias q = {q:.3g} eps, {STEADY_CHANGE_RULE}"
    return {"_roundoff_eps": {k: v for k, v in floors.items() if v > 0}, "_roundoff_eps_rule": rule}


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
        # |u0| / v0 = |1 - 5h / (2R)|: 0.5 (topspin) .. 2.25 (backspin) over the skidding cases.
        skid_speed_param("CoM speed v0 right after the strike (impulse M v0)", (0.5, 2.25)),
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
                p,
                f"height = {p['height']:g} m (R = {p['radius']:g} m), mu = {p['mu']:g}, speed = {p['speed']:g} m/s",
            ),
            cases=("centre", "topspin", "backspin"),
        ),
    )

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        return billiard_settings(params)

    def apply_derived(self, spec: mujoco.MjSpec, name: str, value: float) -> None:
        if not apply_billiard_setting(spec, name, value):
            super().apply_derived(spec, name, value)

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
        # The checks' bounds hold in units of the ball's own scales (the settings follow T = sqrt(R / g)): a slip in
        # units of U = sqrt(g R), a time in units of T; equal to the model file's at the default ball.
        t_scale = time_scale(theory.radius, theory.g) / DEFAULT_TIME_SCALE
        u_scale = math.sqrt(theory.g * theory.radius) / math.sqrt(DEFAULT_G * DEFAULT_RADIUS)
        return {
            # The final speed's error is relative to max(|v_f|, 0.1 v0) (`Check.floor`): the errors come with the
            # friction impulse that takes v0 to v_f, and v_f -> 0 for a blow near the bottom (h -> -R), or for a
            # rolling ball a plastic cushion stops (v0 is then the speed the ball came in with).
            "_floor": {"final-speed": 0.1 * max(abs(theory.speed), abs(v_before))},
            "_tolerance": {
                "initial-slip": _TOLERANCE["initial-slip"] * u_scale,
                "time-to-roll": _TOLERANCE["time-to-roll"] * t_scale,
                "residual-slip": _TOLERANCE["residual-slip"] * u_scale,
                "slip-deceleration": DECELERATION_BIAS
                + DECELERATION_BIAS_PER_V * abs(theory.slip) / (math.sqrt(theory.g * theory.radius)),
                "skid-distance": _TOLERANCE["skid-distance"]
                + VISCOUS_OVERSHOOT
                * (theory.mu * theory.g / friction_damping(model)) ** 2
                / abs(theory.speed * theory.slip or math.inf),
            },
            # A float32 engine's floors (`Scenario.roundoff_scale`): the slip v_x - R omega_y is a difference of two
            # speed-sized numbers, each rounded to ~eps |v0|, however small the slip itself (an MJX float32 census draw
            # with a slip of 1.1e-10 m/s at 2.8e-3 m/s never saw it cross zero: its initial slip came out NaN).
            "_roundoff_scale": {"initial-slip": abs(theory.speed), "residual-slip": abs(theory.speed)},
            # and while it slides, friction changes v and omega by a steady mu g dt and mu g dt / (gamma R) a step:
            # each change is rounded alike every step (`engines.steady_change_error`), a bias q of the deceleration
            # that each check read from the slide carries (an MJX float32 census draw at mu = 0.0023: time to roll
            # 0.66 % long, 3.4 times the random walk's floor; q = 3.2 % there).
            **_sliding_floors(theory, float(model.opt.timestep)),
            "_theory": theory,
            "_rest_height": float(data.qpos[2]),
            "_tau": tau,
            "_t_scale": t_scale,
            "_x_offset": x_offset,
            "initial-slip": theory.slip,
            "time-to-roll": (1 - ROLLED) * theory.time_to_roll,
            "final-speed": theory.final_speed,
            "skid-distance": theory.skid_distance + x_offset,
            "energy-lost": theory.energy_lost,
            "residual-slip": 0.0,
            "lift-height": 0.0,
            "slip-deceleration": (1 + 1 / theory.gamma) * theory.mu * theory.g,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        theory = prediction["_theory"]
        return prediction["_tau"] + max(1.5 * theory.time_to_roll, 0.05 * prediction["_t_scale"])

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
        # A blow at the no-skid height: no sliding phase at all, or one shorter than a step (a float32 engine's
        # rounded height leaves a slip of ~eps v0: an MJX float32 census draw's 9.9e-10 m/s would roll in 5e-8 s,
        # 1e-4 of a step, and timing that slide read 2.75e-3 m/s of friction clock off a ball already rolling).
        if abs(u0) <= 1e-9 * abs(theory.speed) or theory.time_to_roll < float(model.opt.timestep):
            out["initial-slip"] = float(np.abs(slip[after]).max())
            out["residual-slip"] = float(np.abs(slip[after]).max())
            return out
        # The friction clock: while the ball slides, Coulomb's law takes (1 + 1/gamma) mu times the table's normal
        # impulse off the slip, and vertical momentum makes that impulse M (g t + v_z(t) - v_z(0)) whatever MuJoCo's
        # hops do to the normal force; so u + sgn(u0) (1 + 1/gamma) mu (g t + dv_z) stays u0, and the slip reaches
        # zero when t + dv_z / g = t_r (B2's t_r, read with the hops' impulse put back).
        gamma = float(model.body("ball").inertia[1] / (model.body("ball").mass[0] * theory.radius**2))
        dvz = m.v_W[:, 2] - m.v_W[0, 2]
        clock = t + dvz / theory.g
        held = slip + np.sign(u0) * (1 + 1 / gamma) * theory.mu * theory.g * clock
        rolled = signals.crossings(t[after], np.abs(slip[after]) - ROLLED * abs(u0), direction=-1)
        t_roll = float(rolled[0]) if len(rolled) else np.nan
        sliding = after & (t <= 0.8 * t_roll)
        out["initial-slip"] = float(np.mean(held[sliding])) if sliding.sum() > 2 else np.nan
        # The slip's deceleration: held's slope is sgn(u0) times the predicted less the simulated deceleration.
        slope = float(np.polyfit(t[sliding], held[sliding], 1)[0]) if sliding.sum() > 2 else np.nan
        out["slip-deceleration"] = (1 + 1 / gamma) * theory.mu * theory.g - np.sign(u0) * slope
        out["time-to-roll"] = (
            t_roll + float(signals.interpolate(t, dvz, np.array([t_roll]))[0]) / theory.g if len(rolled) else np.nan
        )
        # The same for the position: x - x_B2 = -sgn(u0) mu (z - z_rest) while sliding (integrate the hops' normal
        # impulse twice), so the CoM travel is read with it put back.
        travel = m.com_W[:, 0] + np.sign(u0) * theory.mu * (m.com_W[:, 2] - prediction["_rest_height"])
        out["skid-distance"] = float(signals.interpolate(t, travel, np.array([theory.time_to_roll]))[0])
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
        M ``speed``. With zero action it then skids and rolls as docs/theory.md B1-B2 say: slip u0 = v0 (1 - 5h/2R),
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
        Box(-1, 1, (2,)), float32, normalised: ``action_scale = 0.1`` times it is an extra horizontal force f_x
        (N) at the centre and torque tau_y (N m), world frame, through ``xfrc_applied``; clipped.
        Zero action = the textbook problem.

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

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(6,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_force, self.max_force, shape=(2,), dtype=np.float64)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        # Read every step: cached per episode (a MuJoCo attribute or a mapping look-up costs ~0.1 us each).
        self._radius = float(self.model.geom("ball").size[0])
        self._rest_height = self.prediction["_rest_height"]
        theory = self.prediction["_theory"]
        self._x_scale = max(abs(theory.skid_distance), theory.radius)  # the length scale of the problem

    def observe(self) -> np.ndarray:
        # PlanarMotion.omega_W and CueStrike.slip for one state, in Python floats (as BlowEnv._observation).
        (x, _, z, q_w, q_x, q_y, q_z), (v_x, _, v_z, w_x, w_y, w_z) = self._free_joint()
        omega_y = dot(frames.matrix_rows(q_w, q_x, q_y, q_z)[1], (w_x, w_y, w_z))
        return np.array([x, z - self._rest_height, v_x, v_z, omega_y, v_x - self._radius * omega_y])

    def observe_batch(self, worlds) -> np.ndarray:
        (x, _, z, q_w, q_x, q_y, q_z), (v_x, _, v_z, w_x, w_y, w_z) = self._free_joints(worlds)
        omega_y = dot(frames.matrix_rows(q_w, q_x, q_y, q_z, sqrt=np.sqrt)[1], (w_x, w_y, w_z))
        return np.stack([x, z - self._rest_height, v_x, v_z, omega_y, v_x - self._radius * omega_y], axis=1)

    def _wrench(self, action: list[float]) -> tuple[float, ...]:
        f_x, tau_y = action
        return f_x, 0.0, 0.0, 0.0, tau_y, 0.0

    observables = ("x", "v_x", "slip")

    def theory(self, t: np.ndarray) -> np.ndarray:
        x, v, u = self.prediction["_theory"].state(t)
        return np.stack([x + self.prediction["_x_offset"], v, u], axis=1)

    def measured(self, obs: np.ndarray) -> list[float]:
        x, _, v_x, _, _, slip = obs.tolist()
        return [x, v_x, slip]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        return abs(measured[0] - predicted[0]) / self._x_scale

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        return obs[:, [0, 2, 5]]

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        return np.abs(measured[:, 0] - predicted[:, 0]) / self._x_scale
