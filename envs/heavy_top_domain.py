"""The heavy top's reference run and the domains of its theory: what `rigidbench.envs.heavy_top` refuses before
simulating, and why.

Pure functions of the requested parameters (kg, m, kg m^2, rad, rad/s, m/s^2): the closed form at them
(`closed_form`, docs/theory.md T2-T3), the reference run (`plan`: step and duration, `rigidbench.analytic.heavy_top`),
and the `Domain` tests (`DOMAINS`) and case regimes (the tilt and spin bounds) of the scenario. Split from the scenario
file by concern (issue 34): the scenario declares its parameters, cases and checks and measures; this module says
where the theory holds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigidbench.analytic import heavy_top as theory
from rigidbench.analytic.heavy_top import (  # noqa: F401 (their old import path)
    RK4_TARGET,
    SPIN_TURN,
    UNWRAP_TURN,
    Scales,
    momentum_scale,
    scales,
)
from rigidbench.contract import MAX_ACCELERATION, Derived, Domain, round_step
from rigidbench.params import Bound, Range

# Reference timestep (`HeavyTop.reference_settings`, `reference_run`): the largest that keeps RK4's drift of L and E
# within a target and resolves the motion's rates, rounded down (the rule: `rigidbench.analytic.heavy_top`).
RUN_NUTATIONS = 3.3  # three full nutations: four maxima of theta
# A top falling from near the upright (released at rest below the T6 threshold at theta0 <= FALLING_TILT, the falling
# case) whose three nutations would take more than MAX_STEPS steps runs its first fall only: its checks need no more
# (the growth window and the first maximum, at T_nut / 2), and the way back up takes as long again.
FALL_NUTATIONS = 0.6
MAX_STEPS = 1_000_000

# theta_min is checked relative to itself down to THETA_FLOOR (rad), and in absolute terms (1e-6 x THETA_FLOOR) below:
# an axis passing within THETA_FLOOR of the vertical is located to (Omega h)^4 / 384 <= 3.3e-10 rad (SPIN_TURN), not
# to a fraction of its distance from the vertical.
THETA_FLOOR = 1e-3

# The linearised sleeping top (T6): released at rest from theta0 it tilts to theta0 (s+ + s-)/(s+ - s-) up to
# O(theta0^2). At 1.5x the threshold spin the problem in units of a = I3 omega3 / I1 depends only on theta0 (beta /
# a^2 = 2/9), and the exact cubic (T2) puts the relative error at 0.147 theta0^2: theta0 <= 0.026 rad keeps it below
# 1e-4, a tenth of the check's tolerance (domain 'linear-max-tilt' computes it exactly for any spin).
SLEEPING_TILT = 0.026
LINEAR_ERROR = 1e-4

# The falling top (T6): ln(theta) is fitted over theta in [20, 100] theta0, where the nonlinear terms O(theta^2)
# are <= (100 theta0)^2 <= 1e-4 for theta0 <= 1e-4 rad.
FALLING_TILT = 1e-4


def _pivot_inertia(p: Mapping[str, Any]) -> float:
    return p["I1"] + p["mass"] * p["arm"] ** 2  # parallel axes, docs/theory.md R4


def _mgh(p: Mapping[str, Any]) -> float:
    return p["mass"] * p["g"] * p["arm"]


def _threshold(p: Mapping[str, Any]) -> float:
    return theory.sleeping_threshold(_pivot_inertia(p), p["I3"], _mgh(p))


def _steady(p: Mapping[str, Any], root: int) -> float:
    """The T4 root (0: slow, 1: fast), or 0 where there is none: the steady cases' spin regime refuses those."""
    try:
        rate = theory.steady_precession_rates(_pivot_inertia(p), p["I3"], _mgh(p), p["spin"], p["tilt"])[root]
    except ValueError:  # I3^2 omega3^2 < 4 I1 M g h cos(theta0)
        return 0.0
    return rate if math.isfinite(rate) else 0.0


def closed_form(p: Mapping[str, Any]) -> theory.HeavyTop:
    """The T2-T3 closed form at the parameters (the prediction uses the state MuJoCo holds, equal to round-off)."""
    return theory.heavy_top(
        _pivot_inertia(p),
        p["I3"],
        _mgh(p),
        tilt=p["tilt"],
        tilt_rate=p["nutation_rate"],
        precession=p["precession"],
        spin=p["spin"],
    )


@dataclass(frozen=True)
class Plan:
    """The reference run of a parameter set: closed form, scales, step (s), duration (s) and steps."""

    top: theory.HeavyTop
    scales: Scales
    step: Derived
    duration: float

    @property
    def steps(self) -> float:
        return self.duration / self.step.value


