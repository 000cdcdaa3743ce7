"""Closed forms for spinning tops: torque-free symmetric and asymmetric rotors, the heavy (Lagrange) top.

Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2).

Conventions (docs/theory.md section 0): principal body axes 1, 2, 3; ``omega_body`` are body-frame components of
the angular velocity (rad/s); moments of inertia in kg m^2 about the stated point (the centre of mass for
free bodies, the pivot for the heavy top); z-x-z Euler angles phi, theta, psi (Goldstein = Wilcox section
11.7). scipy's elliptic functions take the parameter m = k^2.

References
----------
[W] Wilcox, *Modern Introductory Mechanics Part II*, ch. 11 (seed 000): sections 11.9 and 11.10.
[H] Harter, lecture slides Unit 6 and Harter & Kim, Am. J. Phys. 44, 1080 (1976), eqs (8)-(18) (seed 001).
[T] docs/theory.md, entries S1-S4 (symmetric), A1-A5 (asymmetric); the heavy top (T1-T7) is
`rigidbench.analytic.heavy_top`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigidbench import lazy

special = lazy.module("scipy.special")


# ---------------------------------------------------------------------------------------------------------
# Torque-free symmetric top (docs/theory.md S1-S4; Wilcox section 11.9, eqs 11.41-11.51)
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SymmetricTop:
    """Torque-free symmetric top (I1 = I2 = I_perp about the CM) from its initial body-frame angular velocity.

    Attributes
    ----------
    body_rate : float
        Omega_b = (I3 - I_perp) omega3 / I_perp (rad/s): rate at which omega circles the symmetry axis in the
        body frame, counter-clockwise seen from +e3 when positive (oblate, omega3 > 0). [W] eq. 11.42, [T] S1.
    amplitude : float
        A = sqrt(omega1^2 + omega2^2) (rad/s), the transverse part of omega, constant.
    phase : float
        delta (rad): omega1 = A cos(Omega_b t + delta), omega2 = A sin(Omega_b t + delta).
    omega3 : float
        Spin about the symmetry axis (rad/s), constant.
    alpha, beta : float
        Cone angles (rad) between omega and e3, and between L and e3 ([W] eqs 11.43-11.45, [T] S2).
    angular_momentum : float
        |L| (kg m^2/s).
    precession_rate : float
        phi_dot = |L| / I_perp (rad/s): rate of the symmetry axis about L ([T] S3).
    spin_rate : float
        psi_dot = -Omega_b (rad/s): spin relative to the line of nodes with space z along L ([T] S3).
    energy : float
        Kinetic energy (J).
    """

    inertia_perp: float
    inertia_axial: float
    body_rate: float
    amplitude: float
    phase: float
    omega3: float
    alpha: float
    beta: float
    angular_momentum: float
    precession_rate: float
    spin_rate: float
    energy: float

    def omega_body(self, t: np.ndarray) -> np.ndarray:
        """Body-frame angular velocity at times `t` (s), shape (len(t), 3). [W] eqs 11.41-11.42."""
        t = np.asarray(t, dtype=float)
        arg = self.body_rate * t + self.phase
        return np.stack(
            [self.amplitude * np.cos(arg), self.amplitude * np.sin(arg), np.full_like(t, self.omega3)], axis=-1
        )


def symmetric_top(inertia_perp: float, inertia_axial: float, omega_body: np.ndarray) -> SymmetricTop:
    """Solve the torque-free symmetric top.

    Parameters
    ----------
    inertia_perp : float
        I1 = I2 (kg m^2), transverse principal moment about the CM.
    inertia_axial : float
        I3 (kg m^2), moment about the symmetry axis.
    omega_body : array_like, shape (3,)
        Initial angular velocity in body principal axes (rad/s).
    """
    w1, w2, w3 = (float(x) for x in omega_body)
    i_p, i_3 = float(inertia_perp), float(inertia_axial)
    amplitude = float(np.hypot(w1, w2))
    L = float(np.sqrt((i_p * w1) ** 2 + (i_p * w2) ** 2 + (i_3 * w3) ** 2))
    body_rate = (i_3 - i_p) * w3 / i_p
    return SymmetricTop(
        inertia_perp=i_p,
        inertia_axial=i_3,
        body_rate=body_rate,
        amplitude=amplitude,
        phase=float(np.arctan2(w2, w1)),
        omega3=w3,
        alpha=float(np.arctan2(amplitude, w3)),
        beta=float(np.arctan2(i_p * amplitude, i_3 * w3)),
        angular_momentum=L,
        precession_rate=L / i_p,
        spin_rate=-body_rate,
        energy=0.5 * (i_p * amplitude**2 + i_3 * w3**2),
    )


# ---------------------------------------------------------------------------------------------------------
# Torque-free asymmetric top (docs/theory.md A1-A5; Harter & Kim eqs 10-18)
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class AsymmetricTop:
    """Exact Jacobi-elliptic solution of Euler's equations for I1 < I2 < I3 ([T] A2).

    Attributes
    ----------
    inertia : tuple of float
        (I1, I2, I3), kg m^2 about the CM.
    energy : float
        E = 1/2 sum I_i omega_i^2 (J).
    angular_momentum : float
        |L| (kg m^2/s).
    about_major : bool
        True when L^2 > 2 E I2: the polhode circles axis 3 (largest moment); else axis 1.
    m : float
        Elliptic parameter k^2.
    rate : float
        s (1/s): tau = s (t - t0).
    amplitudes : tuple of float
        Amplitudes (rad/s) multiplying (cn, sn, dn) [about_major] or (dn, sn, cn) [about minor], per axis.
    signs : tuple of float
        Sign of each component's elliptic function, fixed by the initial state.
    tau0 : float
        Elliptic argument at t = 0.
    period : float
        4 K(k) / s (s): period of omega_1 and omega_2 for the major-axis polhode, of omega_2 and omega_3
        for the minor-axis one; omega_2 = A sn(...) in both.
    reversal_time : float
        2 K(k) / s (s): time between successive sign changes of omega_2 (the flip time of [H] eq. 17b for a
        start near the intermediate axis).
    """

    inertia: tuple[float, float, float]
    energy: float
    angular_momentum: float
    about_major: bool
    m: float
    rate: float
    amplitudes: tuple[float, float, float]
    signs: tuple[float, float, float]
    tau0: float
    period: float
    reversal_time: float

    def omega_body(self, t: np.ndarray) -> np.ndarray:
        """Body-frame angular velocity at times `t` (s), shape (len(t), 3)."""
        tau = self.rate * np.asarray(t, dtype=float) + self.tau0
        sn, cn, dn, _ = special.ellipj(tau, self.m)
        funcs = (cn, sn, dn) if self.about_major else (dn, sn, cn)
        return np.stack([s * a * f for s, a, f in zip(self.signs, self.amplitudes, funcs, strict=True)], axis=-1)


def asymmetric_top(inertia: tuple[float, float, float], omega_body: np.ndarray) -> AsymmetricTop:
    """Solve the torque-free asymmetric top from its initial body-frame angular velocity.

    Parameters
    ----------
    inertia : (I1, I2, I3)
        Principal moments about the CM (kg m^2), strictly increasing.
    omega_body : array_like, shape (3,)
        Initial angular velocity in body principal axes (rad/s).

    Raises
    ------
    ValueError
        If the moments are not strictly increasing, or the state lies on the separatrix (L^2 = 2 E I2,
        k = 1, infinite period) to within 1e-12 relative.

    Notes
    -----
    Case L^2 > 2 E I2 ([T] A2): omega = (A1 cn, A2 sn, A3 dn), s = sqrt((I3-I2)(L^2-2EI1)/(I1 I2 I3)),
    k^2 = (I2-I1)(2EI3-L^2)/((I3-I2)(L^2-2EI1)). Case L^2 < 2 E I2: omega = (A1 dn, A2 sn, A3 cn),
    s = sqrt((I2-I1)(2EI3-L^2)/(I1 I2 I3)), k^2 = (I3-I2)(L^2-2EI1)/((I2-I1)(2EI3-L^2)).
    Signs: Euler's equations are invariant under flipping any two components, so with sigma_3 = sign(w3)
    (major) the consistent pattern is (+1, sigma_3, sigma_3); with sigma_1 = sign(w1) (minor) it is
    (sigma_1, sigma_1, +1). The phase tau0 = F(am, m) with am = atan2(sn, cn) read off the initial state.
    """
    i1, i2, i3 = (float(x) for x in inertia)
    if not i1 < i2 < i3:
        raise ValueError(f"inertia must satisfy I1 < I2 < I3, got {inertia}")
    w = np.asarray(omega_body, dtype=float)
    inertia_arr = np.array([i1, i2, i3])

    def gap(ref: float) -> float:
        """L^2 - 2 E I_ref = sum I_i (I_i - I_ref) w_i^2, summed without cancellation."""
        return float(np.sum(inertia_arr * (inertia_arr - ref) * w**2))

    two_e = float(np.sum(inertia_arr * w**2))
    l2 = float(np.sum((inertia_arr * w) ** 2))
    above_1, above_2, below_3 = gap(i1), gap(i2), -gap(i3)  # L^2 - 2EI1, L^2 - 2EI2, 2EI3 - L^2
    if abs(above_2) <= 1e-12 * l2:
        raise ValueError("the initial state lies on the separatrix L^2 = 2 E I2 (infinite period)")
    about_major = above_2 > 0
    a1 = np.sqrt(below_3 / (i1 * (i3 - i1)))
    a3 = np.sqrt(above_1 / (i3 * (i3 - i1)))
    if about_major:
        a2 = np.sqrt(below_3 / (i2 * (i3 - i2)))
        rate = np.sqrt((i3 - i2) * above_1 / (i1 * i2 * i3))
        m = (i2 - i1) * below_3 / ((i3 - i2) * above_1)
        m1 = (i3 - i1) * above_2 / ((i3 - i2) * above_1)  # 1 - m, without cancellation near the separatrix
        sigma = 1.0 if w[2] >= 0 else -1.0
        signs = (1.0, sigma, sigma)
        am = np.arctan2(w[1] / (signs[1] * a2), w[0] / a1)  # sn, cn
    else:
        a2 = np.sqrt(above_1 / (i2 * (i2 - i1)))
        rate = np.sqrt((i2 - i1) * below_3 / (i1 * i2 * i3))
        m = (i3 - i2) * above_1 / ((i2 - i1) * below_3)
        m1 = -(i3 - i1) * above_2 / ((i2 - i1) * below_3)
        sigma = 1.0 if w[0] >= 0 else -1.0
        signs = (sigma, sigma, 1.0)
        am = np.arctan2(w[1] / (signs[1] * a2), w[2] / a3)  # sn, cn
    k_quarter = special.ellipkm1(m1)
    return AsymmetricTop(
        inertia=(i1, i2, i3),
        energy=0.5 * two_e,
        angular_momentum=float(np.sqrt(l2)),
        about_major=bool(about_major),
        m=float(m),
        rate=float(rate),
        amplitudes=(float(a1), float(a2), float(a3)),
        signs=signs,
        tau0=float(special.ellipkinc(am, m)),
        period=float(4 * k_quarter / rate),
        reversal_time=float(2 * k_quarter / rate),
    )


def separatrix_sensitivity(inertia: tuple[float, float, float], omega_body: np.ndarray) -> float:
    """How much the elliptic solution's phase amplifies an error in the body rates near the separatrix ([T] A2, A3).

    Near the separatrix L^2 = 2 E I2 the period 4 K(k) / s grows like K ~ (1/2) ln(16 / k'^2), and k'^2 is
    proportional to the gap L^2 - 2 E I2 = sum I_i (I_i - I2) omega_i^2. A relative error eta of the body rates (each
    |d omega_i| <= eta |omega|, anywhere on the motion, where |omega_i| <= A_i, its amplitude) moves the gap by up to
    2 eta |omega| sum I_i |I_i - I2| A_i, i.e. ln k'^2 by up to eta times

        S = 2 |omega| sum_i I_i |I_i - I2| A_i / |L^2 - 2 E I2|,

    so K by eta S / 2, each period by 2 eta S in tau = s t, and omega(t) (whose slope in tau is at most its
    amplitude) by ~2 n eta S |omega| after n periods. S >= 2; S ~ L^2 / |L^2 - 2 E I2| for a spin tilted off the
    intermediate axis of a body with distinct moments, smaller for a slender one (I1 << I2 ~ I3), whose gap is
    small in every state but insensitive to the rates.

    Parameters
    ----------
    inertia : (I1, I2, I3), kg m^2, strictly increasing
    omega_body : array_like, shape (3,)
        Body rates (rad/s) at any instant of the motion.

    Raises
    ------
    ValueError
        As `asymmetric_top` (moments not increasing, or on the separatrix).
    """
    top = asymmetric_top(inertia, omega_body)
    i = np.asarray(top.inertia)
    w = np.asarray(omega_body, dtype=float)
    gap = abs(float(np.sum(i * (i - i[1]) * w**2)))
    return float(2 * np.linalg.norm(w) * np.sum(i * np.abs(i - i[1]) * np.asarray(top.amplitudes)) / gap)


def flip_time(inertia: tuple[float, float, float], spin: float, tilt: float) -> float:
    """Harter-Kim reversal time for omega(0) = W (0, cos eps, sin eps) ([H] eqs 13-18, [T] A3).

    T_rev = (2/W) sqrt(I1 I2 I3 / ((I3-I2)(I2(I2-I1) cos^2 eps + I3(I3-I1) sin^2 eps))) K(k), with
    k^2 = I2(I2-I1) cos^2 eps / (I2(I2-I1) cos^2 eps + I3(I3-I1) sin^2 eps) (eq. 15 = 18a).

    Parameters
    ----------
    inertia : (I1, I2, I3), kg m^2
    spin : float
        W (rad/s).
    tilt : float
        eps (rad), the tilt of omega from axis 2 toward axis 3.
    """
    i1, i2, i3 = inertia
    c2, s2 = np.cos(tilt) ** 2, np.sin(tilt) ** 2
    denom = i2 * (i2 - i1) * c2 + i3 * (i3 - i1) * s2
    m1 = i3 * (i3 - i1) * s2 / denom  # 1 - k^2, formed directly: k -> 1 as eps -> 0
    return float(2 / spin * np.sqrt(i1 * i2 * i3 / ((i3 - i2) * denom)) * special.ellipkm1(m1))


def intermediate_axis_growth_rate(inertia: tuple[float, float, float], spin: float) -> float:
    """lambda = W sqrt((I2-I1)(I3-I2)/(I1 I3)) (1/s): exponential growth about axis 2 ([T] A4)."""
    i1, i2, i3 = inertia
    return float(spin * np.sqrt((i2 - i1) * (i3 - i2) / (i1 * i3)))


# The heavy (Lagrange) top's closed forms live in `rigidbench.analytic.heavy_top` (issue 34: a reader of the heavy top
# reads no torque-free tops); their old names here stay importable.
from rigidbench.analytic.heavy_top import (  # noqa: E402, F401
    HeavyTop,
    falling_growth_rate,
    heavy_top,
    sleeping_max_tilt,
    sleeping_threshold,
    steady_precession_rates,
)
