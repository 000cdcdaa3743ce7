"""Torque-free asymmetric top (I1 < I2 < I3): the MuJoCo side of the scenario, and its gymnasium environment.

Theory: docs/theory.md A1-A5 (Jacobi elliptic solution of Euler's equations; Harter & Kim, Am. J. Phys. 44, 1080
(1976), eqs 10-18, reproduced in seed 001), implemented in `rigidbench.analytic.tops.asymmetric_top`.
Model: ``models/free_asymmetric_top.xml``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import signals
from rigidbench.analytic import tops
from rigidbench.contract import Case, Check, Derived, Domain, Scenario, Trajectory, round_step
from rigidbench.envs.rotor import (
    FREE_INERTIA,
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

# Reference timestep (`FreeAsymmetricTop.reference_settings`): the smaller of two limits, as for the symmetric top.
# - Body frame: omega_B follows sn, cn, dn of s t (docs/theory.md A2), whose slopes in tau = s t are at most 1: s h <=
#   BODY_TURN = 1.84e-4 rad: RK4's error (s T)(s h)^4 / 120 <~ 1e-15 over a run; rounded down to one digit
#   (`round_step`) it gives the model file's 1e-4 s at all three default cases (s = 1.84, 1.64, 1.34 rad/s).
# - World frame: the body turns at |omega|; |omega| h <= WORLD_TURN (envs/free_symmetric_top.py: the orientation's
#   error grows only with the body-frame change, <= 4e-11 in momentum drift).
BODY_TURN = 1.84e-4
WORLD_TURN = 0.03
# Most steps of a run; a run needs 2.6 periods of omega2 (two upward crossings for the period, five for the flip).
MAX_STEPS = 1_000_000
_RK4 = (
    "RK4 with s h <= 1.84e-4 and |omega| h <= 0.03 (reference_settings): error ~ (s T)(s h)^4 / 120 <~ 1e-15, "
    "world-frame <= 4e-11; round-off ~1e-12 over <= 1e6 steps, amplified near the separatrix to ~5.2 eta S "
    "(eta <= 2e-14 + 0.05 eps kappa, kappa = I3 / I1; 5.2 eta S <= 5e-9, domain 'separatrix')"
)
_FLIP = (
    "as omega-body; the crossing times are cubic-interpolated (error O(dt^4)); near the separatrix a relative "
    "error eta of the rates shifts each flip by ~eta S / K of its time (T_rev = 2 K / s, K ~ ln(4/k')), <= 6e-10 "
    "(domain 'separatrix')"
)

CHECKS = (
    Check(
        "omega-body",
        "1",
        1e-8,
        "abs",
        _RK4 + " (max |omega(t) - omega_theory(t)| / |omega| over the run)",
        "A2: Jacobi elliptic solution (cn, sn, dn), docs/theory.md; Harter & Kim eqs 10-16",
    ),
    Check(
        "period",
        "s",
        1e-8,
        "rel",
        _RK4 + " (mean spacing of upward zero crossings of omega2)",
        "A2: omega2 = A2 sn(s t + tau0, k) has period 4 K(k) / s",
    ),
    Check(
        "flip-time",
        "s",
        1e-8,
        "rel",
        _FLIP,
        "A3: reversal time 2 K(k) / s, Harter & Kim eq. 17b (as read in docs/theory.md A3)",
    ),
    Check(
        "energy-drift",
        "1",
        1e-9,
        "abs",
        "RK4 is not symplectic: drift ~ (s T)(s h)^4 / 120 <~ 1e-15 at reference, round-off <~ 2e-13 over <= 1e6 "
        "steps; 1e-9 leaves 3 decades",
        "A1: torque-free, E conserved",
    ),
    Check(
        "momentum-drift",
        "1",
        1e-9,
        "abs",
        "world frame: max |L_W(t) - L_W(0)| / |L| <= 4e-11 at reference (|omega| h <= 0.03), round-off <~ 2e-13; "
        "1e-9 leaves a factor 25",
        "A1: torque-free, L_W conserved",
    ),
)
_COMMON = ("omega-body", "period", "energy-drift", "momentum-drift")


def _solution(p: Mapping[str, Any]) -> tops.AsymmetricTop | None:
    """The closed form at the parameters, or None where it is undefined (the domain tests say why)."""
    try:
        return tops.asymmetric_top((p["I1"], p["I2"], p["I3"]), p["omega"])
    except ValueError:
        return None


def reference_step(top: tops.AsymmetricTop, omega: Any) -> Derived:
    """The reference timestep (s): min(BODY_TURN / s, WORLD_TURN / |omega|), rounded down to one digit."""
    speed = float(np.linalg.norm(omega))
    by_body, by_world = BODY_TURN / top.rate, WORLD_TURN / speed
    h = round_step(min(by_body, by_world))
    which = "body frame" if by_body <= by_world else "world frame"
    return Derived(
        h,
        f"min({BODY_TURN:g} rad / s, {WORLD_TURN:g} rad / |omega|) = min({BODY_TURN:g} / {top.rate:.4g}, "
        f"{WORLD_TURN:g} / {speed:.4g}), rounded down to one digit: {h:.1g} s ({which} limit; s = the elliptic "
        "rate of docs/theory.md A2)",
    )


def _vec(v: Any) -> str:
    return ",".join(f"{float(x):.10g}" for x in v)


def _where(p: Mapping[str, Any]) -> str:
    return f"I1, I2, I3 = {p['I1']:.10g}, {p['I2']:.10g}, {p['I3']:.10g} kg m^2, omega = {_vec(p['omega'])} rad/s"


def _separatrix_scales(inertia, omega_body, top) -> dict[str, float]:
    """How the motion amplifies a relative error of the body rates in omega-body and the flip time."""
    sensitivity = tops.separatrix_sensitivity(tuple(inertia), omega_body)
    k_quarter = top.reversal_time * top.rate / 2
    # K moves by eta S / 2, so the period 4 K / s by eta S / (2 K) of itself.
    return {
        "omega-body": 2 * RUN_PERIODS * sensitivity,
        "flip-time": sensitivity / k_quarter,
        "period": sensitivity / (2 * k_quarter),
    }


def rate_roundoff(inertia: Any) -> float:
    """The relative round-off eta of the body rates over a run (see MAX_PHASE_ROUNDOFF): ETA_ROUNDOFF plus
    KAPPA_ROUNDOFF eps kappa, kappa = I3 / I1."""
    return ETA_ROUNDOFF + KAPPA_ROUNDOFF * float(np.finfo(float).eps) * float(inertia[2] / inertia[0])


def _off_separatrix(p: Mapping[str, Any]) -> str | None:
    """Domain test: the separatrix amplification 5.2 eta S of the rates' round-off is at most MAX_PHASE_ROUNDOFF."""
    inertia = (p["I1"], p["I2"], p["I3"])
    try:
        sensitivity = tops.separatrix_sensitivity(inertia, p["omega"])
    except ValueError:  # on the separatrix to 1e-12 (or a non-increasing body, refused by validate first)
        sensitivity = np.inf
    eta = rate_roundoff(inertia)
    if 2 * RUN_PERIODS * eta * sensitivity > MAX_PHASE_ROUNDOFF:
        return (
            f"{_where(p)} (separatrix sensitivity S = {sensitivity:.3g}, rate round-off eta = {eta:.2g}: "
            f"5.2 eta S = {2 * RUN_PERIODS * eta * sensitivity:.2g})"
        )
    return None


