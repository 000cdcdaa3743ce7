"""The heavy (Lagrange) top on a fixed pivot: its closed form (`heavy_top`, docs/theory.md T1-T7), and from it the
rates, reference step, largest acceleration and float32 round-off scales; the scenario (`rigidbench.envs.heavy_top`)
picks the run's length and rounds the step. Pure numpy functions of SI values; nothing here imports mujoco (house
rule 2).

Conventions (docs/theory.md section 0, as `rigidbench.analytic.tops`): ``inertia_pivot`` = I1 + M h^2 about the pivot
(R4) and ``inertia_axial`` = I3 (kg m^2); ``mgh`` = M g h (J); ``spin`` = omega3, every rate in rad/s; the initial
state (tilt, tilt_rate, precession, spin) as `heavy_top` takes it. References: [W] Wilcox, *Modern
Introductory Mechanics Part II*, section 11.10 (seed 000); [T] docs/theory.md T2-T3 (heavy top), R7 (Euler).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rigidbench import lazy

special = lazy.module("scipy.special")

# ---------------------------------------------------------------------------------------------------------
# Heavy symmetric top on a fixed pivot (docs/theory.md T1-T7; Wilcox section 11.10)
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HeavyTop:
    """The Lagrange top reduced to u = cos(theta) ([T] T2, T3).

    theta is measured from the upward vertical; I1 is the transverse moment about the pivot. The cubic is
    solved in w = u0 - u (u0 = cos(theta0)), which keeps its coefficients free of cancellation when the top
    is nearly upright (all three roots then crowd near u = 1).

    Attributes
    ----------
    a, beta : float
        a = I3 omega3 / I1 (1/s); beta = 2 M g h / I1 (1/s^2).
        u_dot^2 = f(u) = (1 - u^2)(alpha - beta u) - (b - a u)^2 = beta (u - u1)(u - u2)(u - u3), b = p_phi / I1.
    c : float
        b - a u0 = phi_dot0 sin^2(theta0) (1/s), kept as formed from the initial state: b itself (the property
        `b`) is c + a u0, and b - a u0 computed from it would cancel to the digits of a u0 that c lacks (near the
        inverted or upright top with a slow precession, a u0 >> c).
    u0 : float
        cos(theta0) at t = 0.
    w_roots : tuple of float
        w1 >= w2 >= w3 with u_i = u0 - w_i, i.e. u1 <= u2 <= u3: theta nutates between arccos(u2) (theta_min)
        and arccos(u1) (theta_max); u3 >= 1.
    nutation_period : float
        T_nut = 4 K(k) / sqrt(beta (u3 - u1)) (s), k^2 = (u2 - u1)/(u3 - u1) ([T] T3).
    t_max_tilt : float
        A time (s) at which u = u1 (theta largest): u(t) = u1 + (u2 - u1) sn^2(nu (t - t_max_tilt), k).
    mean_precession_rate : float
        Delta phi / T_nut (rad/s): phi_dot = (b - a u)/(1 - u^2) over one period, in closed form (elliptic integrals
        of the third kind, `_mean_precession_rate`).
    """

    a: float
    c: float
    beta: float
    u0: float
    sin2_tilt: float
    w_roots: tuple[float, float, float]
    nutation_period: float
    t_max_tilt: float
    mean_precession_rate: float = float("nan")

    @property
    def b(self) -> float:
        """b = p_phi / I1 = c + a u0 (1/s) ([T] T2)."""
        return self.c + self.a * self.u0

    @property
    def roots(self) -> tuple[float, float, float]:
        """u1 <= u2 <= u3."""
        return tuple(self.u0 - w for w in self.w_roots)

    def theta_at_w(self, w: float | np.ndarray) -> float | np.ndarray:
        """theta (rad) at u = u0 - w (scalar or array)."""
        # sin^2(theta) = 1 - u^2 = sin^2(theta0) + 2 u0 w - w^2, without cancellation near theta = 0
        w = np.asarray(w, dtype=float)
        theta = np.arctan2(np.sqrt(np.maximum(self.sin2_tilt + 2 * self.u0 * w - w * w, 0.0)), self.u0 - w)
        return float(theta) if theta.ndim == 0 else theta

    @property
    def theta_min(self) -> float:
        return self.theta_at_w(self.w_roots[1])

    @property
    def theta_max(self) -> float:
        return self.theta_at_w(self.w_roots[0])

    def precession_rate_at_w(self, w: np.ndarray) -> np.ndarray:
        """phi_dot = (b - a u)/(1 - u^2) (rad/s) at u = u0 - w ([T] T2).

        Evaluated as (c + a w) / (sin^2(theta0) + 2 u0 w - w^2), with c = b - a u0 kept from the initial state
        and 1 - u^2 expanded about u0: no term cancels that the state itself does not make cancel, so the
        relative error is a few ulps times the conditioning of the sums c + a w and 1 - u^2 (test:
        `test_precession_rate_at_w_keeps_its_digits_near_the_inverted_top`).
        """
        w = np.asarray(w, dtype=float)
        return (self.c + self.a * w) / (self.sin2_tilt + 2 * self.u0 * w - w * w)

    def w(self, t: np.ndarray) -> np.ndarray:
        """u0 - u(t) at times `t` (s) ([T] T3)."""
        w1, w2, w3 = self.w_roots
        nu = 0.5 * np.sqrt(self.beta * (w1 - w3))
        m = (w1 - w2) / (w1 - w3)
        sn = special.ellipj(nu * (np.asarray(t, dtype=float) - self.t_max_tilt), m)[0]
        return w1 - (w1 - w2) * sn**2

    def u(self, t: np.ndarray) -> np.ndarray:
        """u = cos(theta) at times `t` (s) ([T] T3)."""
        return self.u0 - self.w(t)


def _polish_roots(coeffs: np.ndarray) -> np.ndarray:
    roots = np.sort(np.roots(coeffs).real)
    deriv = np.polyder(coeffs)
    for _ in range(3):  # Newton steps; the roots of a nutating top are simple
        d = np.polyval(deriv, roots)
        safe = np.where(d != 0, d, 1.0)
        roots = roots - np.where(d != 0, np.polyval(coeffs, roots) / safe, 0.0)
    return np.sort(roots)


def heavy_top(
    inertia_pivot: float,
    inertia_axial: float,
    mgh: float,
    *,
    tilt: float,
    tilt_rate: float,
    precession: float,
    spin: float,
) -> HeavyTop:
    """Solve the heavy symmetric top from its state at t = 0.

    Parameters
    ----------
    inertia_pivot : float
        I1 (kg m^2), transverse moment about the pivot (= I_perp,cm + M h^2, docs/theory.md R4).
    inertia_axial : float
        I3 (kg m^2).
    mgh : float
        M g h (J): mass times gravity times pivot-to-CM distance.
    tilt, tilt_rate : float
        theta0 (rad, from the upward vertical) and theta_dot0 (rad/s).
    precession : float
        phi_dot0 (rad/s).
    spin : float
        omega3 = psi_dot + phi_dot cos(theta) (rad/s), conserved.

    Raises
    ------
    ValueError
        If mgh <= 0 (the reduction needs gravity and an offset CM) or the tilt is not in (0, pi).

    Notes
    -----
    With w = u0 - u, c = b - a u0 = phi_dot0 sin^2(theta0) and alpha - beta u = k0 + beta w, where
    k0 = theta_dot0^2 + phi_dot0^2 sin^2(theta0) (the transverse body rates squared),
    f = (sin^2 theta0 + 2 u0 w - w^2)(k0 + beta w) - (c + a w)^2
      = -beta w^3 + (2 u0 beta - k0 - a^2) w^2 + (beta sin^2 theta0 + 2 u0 k0 - 2 a c) w + (k0 sin^2 theta0 - c^2).
    """
    if mgh <= 0:
        raise ValueError(f"mgh = {mgh} J must be positive")
    if not 0 < tilt < np.pi:
        raise ValueError(f"tilt = {tilt} rad must be in (0, pi)")
    i1 = float(inertia_pivot)
    a = inertia_axial * spin / i1
    beta = 2 * mgh / i1
    u0, s2 = float(np.cos(tilt)), float(np.sin(tilt) ** 2)
    k0 = tilt_rate**2 + precession**2 * s2
    c = precession * s2
    coeffs = np.array([-beta, 2 * u0 * beta - k0 - a * a, beta * s2 + 2 * u0 * k0 - 2 * a * c, k0 * s2 - c * c])
    if tilt_rate == 0:
        # theta0 is a turning point: w = 0 is an exact root (k0 s2 = c^2). Deflate and solve the quadratic
        # stably, so that a (nearly) double root at 0, i.e. (nearly) steady precession, stays exact.
        qa, qb, qc = coeffs[:3]
        disc = max(qb * qb - 4 * qa * qc, 0.0)
        q = -0.5 * (qb + np.copysign(np.sqrt(disc), qb))
        w3, w2, w1 = sorted([0.0, q / qa, qc / q if q != 0 else 0.0])
    else:
        w3, w2, w1 = _polish_roots(coeffs)  # ascending w = descending u
    w1, w2 = max(w1, 0.0), min(w2, 0.0)  # u0 lies in [u1, u2]; round-off can put it a hair outside
    nu = 0.5 * np.sqrt(beta * (w1 - w3))
    m = (w1 - w2) / (w1 - w3)
    # K(m) = K(1 - m1), m1 = (w2 - w3)/(w1 - w3) formed without cancellation: a top released near the upright
    # has m within 1e-9 of 1, where 1 - m in double precision would lose half its digits.
    period = 2 * special.ellipkm1((w2 - w3) / (w1 - w3)) / nu
    # phase: w(0) = 0 with w(t) = w1 - (w1 - w2) sn^2(nu (t - t1)); u = u0 - w rises (w falls) just after t1.
    r = 1.0 if w1 == w2 else float(np.clip(w1 / (w1 - w2), 0.0, 1.0))
    offset = special.ellipkinc(np.arcsin(np.sqrt(r)), m) / nu
    u0_dot = -np.sin(tilt) * tilt_rate
    t1 = -offset if u0_dot >= 0 else offset
    mean_rate = _mean_precession_rate(a, c, u0, s2, w1, w2, w3)
    return HeavyTop(a, c, beta, u0, s2, (w1, w2, w3), float(period), float(t1), mean_rate)


def _mean_precession_rate(a: float, c: float, u0: float, s2: float, w1: float, w2: float, w3: float) -> float:
    """Delta phi / T_nut (rad/s) over one nutation period, in closed form ([T] T3).

    phi_dot = (b - a u)/(1 - u^2) = A+ / (1 - u) + A- / (1 + u), A+- = (b -+ a)/2, and with u = u1 + (u2 - u1)
    sn^2(nu t, k) each term integrates over a period 2K / nu to a complete elliptic integral of the third kind:

        Delta phi / T_nut = [A+ Pi(n+ | m) / (1 - u1) + A- Pi(n- | m) / (1 + u1)] / K(m),
        n+ = (u2 - u1) / (1 - u1),  n- = -(u2 - u1) / (1 + u1),  m = k^2,

    Pi(n | m) = R_F(0, 1 - m, 1) + (n / 3) R_J(0, 1 - m, 1, 1 - n) (Carlson; DLMF 19.25.2). Unlike a quadrature in t
    it keeps its accuracy where the axis passes near a pole and phi_dot spikes to ~|omega_perp| / theta there
    (a trapezoid rule on 4096 points missed such a spike by 1e-2 of the rate). Every difference is formed from
    w = u0 - u and 1 -+ u0 without cancellation: 1 - u_i = (1 - u0) + w_i, 1 + u_i = (1 + u0) - w_i.
    """
    one_minus_u0, one_plus_u0 = (s2 / (1 + u0), 1 + u0) if u0 > 0 else (1 - u0, s2 / (1 - u0))
    a_plus = 0.5 * (c - a * one_minus_u0)  # (b - a) / 2, b = c + a u0
    a_minus = 0.5 * (c + a * one_plus_u0)  # (b + a) / 2
    spread = w1 - w2  # u2 - u1
    m1 = (w2 - w3) / (w1 - w3)  # 1 - m
    terms = 0.0
    for amplitude, gap1, gap2, sign in (
        (a_plus, one_minus_u0 + w1, one_minus_u0 + w2, 1.0),  # 1 - u1, 1 - u2
        (a_minus, one_plus_u0 - w1, one_plus_u0 - w2, -1.0),  # 1 + u1, 1 + u2
    ):
        if amplitude == 0:
            continue
        n = sign * spread / gap1
        pi_n = special.elliprf(0.0, m1, 1.0) + n / 3 * special.elliprj(0.0, m1, 1.0, gap2 / gap1)  # 1 - n
        terms += amplitude * pi_n / gap1
    return float(terms / special.ellipkm1(m1))


def steady_precession_rates(
    inertia_pivot: float, inertia_axial: float, mgh: float, spin: float, tilt: float
) -> tuple[float, float]:
    """Slow and fast steady-precession rates phi_dot (rad/s) at fixed tilt ([T] T4, [W] prob. 11.18).

    Roots of I1 cos(theta0) phi_dot^2 - I3 omega3 phi_dot + M g h = 0, written so the slow root stays accurate
    as cos(theta0) -> 0: slow = 2 M g h / (I3 omega3 + sqrt(D)), fast = (I3 omega3 + sqrt(D)) / (2 I1 cos theta0),
    D = I3^2 omega3^2 - 4 I1 M g h cos(theta0). The fast root is infinite at theta0 = pi/2.

    Raises
    ------
    ValueError
        If D < 0: no steady precession at this tilt and spin (above the horizontal the spin must exceed
        sqrt(4 I1 M g h cos(theta0)) / I3).
    """
    p = inertia_axial * spin
    c = np.cos(tilt)
    disc = p * p - 4 * inertia_pivot * mgh * c
    if disc < 0:
        need = np.sqrt(4 * inertia_pivot * mgh * c) / inertia_axial
        raise ValueError(
            f"no steady precession at tilt = {tilt:g} rad with spin = {spin:g} rad/s; needs spin >= {need:g} rad/s"
        )
    root = p + np.copysign(np.sqrt(disc), p)
    slow = 2 * mgh / root
    fast = root / (2 * inertia_pivot * c) if c != 0 else np.inf
    return float(slow), float(fast)


def sleeping_threshold(inertia_pivot: float, inertia_axial: float, mgh: float) -> float:
    """Smallest spin omega3 (rad/s) for which the upright top is stable: I3 omega3 = 2 sqrt(I1 M g h) ([T] T6)."""
    return float(2 * np.sqrt(inertia_pivot * mgh) / inertia_axial)


def sleeping_max_tilt(inertia_pivot: float, inertia_axial: float, mgh: float, spin: float, tilt: float) -> float:
    """Linearised largest tilt (rad) of a top above threshold released at rest from a small tilt ([T] T6).

    theta_max = theta0 (s+ + s-)/(s+ - s-) = theta0 I3 omega3 / sqrt(I3^2 omega3^2 - 4 I1 M g h).
    Relative error O(theta0^2) from the linearisation.
    """
    p = inertia_axial * spin
    return float(tilt * p / np.sqrt(p * p - 4 * inertia_pivot * mgh))


def falling_growth_rate(inertia_pivot: float, inertia_axial: float, mgh: float, spin: float) -> float:
    """gamma = sqrt(4 I1 M g h - I3^2 omega3^2) / (2 I1) (1/s): tilt growth below threshold ([T] T6)."""
    return float(np.sqrt(4 * inertia_pivot * mgh - (inertia_axial * spin) ** 2) / (2 * inertia_pivot))


# Reference timestep (`step_limits`). MuJoCo integrates the body-frame rates of the ball joint, whose transverse
# part turns in the body frame as the body spins, and a phase error of RK4 there that the quaternion does not share
# turns the transverse angular momentum I1 omega_perp about the axis. Over a run of T that is a relative error in L
# (and E) of about
#     r Omega T (Omega h)^4 / 120,   r = I1 |omega_perp|max / L_scale,   Omega = the fastest rate of the motion
# (`Scales.fastest`: the largest |omega|, the body-frame precession |I3 - I1| |omega3| / I1, the nutation, sqrt(beta))
# (measured: at most 0.09 of it, scaling as h^4, over 114 census draws and slow tops swinging through 2.9 rad). The
# step keeps it at RK4_TARGET = 4e-9, 0.4 of the scenario's 1e-8 drift tolerances; it resolves the fastest rate by
# at least 1 / SPIN_TURN = 53 steps a radian (the model file's 1e-4 s at the default spin, 150 rad/s: every rate of
# the motion, the nutation's cubic-interpolated events included, with an RK4 phase error (Omega h)^4 / 120 <= 1e-9
# a radian) and the azimuth of a steady top by at most UNWRAP_TURN = 0.5 rad a step (to unwrap phi). Rounded down
# to one digit it is the model file's 1e-4 s at the default cases (the fast-precession one: 7e-5 s, its RK4 bound).
RK4_TARGET = 4e-9
SPIN_TURN = 0.0188
UNWRAP_TURN = 0.5


@dataclass(frozen=True)
class Scales:
    """Rates (rad/s) of a motion of the heavy top, over a nutation period, from the closed form ([T] T2-T3).

    Attributes
    ----------
    spin : float
        |Omega_b| = |I3 - I1| |omega3| / I1: the rate at which the transverse body rates turn in the body frame
        by themselves (Euler's equations, [T] R7; gravity adds a torque of the pendulum's rate, `pendulum`).
    omega : float
        |omega| at its largest: the body's turning rate.
    precession : float
        |phi_dot| at its largest.
    nutation : float
        2 pi / T_nut.
    transverse : float
        sqrt(omega1^2 + omega2^2) at its largest.
    pendulum : float
        sqrt(beta) = sqrt(2 M g h / I1): the rate of the gravity torque's effect.
    """

    spin: float
    omega: float
    precession: float
    nutation: float
    transverse: float
    pendulum: float

    @property
    def fastest(self) -> float:
        """The fastest rate (rad/s) of the state MuJoCo integrates (the azimuth's whirl near the vertical is not
        one)."""
        return max(self.spin, self.omega, self.nutation, self.pendulum)


def scales(top: HeavyTop, inertia_pivot: float, inertia_axial: float, spin: float, transverse0: float) -> Scales:
    """The `Scales` of the motion `top` ([T] T2-T3), its initial transverse body rate |omega_perp(0)| being
    `transverse0` (rad/s)."""
    w2, w1 = top.w_roots[1], top.w_roots[0]
    w = np.linspace(w2, w1, 257)
    # omega_perp^2 = theta_dot^2 + phi_dot^2 sin^2(theta) = alpha - beta u (energy, [T] T2) = k0 + beta w
    transverse = float(np.sqrt(max(transverse0**2 + top.beta * w1, 0.0)))
    return Scales(
        spin=abs(inertia_axial - inertia_pivot) * abs(spin) / inertia_pivot,
        omega=float(np.hypot(spin, transverse)),
        precession=float(np.max(np.abs(top.precession_rate_at_w(w)))),
        nutation=2 * np.pi / top.nutation_period,
        transverse=transverse,
        pendulum=float(np.sqrt(top.beta)),
    )


def momentum_scale(inertia_pivot: float, inertia_axial: float, mgh: float, transverse0: float, spin: float) -> float:
    """L_scale = sqrt(|L(0)|^2 + 2 I1 M g h) (kg m^2/s): the angular momentum at the start plus what a fall
    through the potential's amplitude gives ([T] T2); defined (> 0) for a top released at rest without spin."""
    return float(np.sqrt((inertia_pivot * transverse0) ** 2 + (inertia_axial * spin) ** 2 + 2 * inertia_pivot * mgh))