def plan(p: Mapping[str, Any]) -> Plan:
    """The reference run at the parameters `p` (`rigidbench.analytic.heavy_top.RK4_TARGET`).

    Raises
    ------
    ValueError
        Where the closed form is undefined (mgh <= 0, a tilt outside (0, pi)).
    """
    return reference_run(
        closed_form(p),
        _pivot_inertia(p),
        p["I3"],
        _mgh(p),
        tilt=p["tilt"],
        tilt_rate=p["nutation_rate"],
        precession=p["precession"],
        spin=p["spin"],
    )


def reference_run(
    top: theory.HeavyTop,
    inertia_pivot: float,
    inertia_axial: float,
    mgh: float,
    *,
    tilt: float,
    tilt_rate: float,
    precession: float,
    spin: float,
) -> Plan:
    """The reference run of the motion `top` (its initial state as `theory.heavy_top` takes it): RUN_NUTATIONS
    nutation periods (FALL_NUTATIONS for a falling top whose three would exceed MAX_STEPS) at the step of the
    comment on `rigidbench.analytic.heavy_top.RK4_TARGET`."""
    i1 = inertia_pivot
    falling = (
        tilt <= FALLING_TILT
        and tilt_rate == 0
        and precession == 0
        and abs(spin) < theory.sleeping_threshold(i1, inertia_axial, mgh)
    )
    for nutations in (RUN_NUTATIONS, FALL_NUTATIONS) if falling else (RUN_NUTATIONS,):
        limits = theory.step_limits(
            top,
            inertia_pivot,
            inertia_axial,
            mgh,
            tilt=tilt,
            tilt_rate=tilt_rate,
            precession=precession,
            spin=spin,
            nutations=nutations,
        )
        h = round_step(limits.step)
        if limits.duration / h <= MAX_STEPS:
            break
    return Plan(top, limits.scales, Derived(h, limits.rule(h)), limits.duration)


def _plan_or_none(p: Mapping[str, Any]) -> Plan | None:
    try:
        return plan(p)
    except (ValueError, ArithmeticError):
        return None


def _where(p: Mapping[str, Any], *names: str) -> str:
    units = {"mass": "kg", "arm": "m", "I1": "kg m^2", "I3": "kg m^2", "tilt": "rad", "g": "m/s^2"}
    return ", ".join(f"{n} = {float(p[n]):.10g} {units.get(n, 'rad/s')}" for n in names)


_ALL_NAMES = ("mass", "arm", "I1", "I3", "tilt", "spin", "precession", "nutation_rate", "g")


def _run_length(p: Mapping[str, Any]) -> str | None:
    """Domain test: the run (`run_nutations` nutation periods) takes at most MAX_STEPS reference steps."""
    pl = _plan_or_none(p)
    if pl is not None and not pl.steps <= MAX_STEPS:
        return (
            f"{_where(p, *_ALL_NAMES)} ({pl.duration / pl.top.nutation_period:g} nutation periods of "
            f"{pl.top.nutation_period:.3g} s take {pl.steps:.3g} steps of {pl.step.value:.1g} s)"
        )
    return None


# The body-frame angular acceleration of the top is at most |I1 - I3| |omega3| |omega_perp|max / I1 + M g h / I1
# (`rigidbench.analytic.heavy_top.acceleration_bound`); refused above settings.MAX_ACCELERATION (mjMAXVAL / 10).


def _acceleration(p: Mapping[str, Any]) -> str | None:
    """Domain test: the largest angular acceleration of the motion stays below MAX_ACCELERATION."""
    pl = _plan_or_none(p)
    if pl is None:
        return None
    bound = theory.acceleration_bound(_pivot_inertia(p), p["I3"], _mgh(p), p["spin"], pl.scales.transverse)
    if not bound <= MAX_ACCELERATION:
        return f"{_where(p, *_ALL_NAMES)} (angular accelerations up to {bound:.3g} rad/s^2)"
    return None


# The mean precession is the advance of phi between the first and last theta maxima over the run, known to ~2e-11
# rad (round-off and interpolation, measured); it must advance by 1.2e-4 rad for that to stay below half the 1e-6
# tolerance (a planar swing, spin = 0 and phi_dot0 = 0, does not precess at all).
MIN_ADVANCE = 1.2e-4