def _off_principal_axis(p: Mapping[str, Any]) -> str | None:
    """Domain test: the amplitude of omega2 over the motion is at least 1e-9 |omega|."""
    top = _solution(p)
    if top is None:
        return None
    speed = float(np.linalg.norm(np.asarray(p["omega"], dtype=float)))
    if not top.amplitudes[1] >= 1e-9 * speed:
        return f"{_where(p)} (omega2 oscillates by {abs(top.amplitudes[1]):.3g} rad/s)"
    return None


def _resolvable(p: Mapping[str, Any]) -> str | None:
    """Domain test: the body-frame motion turns >= MIN_TURN_PER_STEP per reference step."""
    top = _solution(p)
    if top is None:
        return None
    h = reference_step(top, p["omega"]).value
    if top.rate * h < MIN_TURN_PER_STEP:
        return f"{_where(p)} (s = {top.rate:.3g} rad/s turns {top.rate * h:.2g} rad per reference step of {h:.3g} s)"
    return None


def _run_length(p: Mapping[str, Any]) -> str | None:
    """Domain test: 2.6 periods of omega2 fit in MAX_STEPS reference steps."""
    top = _solution(p)
    if top is None:
        return None
    h = reference_step(top, p["omega"]).value
    steps = RUN_PERIODS * top.period / h
    if steps > MAX_STEPS:
        return f"{_where(p)} (2.6 periods of {top.period:.3g} s take {steps:.3g} steps of {h:.3g} s)"
    return None