@dataclass(frozen=True)
class StepLimits:
    """The largest reference steps (s) of a run of the heavy top, by each rule of the comment on RK4_TARGET.

    Attributes
    ----------
    scales : Scales
        The rates of the motion.
    nutations : float
        The run's length in nutation periods.
    duration : float
        The run's length (s).
    r : float
        I1 |omega_perp|max / L_scale (at most 1).
    omega : float
        `Scales.fastest` (rad/s).
    limits : dict of str to float
        The step (s) each rule allows: "RK4 drift", "resolution", "azimuth unwrap" (inf unless steady).
    """

    scales: Scales
    nutations: float
    duration: float
    r: float
    omega: float
    limits: dict[str, float]

    @property
    def which(self) -> str:
        """The name of the rule that sets the step (the smallest limit)."""
        return min(self.limits, key=self.limits.get)

    @property
    def step(self) -> float:
        """The largest step (s) every rule allows."""
        return self.limits[self.which]

    def rule(self, rounded: float) -> str:
        """The rule in words, with its numbers and the step `rounded` (s) the scenario takes from it."""
        by_rk4, by_resolution, by_unwrap = self.limits.values()
        return (
            f"min((120 x {RK4_TARGET:g} / (r Omega^5 T))^(1/4), {SPIN_TURN:g} / Omega, {UNWRAP_TURN:g} / "
            f"|phi_dot| if steady) with r = I1 |omega_perp|max / L_scale = {self.r:.3g}, Omega = max(|omega|max, "
            f"|I3 - I1| |omega3| / I1, omega_nut, sqrt(beta)) = {self.omega:.4g} rad/s, T = {self.nutations:g} "
            f"T_nut = {self.duration:.4g} s: min({by_rk4:.4g}, {by_resolution:.4g}, {by_unwrap:.4g}) s "
            f"({self.which}), rounded down to one digit: {rounded:.1g} s"
        )


