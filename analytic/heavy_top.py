"""The heavy top's rates, reference step, largest acceleration and float32 round-off scales, from its closed form
(`rigidbench.analytic.tops.heavy_top`, docs/theory.md T2-T3); the scenario (`rigidbench.envs.heavy_top`) picks the
run's length and rounds the step. Pure numpy functions of SI values; nothing here imports mujoco (house rule 2).

Conventions (docs/theory.md section 0, as `rigidbench.analytic.tops`): ``inertia_pivot`` = I1 + M h^2 about the pivot
(R4) and ``inertia_axial`` = I3 (kg m^2); ``mgh`` = M g h (J); ``spin`` = omega3, every rate in rad/s; the initial
state (tilt, tilt_rate, precession, spin) as `tops.heavy_top` takes it. References: [W] Wilcox, *Modern
Introductory Mechanics Part II*, section 11.10 (seed 000); [T] docs/theory.md T2-T3 (heavy top), R7 (Euler).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rigidbench.analytic import tops

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


def scales(top: tops.HeavyTop, inertia_pivot: float, inertia_axial: float, spin: float, transverse0: float) -> Scales:
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
    top: tops.HeavyTop,
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
    top: tops.HeavyTop,
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
    top : tops.HeavyTop
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