# Near the separatrix a relative error eta of the body rates moves omega(t) over the run's 2.6 periods by ~5.2 eta S
# (`tops.separatrix_sensitivity`); refused where that exceeds MAX_PHASE_ROUNDOFF, half the 1e-8 omega-body tolerance.
# eta has two parts, both measured (`rate_roundoff`):
# - ETA_ROUNDOFF: the round-off of the step itself, <= 2e-14 (15 runs at S = 6e2 .. 5e5, 3e-3 to 3e-2 rad off the
#   intermediate axis of five bodies; e.g. omega-body 1e-9 at S = 4.4e4, 9.4e-9 at S = 5.1e5). Alone it allows
#   S <= 4.8e4: ~0.9e-2 rad off the intermediate axis of the default body (its intermediate-axis case starts 0.02 rad
#   off, S = 6.9e3).
# - KAPPA_ROUNDOFF eps kappa, kappa = I3 / I1: MuJoCo forms the inertia in world axes and solves for the angular
#   acceleration there, so each step's acceleration along body axis 1 carries a relative error ~eps kappa; those
#   errors random-walk over the run to ~eps kappa (s T) / sqrt(N) (s T / sqrt(N) = 0.05 .. 0.1 over these runs).
#   Measured on slender bodies (I1 << I2 ~ I3, kappa = 5e2 .. 8e6, S up to 4.4e4, census draws and a grid): the
#   omega-body error / (5.2 S eps kappa) <= 0.029 where this term dominates (0.022 at kappa = 1.3e6, S = 6.7e3, error
#   2.2e-7; 0.017 at kappa = 7.8e6, S = 4.4e4, error 6.7e-6: both failed before this term was in the domain).
ETA_ROUNDOFF = 2e-14
KAPPA_ROUNDOFF = 0.05
MAX_PHASE_ROUNDOFF = 5e-9
RUN_PERIODS = 2.6

DOMAINS = (
    Domain("mujoco-min-rate", "A1 (MuJoCo: mjMINVAL)", MIN_RATE_DOMAIN_TEXT, mujoco_min_rate),
    Domain(
        "separatrix",
        "A2, A3 (k' -> 0 at the separatrix, L^2 = 2 E I2)",
        f"5.2 eta S <= {MAX_PHASE_ROUNDOFF:g}, S = 2 |omega| sum I_i |I_i - I2| A_i / |L^2 - 2 E I2| "
        "(A_i: amplitudes of omega_i): near the separatrix the period 4 K(k) / s grows like ln(4/k') and a "
        f"relative error eta of the body rates moves omega(t) by ~5.2 eta S over the run's 2.6 periods; eta = "
        f"{ETA_ROUNDOFF:g} + {KAPPA_ROUNDOFF:g} eps I3 / I1 (measured: the step's round-off, and MuJoCo's solve for "
        "the acceleration in world axes, where the inertia has condition I3 / I1); beyond, 5.2 eta S exceeds half "
        "the 1e-8 omega-body tolerance (about 0.9e-2 rad off the intermediate axis of the default 1 : 2 : 2.5 body; "
        "far less for a slender body, I1 << I2 ~ I3)",
        _off_separatrix,
    ),
    Domain(
        "principal-axis",
        "A2 (omega2 = A2 sn(s t + tau0, k))",
        "the amplitude A2 of omega2 is >= 1e-9 |omega|: a spin about a principal axis (axis 1 or 3) does not move, "
        "omega2 has no zero crossings to time (period, flip) and the elliptic phase is 0/0",
        _off_principal_axis,
    ),
    Domain(
        "resolvable-rates",
        "A2 (measured from omega_B(t))",
        f"the elliptic rate s turns by >= {MIN_TURN_PER_STEP:.2g} rad per reference step: MuJoCo rounds each "
        "step's change of the state to an ulp, so a body-frame motion that turns x rad per step is known only to "
        "eps/x relative (a nearly symmetric body spun nearly about its symmetry axis lies beyond)",
        _resolvable,
    ),
    Domain(
        "run-length",
        "A2 (period 4 K(k) / s)",
        f"2.6 periods of omega2 in at most {MAX_STEPS:.0e} reference steps (the period and the flip time need "
        "two upward crossings and five crossings of omega2)",
        _run_length,
    ),
)