def step_limits(
    top: HeavyTop,
    inertia_pivot: float,
    inertia_axial: float,
    mgh: float,
    *,
    tilt: float,
    tilt_rate: float,
    precession: float,
    spin: float,
    nutations: float,
) -> StepLimits:
    """The largest RK4 steps (s) by each rule of the comment on RK4_TARGET, for a run of `nutations` nutation
    periods of the motion `top` ([T] T2-T3) from the initial state it was made from."""
    i1 = inertia_pivot
    transverse0 = float(np.hypot(tilt_rate, precession * np.sin(tilt)))
    sc = scales(top, i1, inertia_axial, spin, transverse0)
    r = min(1.0, i1 * sc.transverse / momentum_scale(i1, inertia_axial, mgh, transverse0, spin))
    omega = sc.fastest
    # phi is unwrapped only for a steady top (its precession rate is a slope); a nutating one's mean precession counts
    # whole turns from the prediction, and need not follow the azimuth's whirl near the vertical
    steady = tilt_rate == 0 and top.w_roots[0] - top.w_roots[1] < 1e-12
    duration = nutations * top.nutation_period
    by_rk4 = (120 * RK4_TARGET / (max(r, 1e-300) * omega**5 * duration)) ** 0.25
    by_resolution = SPIN_TURN / omega
    by_unwrap = UNWRAP_TURN / sc.precession if steady and sc.precession > 0 else np.inf
    limits = {"RK4 drift": by_rk4, "resolution": by_resolution, "azimuth unwrap": by_unwrap}
    return StepLimits(sc, nutations, duration, r, omega, limits)