def _advancing(p: Mapping[str, Any]) -> str | None:
    """Domain test: |mean phi_dot| over the run's whole nutation periods >= MIN_ADVANCE rad."""
    pl = _plan_or_none(p)
    if pl is None:
        return None
    advance = abs(pl.top.mean_precession_rate) * 3 * pl.top.nutation_period
    if not advance >= MIN_ADVANCE:
        return f"{_where(p, *_ALL_NAMES)} (the axis advances {advance:.3g} rad in three nutation periods)"
    return None


def _steady_by_derivation(root: int, case: str):
    def test(p: Mapping[str, Any]) -> str | None:
        derived = _steady(p, root)
        if p["precession"] != derived:
            return (
                f"precession = {p['precession']:.10g} rad/s set by hand (case '{case}' starts at the "
                f"{'slow' if root == 0 else 'fast'} T4 root, {derived:.10g} rad/s here; a top started at another "
                "phi_dot nutates: run heavy-top:nutation, or heavy-top:looping)"
            )
        return None

    return test


def _linear_max_tilt(p: Mapping[str, Any]) -> str | None:
    """Domain test (sleeping): above the T6 threshold, with the linear max tilt within LINEAR_ERROR of the exact."""
    i1, i3, mgh = _pivot_inertia(p), p["I3"], _mgh(p)
    if (i3 * p["spin"]) ** 2 <= 4 * i1 * mgh:
        return f"{_where(p, 'spin')} (at or below the sleeping threshold {_threshold(p):.4g} rad/s)"
    top = _plan_or_none(p)
    if top is None:
        return None
    linear = theory.sleeping_max_tilt(i1, i3, mgh, p["spin"], p["tilt"])
    error = abs(linear / top.top.theta_max - 1)
    if not error <= LINEAR_ERROR:
        return f"{_where(p, 'tilt', 'spin')} (the linear max tilt is {error:.2g} off the exact root of T2)"
    return None


def _falling(p: Mapping[str, Any]) -> str | None:
    """Domain test (falling): |spin| at most half the T6 threshold."""
    if abs(p["spin"]) > 0.5 * _threshold(p) * (1 + 1e-12):
        return f"{_where(p, 'spin')} (the threshold is {_threshold(p):.4g} rad/s)"
    return None


def _spin_bound(p: Mapping[str, Any]) -> float:
    """S = omega_c / sqrt(2 SIGMA_MIN): |spin| <= S keeps beta / a^2 >= SIGMA_MIN (omega_c: the T6 threshold)."""
    return _threshold(p) / math.sqrt(2 * SIGMA_MIN)


# A top's pivot inertia is at most RHO_MAX times its axial one: the transverse body rates turn at the spin, the
# nutation at ~I3 omega3 / I1, so a run of RUN_NUTATIONS nutations takes ~RHO_MAX times more steps than nutations
# need (1e5 to 1e6 at RHO_MAX = 100); a longer arm makes a spinning pendulum, not a top.
RHO_MAX = 100.0
# The T6 threshold omega_c = 2 sqrt(I1 M g h) / I3 is the top's natural rate (>= the pendulum's sqrt(M g h / I1) / 2):
# at most OMEGA_C_MAX (a bound on g), so that the spins up to S = 129 omega_c and the initial rates fit RATE_RANGE.
OMEGA_C_MAX = 1e4
RATE_RANGE = Range(-1e6, 1e6)
# The gyroscopic ratio beta / a^2 = 2 I1 M g h / (I3 omega3)^2 at least: a faster top nutates by ~(beta / a^2)
# sin^2(theta0) and precesses by ~pi beta / a^2 rad per nutation, below the ~1e-11 of the state's round-off
# relative to the 1e-6 tolerances (the mean precession needs 1.2e-4 rad over three nutations: 'advancing').
SIGMA_MIN = 3e-5

