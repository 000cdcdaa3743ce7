"""Torque-free symmetric top: the MuJoCo side of the scenario, and its gymnasium environment.

Theory: docs/theory.md S1-S4 (Wilcox Part II section 11.9, eqs 11.41-11.51), implemented in
`rigidbench.analytic.tops.symmetric_top`. Model: ``models/free_symmetric_top.xml``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import frames, signals
from rigidbench.analytic import tops
from rigidbench.contract import Case, Check, Derived, Domain, Scenario, Trajectory, round_step
from rigidbench.envs.rotor import (
    FREE_INERTIA,
    MAX_FREE_STEPS,
    MIN_RATE_DOMAIN_TEXT,
    MIN_TURN_PER_STEP,
    OMEGA_PARAM,
    FreeRotorEnv,
    free_body_motion,
    mujoco_min_rate,
    require_rigid_body_inertia,
    set_free_body_rotation,
)
from rigidbench.params import BodyInertia, Bound, Param, Range

# Reference timestep (`FreeSymmetricTop.reference_settings`): the smaller of two limits.
# - Body frame: omega circles e3 at Omega_b = (I3 - I1) omega3 / I1, and RK4's relative error in that rate is
#   (Omega_b h)^4 / 120. BODY_TURN = 3.51e-4 rad per step: a relative error <= 1.3e-16, below round-off; rounded
#   down to one digit (`round_step`) it gives the model file's 1e-4 s at both default cases (|Omega_b| = 3 and
#   3.5 rad/s).
# - World frame: the body turns at |omega| and its axis precesses about L at |L| / I1 (up to 2 |omega|, oblate).
#   MuJoCo's quaternion step is exact while omega_B is constant, so the orientation's error grows only with the
#   body-frame change: WORLD_TURN = 0.03 rad per step keeps the world-frame checks (precession-rate, spin-rate,
#   momentum-drift) at <= 4e-11 (measured; it grows like WORLD_TURN^4) where Omega_b h = BODY_TURN, the largest
#   body-frame change a world-limited step meets (test_world_limited_timestep_keeps_the_world_frame_checks).
BODY_TURN = 3.51e-4
WORLD_TURN = 0.03
_RK4 = (
    "RK4 with Omega_b h <= 3.51e-4 and max(|omega|, |L|/I1) h <= 0.03 (reference_settings): relative rate error "
    "(Omega_b h)^4/120 <= 1.3e-16, world-frame error <= 4e-11, round-off ~1e-12 over <= 2e5 steps; a rate that "
    "turns >= 4.4e-8 rad per step is rounded to <= 5e-9 (domain 'resolvable-rates')"
)

CHECKS = (
    Check(
        "omega-body",
        "1",
        1e-8,
        "abs",
        _RK4 + " (max |omega(t) - omega_theory(t)| / |omega| over the run)",
        "S1: omega1 + i omega2 = A exp(i (Omega_b t + delta)), Wilcox eqs 11.41-11.42",
    ),
    Check(
        "body-rate",
        "rad/s",
        1e-8,
        "rel",
        _RK4 + " (slope of the unwrapped body-frame phase of omega)",
        "S1: Omega_b = (I3 - I1) omega3 / I1, Wilcox eq. 11.42",
    ),
    Check(
        "precession-rate",
        "rad/s",
        1e-8,
        "rel",
        _RK4 + " (slope of the azimuth of e3 about L)",
        "S3: phi_dot = |L| / I1, Wilcox eqs 11.46-11.51 (signs restored)",
    ),
    Check(
        "spin-rate",
        "rad/s",
        1e-8,
        "rel",
        _RK4 + " (slope of psi with space z along L)",
        "S3: psi_dot = -Omega_b = (I1 - I3) omega3 / I1",
    ),
    Check(
        "cone-beta",
        "rad",
        1e-8,
        "abs",
        _RK4 + " (max over the run of |angle(L, e3) - beta|)",
        "S2: tan beta = I1 A / (I3 omega3), Wilcox eq. 11.44",
    ),
    Check(
        "cone-alpha",
        "rad",
        1e-8,
        "abs",
        _RK4 + " (max over the run of |angle(omega, e3) - alpha|)",
        "S2: tan alpha = A / omega3, Wilcox eq. 11.43",
    ),
    Check(
        "space-cone",
        "rad",
        1e-8,
        "abs",
        _RK4 + " (max over the run of |angle(omega, L) - |beta - alpha||)",
        "S4: the body cone rolls on the space cone of half-angle |beta - alpha|",
    ),
    Check(
        "energy-drift",
        "1",
        1e-9,
        "abs",
        "RK4 is not symplectic: drift ~ (Omega_b T) (Omega_b h)^4 / 120 <~ 1e-14 at reference, round-off ~1e-14 over "
        "<= 2e5 steps; 1e-9 leaves 4 decades",
        "R2/R7: torque-free, E conserved",
    ),
    Check(
        "momentum-drift",
        "1",
        1e-9,
        "abs",
        "world frame: max |L_W(t) - L_W(0)| / |L| <= 4e-11 at reference (the timestep rule above), round-off "
        "~1e-13; 1e-9 leaves a factor 25",
        "R7: torque-free, L_W conserved",
    ),
)
_ALL = tuple(c.name for c in CHECKS)


def rates(i1: float, i3: float, omega: Any) -> tuple[float, float, float]:
    """(Omega_b, |L| / I1, max(|omega|, |L| / I1)) in rad/s: the body-frame precession, the precession of e3 about L
    (docs/theory.md S1, S3) and the fastest turning rate of the motion."""
    w1, w2, w3 = (float(x) for x in omega)
    body = (i3 - i1) * w3 / i1
    precession = float(np.sqrt(w1 * w1 + w2 * w2 + (i3 * w3 / i1) ** 2))
    return body, precession, max(float(np.sqrt(w1 * w1 + w2 * w2 + w3 * w3)), precession)


def reference_step(i1: float, i3: float, omega: Any) -> Derived:
    """The reference timestep (s): min(BODY_TURN / |Omega_b|, WORLD_TURN / max(|omega|, |L| / I1)), rounded down to
    one digit."""
    body, _precession, fastest = rates(i1, i3, omega)
    by_body = BODY_TURN / abs(body) if body else np.inf
    by_world = WORLD_TURN / fastest
    h = round_step(min(by_body, by_world))
    which = "body frame" if by_body <= by_world else "world frame"
    return Derived(
        h,
        f"min({BODY_TURN:g} rad / |Omega_b|, {WORLD_TURN:g} rad / max(|omega|, |L|/I1)) = "
        f"min({BODY_TURN:g} / {abs(body):.4g}, {WORLD_TURN:g} / {fastest:.4g}), rounded down to one digit: "
        f"{h:.1g} s ({which} limit)",
    )


def _resolvable(p: Mapping[str, Any]) -> str | None:
    """Domain test: the slower measured rate turns by at least MIN_TURN_PER_STEP per reference step."""
    if not (np.isfinite(p["I1"]) and np.isfinite(p["I3"])):
        return None
    body, precession, fastest = rates(p["I1"], p["I3"], p["omega"])
    if fastest == 0:
        return "omega = 0,0,0 rad/s (the body does not turn)"
    h = reference_step(p["I1"], p["I3"], p["omega"]).value if body else WORLD_TURN / fastest
    if abs(body) <= precession:
        slow, name = abs(body), "|Omega_b| = |I3 - I1| |omega3| / I1"
    else:
        slow, name = precession, "|L| / I1"
    if slow * h < MIN_TURN_PER_STEP:
        return (
            f"I1 = {p['I1']:.10g} kg m^2, I3 = {p['I3']:.10g} kg m^2, omega = {_vec(p['omega'])} rad/s "
            f"({name} = {slow:.3g} rad/s turns {slow * h:.2g} rad per reference step of {h:.3g} s)"
        )
    return None


def _precessing(p: Mapping[str, Any]) -> str | None:
    """Domain test: a transverse part of omega of at least 1e-6 |omega3|."""
    w1, w2, w3 = (float(x) for x in p["omega"])
    if np.hypot(w1, w2) < 1e-6 * abs(w3):
        return f"omega = {_vec(p['omega'])} rad/s (transverse part {np.hypot(w1, w2):.3g} rad/s)"
    return None


# MuJoCo solves for the angular acceleration in world axes, with an inertia matrix of condition
# kappa = max(I1/I3, I3/I1): the axial rate omega3 then wanders by ~eps kappa |omega| (measured 5e-13 |omega| at
# kappa = 2.1e3, |omega| = 56 rad/s, over 2e5 steps; 1e-2 of that at kappa = 21), which Omega_b = (I3 - I1) omega3 / I1
# inherits relative to |omega3|: eps_b = eps kappa |omega| / |omega3|. The body-frame phase of omega then drifts by
# eps_b Omega_b T over the run, moving omega(t) by (A / |omega|) eps_b |Omega_b| T relative to |omega| (measured:
# 4.0e-8 where this estimate gives 4.2e-8, kappa = 3.2e4). Refused where either exceeds half the 1e-8 tolerances.
AXIAL_ROUND_OFF_LIMIT = 5e-9
# The thinnest rod covered, I3 >= I1 / MAX_INERTIA_RATIO (a uniform rod ~77 radii long): beyond, the axial round-off
# above refuses most spins off the symmetry axis (9 % of a census's draws with the ratio free, 0.8 % with it <= 1e3).
MAX_INERTIA_RATIO = 1e3


def run_duration(body_rate: float, precession_rate: float, step: float) -> float:
    """Simulated time (s): five turns of the slower of Omega_b and |L| / I1, at most MAX_FREE_STEPS reference steps
    (the rates are slopes of unwrapped phases and need no whole turns; domain 'resolvable-rates' bounds their
    rounding per step)."""
    slowest = min(abs(body_rate), precession_rate)
    return min(5 * 2 * np.pi / slowest, MAX_FREE_STEPS * step)


def axial_round_off(i1: float, i3: float, omega: Any) -> tuple[float, float] | None:
    """The axial round-off in units of eps (see AXIAL_ROUND_OFF_LIMIT): eps_b / eps = kappa |omega| / |omega3|, the
    relative error of Omega_b and the spin rate, and eps_b max(1, (A / |omega|) |Omega_b| T) / eps, omega(t)'s over
    the run; None where omega3 or Omega_b is 0 (domains 'resolvable-rates' and 'mujoco-min-rate' refuse those)."""
    w = np.asarray(omega, dtype=float)
    speed = float(np.linalg.norm(w))
    body, precession, _fastest = rates(i1, i3, w)
    if w[2] == 0 or speed == 0 or body == 0:
        return None
    rate = max(i1 / i3, i3 / i1) * speed / abs(w[2])
    phase = abs(body) * run_duration(body, precession, reference_step(i1, i3, w).value)
    return rate, rate * max(1.0, float(np.hypot(w[0], w[1])) / speed * phase)


def _axial_round_off(p: Mapping[str, Any]) -> str | None:
    """Domain test: eps_b max(1, (A / |omega|) |Omega_b| T) <= AXIAL_ROUND_OFF_LIMIT (see there)."""
    gains = axial_round_off(p["I1"], p["I3"], p["omega"])
    if gains is None:
        return None
    error = float(np.finfo(float).eps) * gains[1]
    if error > AXIAL_ROUND_OFF_LIMIT:
        return (
            f"I1 = {p['I1']:.10g} kg m^2, I3 = {p['I3']:.10g} kg m^2, omega = {_vec(p['omega'])} rad/s "
            f"(round-off of Omega_b and of omega(t) up to {error:.2g})"
        )
    return None


AXIAL_ROUNDOFF_RULE = (
    "the axial round-off (domain 'axial-round-off'): eps_b = eps kappa |omega| / |omega3|, kappa = max(I1/I3, I3/I1), "
    "the relative error of Omega_b and the spin rate; omega(t)'s by eps_b max(1, (A / |omega|) |Omega_b| T)"
)


def _float32_floors(i1: float, i3: float, omega: Any) -> dict[str, Any]:
    """A float32 engine's floors (`Scenario._roundoff_check`) beyond the random walk's.

    - The axial round-off in units of eps (``_roundoff_eps``, `axial_round_off`): float64's domain 'axial-round-off'
      keeps it below half the 1e-8 tolerances; on float32 it is 5.4e8 times larger and is the floor of omega(t),
      Omega_b and the spin rate. A Warp census draw (kappa = 13.4, |omega| / |omega3| = 318) had omega(t) 1.8e-3 off
      against the random walk's 5.3e-4; this floor is 6.4e-3 there.
    - The world-frame momentum is read from the orientation the spin advances every step (``_roundoff_secular``):
      Warp's float32 turns the body with a bias, L_W's direction drifting 0.04-0.056 eps a step, linearly from 3e3 to
      1e5 steps (a census draw spinning at 171 rad/s: 5.3e-4 after 1.1e5 steps, 13.5 eps sqrt(N); C MuJoCo with only
      its state rounded to float32 drifts 0.64 eps sqrt(N), a random walk; MJX float32 on an H100 5.29e-4).
    """
    out: dict[str, Any] = {"_roundoff_secular": ("momentum-drift",)}
    gains = axial_round_off(i1, i3, omega)
    if gains is not None:
        rate, omega_body = gains
        out["_roundoff_eps"] = {"omega-body": omega_body, "body-rate": rate, "spin-rate": rate}
        out["_roundoff_eps_rule"] = AXIAL_ROUNDOFF_RULE
    return out


def _vec(v: Any) -> str:
    return ",".join(f"{float(x):.10g}" for x in v)


DOMAINS = (
    Domain("mujoco-min-rate", "S1 (MuJoCo: mjMINVAL)", MIN_RATE_DOMAIN_TEXT, mujoco_min_rate),
    Domain(
        "resolvable-rates",
        "S1, S3 (measured as slopes of phases)",
        f"the slower of Omega_b and |L|/I1 turns by >= {MIN_TURN_PER_STEP:.2g} rad per reference step: MuJoCo "
        "rounds each step's change of the state to an ulp, so a rate that turns x rad per step is known only to "
        "eps/x relative (a near-spherical top, |I3 - I1| << I1, or a spin omega3 -> 0 lies beyond); the run "
        "holds at most 2e5 steps",
        _resolvable,
    ),
    Domain(
        "axial-round-off",
        "S1 (Omega_b from omega3)",
        f"eps_b max(1, (A / |omega|) |Omega_b| T) <= {AXIAL_ROUND_OFF_LIMIT:g}, eps_b = eps kappa |omega| / |omega3|, "
        "kappa = max(I1/I3, I3/I1): MuJoCo solves for the angular acceleration in world axes, where the inertia "
        "has condition kappa, so omega3 wanders by ~eps kappa |omega| (measured), Omega_b = (I3 - I1) omega3 / I1 "
        "by eps_b relative, and the body-frame phase of omega by eps_b |Omega_b| T over the run; beyond, that "
        "exceeds half the 1e-8 tolerances (a thin rod, I3 << I1, spun nearly about a transverse axis)",
        _axial_round_off,
    ),
    Domain(
        "precessing",
        "S1, S2",
        "transverse part sqrt(omega1^2 + omega2^2) >= 1e-6 |omega3|: below, omega lies on the symmetry axis to "
        "round-off and the body-frame phase of omega is undefined",
        _precessing,
    ),
)


class FreeSymmetricTop(Scenario):
    """A free rigid body with I1 = I2 spinning with no torque: omega precesses about the symmetry axis in the
    body frame at Omega_b, and the symmetry axis precesses about L in space at |L|/I1 (docs/theory.md S1-S4)."""

    slug = "free-symmetric-top"
    title = "Torque-free symmetric top (prolate and oblate)"
    env_id = "rigidbench/FreeSymmetricTop-v0"
    params = (
        Param(
            "I1",
            "kg m^2",
            "transverse principal moment I1 = I2 about the CM (the motion depends only on I3 / I1)",
            FREE_INERTIA,
            BodyInertia("top", (0, 1)),
        ),
        Param(
            "I3",
            "kg m^2",
            "principal moment about the symmetry axis (body z), about the CM",
            FREE_INERTIA,
            BodyInertia("top", (2,)),
            within=Bound(
                f"[I1 / {MAX_INERTIA_RATIO:g}, 2 I1] (the triangle inequality I3 <= I1 + I2 of every rigid body; a rod "
                "thinner than I3 = I1 / 1000 makes MuJoCo's axial rate wander by eps (I1 / I3) |omega|, see the "
                "domain 'axial-round-off')",
                lambda p: Range(max(FREE_INERTIA.low, p["I1"] / MAX_INERTIA_RATIO), 2 * p["I1"]),
                ("I1",),
            ),
        ),
        OMEGA_PARAM,
    )
    cases = (
        Case(
            "prolate",
            "I3 < I1 (a cigar): omega circles e3 clockwise seen from +e3; beta > alpha",
            {"I1": 2.0, "I3": 0.8, "omega": (0.3, 0.2, 5.0)},
            _ALL,
        ),
        Case(
            "oblate",
            "I3 > I1 (a disc): omega circles e3 counter-clockwise; beta < alpha",
            {"I1": 1.0, "I3": 1.7, "omega": (0.3, 0.2, 5.0)},
            _ALL,
        ),
    )
    checks = CHECKS
    domains = DOMAINS

    def validate(self, params: Mapping[str, Any]) -> None:
        require_rigid_body_inertia(params["I1"], params["I1"], params["I3"], "I1 = I2, I3")

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        return {"timestep": reference_step(params["I1"], params["I3"], params["omega"])}

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        set_free_body_rotation(data, params["omega"])

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        motion = free_body_motion(model, np.array([data.time]), data.qpos[None], data.qvel[None])
        i1, _, i3 = motion.inertia_B
        top = tops.symmetric_top(i1, i3, motion.omega_B[0])
        step = reference_step(i1, i3, motion.omega_B[0]).value
        return {
            "_theory": top,
            **_float32_floors(i1, i3, motion.omega_B[0]),
            "omega-body": 0.0,
            "body-rate": top.body_rate,
            "precession-rate": top.precession_rate,
            "spin-rate": top.spin_rate,
            "cone-beta": 0.0,
            "cone-alpha": 0.0,
            "space-cone": 0.0,
            "energy-drift": 0.0,
            "momentum-drift": 0.0,
            "_reference_step": step,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        # `run_duration`, at the reference step, not the simulated one, so that a timestep sweep compares runs of the
        # same length.
        top = prediction["_theory"]
        return run_duration(top.body_rate, top.precession_rate, prediction["_reference_step"])

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        top = prediction["_theory"]
        m = free_body_motion(model, traj.time, traj.qpos, traj.qvel)
        t = m.time
        w = m.omega_B
        L0 = m.L_W[0]
        L_hat = L0 / np.linalg.norm(L0)
        # psi with space z along L: rotate the world so L is z, then psi = atan2(R31, R32) (docs/theory.md section 0)
        u = np.cross(L_hat, np.eye(3)[np.argmin(np.abs(L_hat))])
        u /= np.linalg.norm(u)
        basis = np.stack([u, np.cross(L_hat, u), L_hat])  # rows: new x, y, z in world coordinates
        R_LB = basis @ m.R_WB
        beta = frames.angle_between(m.L_W, m.e3_W)
        alpha = frames.angle_between(m.omega_W, m.e3_W)
        space = frames.angle_between(m.omega_W, m.L_W)
        scale = float(np.linalg.norm(w[0]))
        return {
            "omega-body": float(np.abs(w - top.omega_body(t)).max() / scale),
            "body-rate": signals.phase_rate(t, np.arctan2(w[:, 1], w[:, 0])),
            "precession-rate": signals.phase_rate(t, frames.azimuth_about(L_hat, m.e3_W)),
            "spin-rate": signals.phase_rate(t, np.arctan2(R_LB[:, 2, 0], R_LB[:, 2, 1])),
            "cone-beta": float(np.abs(beta - top.beta).max()),
            "cone-alpha": float(np.abs(alpha - top.alpha).max()),
            "space-cone": float(np.abs(space - abs(top.beta - top.alpha)).max()),
            "energy-drift": signals.max_relative_drift(m.kinetic_energy),
            "momentum-drift": signals.max_relative_drift(m.L_W),
        }


class FreeSymmetricTopEnv(FreeRotorEnv):
    """``rigidbench/FreeSymmetricTop-v0``: the torque-free symmetric top, scored against theory every step.

    Description
        A free rigid body with I1 = I2 (about its CM) and no gravity. With zero action it is the textbook
        torque-free symmetric top (docs/theory.md S1-S4): omega circles the symmetry axis in the body frame at
        Omega_b = (I3 - I1) omega3 / I1 and the axis precesses about L at |L| / I1.

    Observation Space
        See `RotorEnv`: body-to-world quaternion (4) and body-frame angular velocity (3, rad/s).

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = 1`` N m times it is a torque on the body in world
        axes, applied through ``xfrc_applied``.
        Out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|omega_B - omega_theory(t)| / |omega_theory(t)|``: the negative relative deviation of the
        body rates from the closed form at the current time; ``info["reward_deviation"]`` holds it, and
        ``info["measured"]`` / ``info["predicted"]`` the two vectors.
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        The case's (or the given) ``omega`` in body axes, body unrotated at the origin. Deterministic.

    Episode End
        Truncated after five turns of the slower precession, at most 2e5 reference steps (the validation run's
        duration); terminated only if the simulation diverges (``info["diverged"] = True``).
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        See `ScenarioEnv`: ``case`` (``prolate``, ``oblate``), ``params`` (``I1``, ``I3``, ``omega``),
        ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 1 ms at the
        prolate default: the reference timestep follows I1, I3 and omega, see `FreeSymmetricTop.reference_settings`),
        ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = FreeSymmetricTop