def acceleration_bound(inertia_pivot: float, inertia_axial: float, mgh: float, spin: float, transverse: float) -> float:
    """An upper bound (rad/s^2) on the body-frame angular acceleration, ``|I1 - I3| |omega3| |omega_perp|max / I1
    + M g h / I1``: Euler's equations ([T] R7) with the gravity torque at its largest; `transverse` is
    |omega_perp|max (rad/s, `Scales.transverse`)."""
    return abs(inertia_pivot - inertia_axial) * abs(spin) * transverse / inertia_pivot + mgh / inertia_pivot


def roundoff_scales(
    top: HeavyTop,
    *,
    duration: float,
    nutations: float,
    precession_rate: float,
    tilt: float,
    falling: bool,
) -> dict[str, float]:
    """The float32 round-off scales of the heavy top's checks whose quantity is small against what float32 rounds.

    theta-min, theta-max and max-tilt-linear take the generic rule for a small angle: float32 keeps the axis to an
    absolute ~eps rad per step, its quaternion's numbers being O(1), a random walk of eps sqrt(N) rad over the run
    (measured on Warp and MJX float32 at spins of 1.7e3-9.2e3 rad/s, theta's extrema were off by 0.5-1.0
    eps sqrt(N) rad). Never below 1, the relative floor of any quantity. In units of one radian of that noise:

    * a rate read from an angle's advance over the run (mean-precession, the steady precession-rate) is as precise
      as the advance, |phi_dot| T rad, and phi is the azimuth of the axis, which the axis' noise moves by noise /
      sin(theta): scale 1 / (|phi_dot| T sin(theta)), theta where phi is read (the steady top's tilt; for the mean
      precession the family of extremes farther from its pole) (measured 1.0-1.7 eps sqrt(N) / (|phi_dot| T) on a
      looping and a slow steady top: a top spinning 2e5 times faster than it precesses moved 2.6e-3 rad in the
      run; a Warp census draw tilted 0.0257 rad, without the sin(theta), was 9.0e-2 off against a floor of
      4.6e-2, 20 units of eps sqrt(N) / (|phi_dot| T) where 1 / sin(theta) = 39);
    * the precession at a turning point, phi_dot = (b - a u) / (1 - u^2) ([T] T2), is a difference of terms of
      size |b| + |a u|, each known to float32's relative noise (a = I3 omega3 / I1 and b = p_phi / I1 are the
      spin's and the vertical momentum's): scale (|b| + |a u|) / |b - a u|, large where the top loops (b ~ a u).
      An upper bound: the dynamics keeps the two noises correlated, and on four looping tops the errors measured
      were 0.0002-0.13 of it, so a float32 census reports these checks unresolved more often than it must;
    * the nutation period is a phase's advance, 2 pi n_nut nutations of amplitude theta_max - theta_min: the
      axis' noise moves the phase by noise / amplitude (measured 0.13-0.22 of that; a fast top nutates by 1e-4
      rad, a few times the noise);
    * the falling top's growth rate is a slope of ln(theta) fitted from theta = 20 theta0 up, where the noise is
      1 / (20 theta0) of theta, over ln(5) of ln(theta).

    Parameters
    ----------
    top : HeavyTop
    duration, nutations : float
        The run's length: in s, and in nutation periods.
    precession_rate : float
        What the precession-rate check predicts (rad/s).
    tilt : float
        theta0 (rad).
    falling : bool
        Whether the tilt-growth-rate check runs.

    Returns
    -------
    dict of str to float
        Scale (>= 1, or inf) by check name, for the checks it applies to.
    """
    out: dict[str, float] = {}
    # where phi is read: the extremes farther from their pole (a steady top's theta-min = theta-max = its tilt)
    sin_theta = max(math.sin(float(top.theta_min)), math.sin(float(top.theta_max)))
    for name, value in (("mean-precession", top.mean_precession_rate), ("precession-rate", precession_rate)):
        rate = abs(float(value))
        if rate > 0:  # at a pole the azimuth is not defined at all: an infinite scale, unresolved on float32
            out[name] = max(1.0, 1.0 / (rate * duration * sin_theta)) if sin_theta > 0 else math.inf
    for name, u in (("precession-at-theta-min", top.roots[1]), ("precession-at-theta-max", top.roots[0])):
        difference = abs(top.b - top.a * u)
        if difference > 0:
            out[name] = max(1.0, (abs(top.b) + abs(top.a * u)) / difference)
    amplitude = float(top.theta_max - top.theta_min)
    if amplitude > 0:
        phase = 2 * math.pi * float(nutations)
        out["nutation-period"] = max(1.0, 1.0 / (amplitude * phase))
    if falling:
        out["tilt-growth-rate"] = max(1.0, 1.0 / (20 * float(tilt) * math.log(5.0)))
    return out