DOMAINS = (
    Domain(
        "mujoco-max-acceleration",
        "T1 (MuJoCo: mjMAXVAL = 1e10)",
        f"angular accelerations |I1 - I3| |omega3| |omega_perp|max / I1 + M g h / I1 <= {MAX_ACCELERATION:g} "
        "rad/s^2: MuJoCo treats a joint acceleration above mjMAXVAL = 1e10 as a divergence and resets the state "
        "(an engine limit, not the theory's)",
        _acceleration,
    ),
    Domain(
        "run-length",
        "T3 (T_nut = 4 K(k) / sqrt(beta (u3 - u1)))",
        f"{RUN_NUTATIONS:g} nutation periods (or the first fall of a falling top) in at most {MAX_STEPS:.0e} "
        "reference steps (the step follows the fastest rate of the motion, its spin at most, the run its "
        "nutation: a top with a long arm, I1 ~ 100 I3, spins ~100 times faster than it nutates)",
        _run_length,
    ),
    Domain(
        "advancing",
        "T3 (mean precession)",
        f"the axis advances by >= {MIN_ADVANCE:g} rad in three nutation periods: the mean precession is the "
        "advance of phi between theta maxima, known to ~2e-11 rad (round-off), so smaller advances are not "
        "measurable to the 1e-6 tolerance (a planar swing, spin = 0 and phi_dot0 = 0, does not precess)",
        _advancing,
        cases=("nutation", "looping", "sleeping"),
    ),
    Domain(
        "slow-steady",
        "T4 (steady precession)",
        "case slow-precession starts at the slow T4 root: precession is derived, not set by hand (a top started "
        "at another phi_dot nutates; heavy-top:nutation and heavy-top:looping take any phi_dot)",
        _steady_by_derivation(0, "slow-precession"),
        cases=("slow-precession",),
    ),
    Domain(
        "fast-steady",
        "T4 (steady precession)",
        "case fast-precession starts at the fast T4 root: precession is derived, not set by hand (a top started "
        "at another phi_dot nutates; heavy-top:nutation and heavy-top:looping take any phi_dot)",
        _steady_by_derivation(1, "fast-precession"),
        cases=("fast-precession",),
    ),
    Domain(
        "linear-max-tilt",
        "T6 (sleeping top, Wilcox prob. 11.13)",
        f"I3^2 omega3^2 > 4 I1 M g h (above the threshold) and the linear max tilt within {LINEAR_ERROR:g} of "
        "the exact root of T2 (a tenth of the check's 1e-3 tolerance): the linearisation's error grows like "
        "theta0^2 and without bound toward the threshold",
        _linear_max_tilt,
        cases=("sleeping",),
    ),
    Domain(
        "falling",
        "T6 (falling top)",
        "|spin| <= half the T6 threshold 2 sqrt(I1 M g h) / I3: the fit of ln(theta) over [20, 100] theta0 is "
        "biased by the decaying mode, more as the spin nears the threshold (2.2e-4 measured at one half)",
        _falling,
        cases=("falling",),
    ),
)

_ZERO = Range(0.0, 0.0)
# Tilts of the nutation, looping and steady cases: near the vertical their checks are ill-conditioned (theta_min -> 0
# is checked relative to itself; a top below the sleeping threshold returns to its start only to dE / (M g h
# theta0^2); the azimuth of a steady top's axis carries the orientation's round-off over sin(theta0)). The sleeping and
# falling cases cover the nearly upright top.
_OFF_VERTICAL = Range(0.01, np.pi - 0.01)
_OFF_VERTICAL_WHY = (
    "theta0 within 0.01 rad of the vertical makes the checks relative to theta ill-conditioned (the sleeping and "
    "falling cases cover the nearly upright top)"
)
# Spins of the steady and looping cases: T4 has roots for I3^2 omega3^2 >= 4 I1 M g h cos(theta0), i.e. omega3 >=
# omega_c sqrt(cos(theta0)) above the horizontal; at least omega_c / 100 keeps the slow root below 100 omega_c near
# the horizontal (2 M g h / (I3 omega3)). A negative spin mirrors the motion (phi_dot -> -phi_dot).
_STEADY_SPIN = Bound(
    "[omega_c max(sqrt(max(cos tilt, 0)), 0.01), S]",
    lambda p: Range(_threshold(p) * max(math.sqrt(max(math.cos(p["tilt"]), 0.0)), 0.01), _spin_bound(p)),
    ("mass", "arm", "I1", "I3", "g", "tilt"),
)
# The fast root (I3 omega3 + sqrt(D)) / (2 I1 cos(theta0)) <= I3 omega3 / (I1 cos(theta0)): infinite at the
# horizontal, so fast-precession stays above it (cos(theta0) >= 0.07) with a spin that keeps the root <= 5e5 rad/s.
FAST_TILT = 1.5
_FAST_SPIN = Bound(
    "[omega_c max(sqrt(cos tilt), 0.01), min(S, 5e5 (I1 + M arm^2) cos(tilt) / I3)]",
    lambda p: Range(
        _threshold(p) * max(math.sqrt(max(math.cos(p["tilt"]), 0.0)), 0.01),
        min(_spin_bound(p), 5e5 * _pivot_inertia(p) * math.cos(p["tilt"]) / p["I3"]),
    ),
    ("mass", "arm", "I1", "I3", "g", "tilt"),
)
_AT_REST = "released at rest (theta_dot = phi_dot = 0), as T6 assumes"
