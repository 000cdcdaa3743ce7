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
[T] docs/theory.md, entries S1-S4 (symmetric), A1-A5 (asymmetric), T1-T7 (heavy top).
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