class FreeAsymmetricTop(Scenario):
    """A free rigid body with three different principal moments: stable spins about the largest and smallest
    axes, and the intermediate-axis flip (tennis-racket effect), against the exact elliptic solution.

    The cases name their default start; an omega set by hand may put the polhode about either axis, and every
    check holds in both regimes (docs/theory.md A2: omega2 = A2 sn(s t + tau0, k) in both)."""

    slug = "free-asymmetric-top"
    title = "Torque-free asymmetric top (stable axes and the intermediate-axis flip)"
    env_id = "rigidbench/FreeAsymmetricTop-v0"
    params = (
        Param(
            "I1",
            "kg m^2",
            "smallest principal moment about the CM (body x); the motion depends only on the ratios of I1, I2, I3",
            Range(FREE_INERTIA.low, FREE_INERTIA.high, high_open=True),  # room for I1 < I2 < I3 <= 1e3
            BodyInertia("top", (0,)),
        ),
        Param(
            "I2",
            "kg m^2",
            "intermediate principal moment about the CM (body y)",
            FREE_INERTIA,
            BodyInertia("top", (1,)),
            within=Bound(
                "(I1, 1e3) (I1 < I2 < I3; free-symmetric-top for two equal moments)",
                lambda p: Range(p["I1"], FREE_INERTIA.high, low_open=True, high_open=True),
                ("I1",),
            ),
        ),
        Param(
            "I3",
            "kg m^2",
            "largest principal moment about the CM (body z)",
            FREE_INERTIA,
            BodyInertia("top", (2,)),
            within=Bound(
                "(I2, I1 + I2] (I2 < I3, and the triangle inequality I3 <= I1 + I2 of every rigid body)",
                lambda p: Range(p["I2"], p["I1"] + p["I2"], low_open=True),
                ("I1", "I2"),
            ),
        ),
        OMEGA_PARAM,
    )
    cases = (
        Case(
            "major-axis",
            "spin slightly off the largest axis (3): stable, the polhode circles axis 3",
            {"omega": (0.05, 0.1, 3.0)},
            _COMMON,
        ),
        Case(
            "minor-axis",
            "spin slightly off the smallest axis (1): stable, the polhode circles axis 1",
            {"omega": (3.0, 0.1, 0.05)},
            _COMMON,
        ),
        Case(
            "intermediate-axis",
            "omega = W (0, cos eps, sin eps), W = 3 rad/s, eps = 0.02 rad: the body flips over every 2 K / s",
            {"omega": (0.0, 3.0 * np.cos(0.02), 3.0 * np.sin(0.02))},
            (*_COMMON, "flip-time"),
        ),
    )
    checks = CHECKS
    domains = DOMAINS

    def validate(self, params: Mapping[str, Any]) -> None:
        i1, i2, i3 = params["I1"], params["I2"], params["I3"]
        if not i1 < i2 < i3:
            raise ValueError(
                f"parameters I1 = {i1:g}, I2 = {i2:g}, I3 = {i3:g} kg m^2 must satisfy I1 < I2 < I3 "
                "(use free-symmetric-top for two equal moments)"
            )
        require_rigid_body_inertia(i1, i2, i3)

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        top = _solution(params)
        return {} if top is None else {"timestep": reference_step(top, params["omega"])}

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        set_free_body_rotation(data, params["omega"])

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        motion = free_body_motion(model, np.array([data.time]), data.qpos[None], data.qvel[None])
        top = tops.asymmetric_top(tuple(motion.inertia_B), motion.omega_B[0])
        scales = _separatrix_scales(motion.inertia_B, motion.omega_B[0], top)
        kappa = float(motion.inertia_B[2] / motion.inertia_B[0])
        return {
            "_theory": top,
            # Float32 (`Scenario.roundoff_scale`): near the separatrix a relative error eta of the rates moves
            # omega(t) by ~5.2 eta S over the run and each flip by ~eta S / K of its time (the float64 tolerances'
            # reasons, `tops.separatrix_sensitivity`).
            "_roundoff_scale": scales,
            # The world-frame momentum is read from the orientation the spin advances every step: secular on float32
            # (as for the symmetric top, `free_symmetric_top._float32_floors`).
            "_roundoff_secular": ("momentum-drift",),
            # and MuJoCo's solve in world axes adds a relative rate error KAPPA_ROUNDOFF eps kappa, kappa = I3 / I1
            # (`rate_roundoff`), which the random walk of the generic floor does not see: 0.07 on float32 at
            # kappa = 6e5, where MJX's period was 2.2e-3 off against the generic floor's 1.7e-3.
            "_roundoff_eps": {name: KAPPA_ROUNDOFF * kappa * scale for name, scale in scales.items()},
            "_roundoff_eps_rule": f"{KAPPA_ROUNDOFF:g} eps kappa x scale, kappa = I3 / I1 = {kappa:.3g}: the world-axes"
            " solve's rate error (`rate_roundoff`), times the check's separatrix scale",
            "omega-body": 0.0,
            "period": top.period,
            "flip-time": top.reversal_time,
            "energy-drift": 0.0,
            "momentum-drift": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return RUN_PERIODS * prediction["_theory"].period  # at least two full periods of omega2, i.e. five flips

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        top = prediction["_theory"]
        m = free_body_motion(model, traj.time, traj.qpos, traj.qvel)
        w2 = m.omega_B[:, 1]
        up = signals.crossings(m.time, w2, direction=1)
        every = signals.crossings(m.time, w2)
        return {
            "omega-body": float(np.abs(m.omega_B - top.omega_body(m.time)).max() / np.linalg.norm(m.omega_B[0])),
            "period": signals.mean_spacing(up),
            "flip-time": signals.mean_spacing(every),
            "energy-drift": signals.max_relative_drift(m.kinetic_energy),
            "momentum-drift": signals.max_relative_drift(m.L_W),
        }


class FreeAsymmetricTopEnv(FreeRotorEnv):
    """``rigidbench/FreeAsymmetricTop-v0``: the torque-free asymmetric top, scored against theory every step.

    Description
        A free rigid body with I1 < I2 < I3 (about its CM) and no gravity. With zero action it is Euler's
        torque-free top, solved exactly by Jacobi elliptic functions (docs/theory.md A2); the ``intermediate-axis``
        case shows the flip (A3).

    Observation Space
        See `RotorEnv`: body-to-world quaternion (4) and body-frame angular velocity (3, rad/s).

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = 1`` N m times it is a torque on the body in world
        axes, through ``xfrc_applied``; clipped.

    Rewards
        ``reward = -|omega_B - omega_theory(t)| / |omega_theory(t)|`` (see ``info["reward_deviation"]``).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        The case's (or given) ``omega`` in body axes, body unrotated. Deterministic.

    Episode End
        Truncated after 2.6 periods of omega2 (the validation run's duration); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (``major-axis``, ``minor-axis``, ``intermediate-axis``), ``params`` (``I1``, ``I2``, ``I3``,
        ``omega``), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10: 1 ms at
        the default cases; the reference timestep follows I1, I2, I3 and omega, see
        `FreeAsymmetricTop.reference_settings`), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = FreeAsymmetricTop
