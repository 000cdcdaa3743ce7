"""Closed forms for the gyrocompass: a fast rotor held horizontal by a gimbal free about the local vertical, on a
platform turning at a constant rate (the Earth, scaled).

Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2).

Conventions (docs/theory.md section 0, "Earth frames", and G1): local frame x = East, y = North, z = Up; the platform
turns at ``Omega (0, cos(lat), sin(lat))``; ``alpha`` is the azimuth of the spin axis e from North towards East;
``chi`` the rotor's spin angle about e, relative to the gimbal. ``inertia_axial`` (I_a) and
``inertia_transverse`` (I_t) are the rotor's principal moments about its centre of mass, which sits at the gimbal
centre; ``inertia_gimbal`` (I_g) is the gimbal's moment about the vertical. ``Omega_perp = Omega cos(lat)`` is the
platform rate's component perpendicular to the gimbal axis (G1: "in general Omega cos(lat) -> Omega_perp").

The exact hunting equation (docs/theory.md G1, from the Lagrangian; checked here against an independent numerical
Lagrangian in ``tests/test_gyrocompass_analytic.py``)::

    (I_t + I_g) alpha'' = -H Omega_perp sin(alpha) + I_t Omega_perp^2 sin(alpha) cos(alpha)
    H = I_a (chi' + Omega_perp cos(alpha))                     (conserved)

is a pendulum in the potential ``V(alpha) = -A cos(alpha) - (B/2) sin(alpha)^2`` (per unit I_t + I_g), with
``A = H Omega_perp / (I_t + I_g)`` and ``B = I_t Omega_perp^2 / (I_t + I_g)``: the spin axis hunts about North
(alpha = 0, for H Omega_perp > 0) at ``omega_g^2 = A - B`` for small amplitudes, with the period of any
amplitude by quadrature.

References
----------
[T] docs/theory.md, entry G1.
[H] Harter, lecture slides Unit 6 (seed 001): the gyrocompass "will seek true North ... hunting motion".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rigidbench import lazy

integrate = lazy.module("scipy.integrate")


def spin_momentum(inertia_axial: float, spin_rate: float, omega_perp: float, azimuth: float) -> float:
    """H = I_a (chi' + Omega_perp cos(alpha)) (kg m^2/s): the rotor's angular momentum along its spin axis, with
    chi' its spin relative to the gimbal ([T] G1; conserved: the bearing exerts no torque about the axis)."""
    return float(inertia_axial * (spin_rate + omega_perp * np.cos(azimuth)))


@dataclass(frozen=True)
class Gyrocompass:
    """The hunting of a gyrocompass about North ([T] G1).

    Attributes
    ----------
    inertia_transverse, inertia_gimbal : float
        I_t (rotor, about a transverse axis through its CM) and I_g (gimbal, about the vertical), kg m^2.
    spin_momentum : float
        H (kg m^2/s), `spin_momentum`; positive along the spin axis e.
    omega_perp : float
        Omega_perp = Omega cos(lat) (rad/s): the platform rate's component perpendicular to the gimbal axis.
    """

    inertia_transverse: float
    inertia_gimbal: float
    spin_momentum: float
    omega_perp: float

    @property
    def inertia_azimuth(self) -> float:
        """I_t + I_g (kg m^2): the moment about the gimbal axis that the hunting moves."""
        return self.inertia_transverse + self.inertia_gimbal

    @property
    def A(self) -> float:
        """A = H Omega_perp / (I_t + I_g) (1/s^2): the gyroscopic restoring term."""
        return self.spin_momentum * self.omega_perp / self.inertia_azimuth

    @property
    def B(self) -> float:
        """B = I_t Omega_perp^2 / (I_t + I_g) (1/s^2): the centrifugal-like term of the rotor's transverse moment."""
        return self.inertia_transverse * self.omega_perp**2 / self.inertia_azimuth

    @property
    def north_seeking(self) -> bool:
        """Whether alpha = 0 is a stable equilibrium: A > B, i.e. H Omega_perp > I_t Omega_perp^2."""
        return self.A > self.B

    @property
    def hunting_frequency(self) -> float:
        """omega_g = sqrt(A - B) = sqrt(Omega_perp (H - I_t Omega_perp) / (I_t + I_g)) (rad/s), small amplitudes.

        Raises
        ------
        ValueError
            If alpha = 0 is not stable (A <= B): no hunting about North.
        """
        if not self.north_seeking:
            raise ValueError(
                f"H = {self.spin_momentum:g} kg m^2/s, Omega_perp = {self.omega_perp:g} rad/s: A = {self.A:g} <= "
                f"B = {self.B:g} 1/s^2, North is not a stable equilibrium (needs H > I_t Omega_perp)"
            )
        return float(np.sqrt(self.A - self.B))

    @property
    def simple_frequency(self) -> float:
        """sqrt(H Omega_perp / (I_t + I_g)) (rad/s): the fast-rotor form of omega_g, off by ~I_t Omega_perp / (2 H)."""
        return float(np.sqrt(self.A))

    def acceleration(self, azimuth: np.ndarray) -> np.ndarray:
        """alpha'' (rad/s^2) of the exact hunting equation at `azimuth` (rad)."""
        s, c = np.sin(azimuth), np.cos(azimuth)
        return -self.A * s + self.B * s * c

    def potential(self, azimuth: np.ndarray) -> np.ndarray:
        """V(alpha) = -A cos(alpha) - (B/2) sin(alpha)^2 (1/s^2): alpha'' = -dV/dalpha."""
        return -self.A * np.cos(azimuth) - 0.5 * self.B * np.sin(azimuth) ** 2

    def turning_angle(self, azimuth0: float, rate0: float = 0.0) -> float:
        """Largest |alpha| (rad) of the hunting started at `azimuth0` (rad) with rate `rate0` (rad/s), from the first
        integral E = alpha'^2/2 + V(alpha): the root cos(alpha) of (B/2) c^2 - A c - (B/2 + E) = 0 in [-1, 1].

        Raises
        ------
        ValueError
            If the motion is not a hunting about North (it passes over alpha = pi).
        """
        a, b = self.A, self.B
        r2 = rate0 * rate0
        cos0 = np.cos(azimuth0)
        # E = r^2/2 + V(alpha0); the discriminant A^2 + 2 B (B/2 + E) = (A - B cos alpha0)^2 + B r^2, and
        # 1 - c = N / (A + sqrt(D)) with N = 2 sin^2(alpha0/2) (2 A - B cos alpha0) + r^2 + B r^2 / (sqrt(D) + A - B
        # cos alpha0): free of cancellation at small angles, where cos(alpha) -> 1 would lose alpha^2 to round-off.
        base = a - b * cos0
        root = float(np.sqrt(base * base + b * r2))
        half = np.sin(azimuth0 / 2) ** 2
        one_minus_c = (2 * half * (2 * a - b * cos0) + r2 + b * r2 / (root + base)) / (a + root)
        if not self.north_seeking or base <= 0 or not 0.0 <= one_minus_c < 2.0:
            raise ValueError(
                f"azimuth {azimuth0:g} rad at rate {rate0:g} rad/s passes over alpha = pi: no hunting about North"
            )
        if one_minus_c <= 1.0:
            return float(2 * np.arcsin(np.sqrt(0.5 * one_minus_c)))
        return float(np.arccos(1.0 - one_minus_c))

    def max_rate(self, amplitude: float) -> float:
        """Largest |alpha'| (rad/s) of the hunting of turning angle `amplitude` (rad): at alpha = 0 where B < A,
        sqrt(2 (V(amplitude) - V(0)))."""
        return float(np.sqrt(max(0.0, 2 * (float(self.potential(amplitude)) - float(self.potential(0.0))))))

    def period(self, amplitude: float) -> float:
        """Hunting period (s) at turning angle `amplitude` (rad), by quadrature ([T] G1).

        ``T = 4 int_0^a dalpha / sqrt(2 (V(a) - V(alpha)))``; with sin(alpha/2) = k sin(phi), k = sin(a/2), and
        ``V(a) - V(alpha) = (cos alpha - cos a) (A - (B/2)(cos alpha + cos a))``, the integrand is smooth:
        ``T = 4 int_0^{pi/2} dphi / (sqrt(1 - k^2 sin^2 phi) sqrt(A - (B/2)(cos alpha + cos a)))``. With B = 0 it is
        the pendulum's 4 K(k) / sqrt(A) ([T] O1).

        Raises
        ------
        ValueError
            If the amplitude is not in [0, pi) or North is not stable.
        """
        a = abs(float(amplitude))
        if not a < np.pi:
            raise ValueError(f"amplitude = {amplitude!r} rad is outside [0, pi)")
        self.hunting_frequency  # noqa: B018 - raises where North is not stable
        k = np.sin(a / 2)
        big_a, big_b, cos_a = self.A, self.B, np.cos(a)

        def integrand(phi: float) -> float:
            s = k * np.sin(phi)
            cos_alpha = 1 - 2 * s * s
            return 1.0 / (np.sqrt(1 - s * s) * np.sqrt(big_a - 0.5 * big_b * (cos_alpha + cos_a)))

        value, _err = integrate.quad(integrand, 0.0, np.pi / 2, epsabs=0.0, epsrel=1e-13, limit=200)
        return float(4 * value)

    def small_amplitude_shift(self, amplitude: float) -> float:
        """The leading relative period shift ((A - 4 B) / (A - B)) a^2 / 16 of turning angle a (rad): V's quartic
        term -(A - 4 B) alpha^4 / 24 against its quadratic (A - B) alpha^2 / 2, as for the pendulum (a^2/16, [T] O1)."""
        return float((self.A - 4 * self.B) / (self.A - self.B) * amplitude**2 / 16)

    def azimuth(self, t: np.ndarray, azimuth0: float, rate0: float = 0.0) -> np.ndarray:
        """alpha(t) (rad) of the exact hunting equation from alpha(0) = `azimuth0`, alpha'(0) = `rate0`
        (`trajectory`)."""
        return self.trajectory(t, azimuth0, rate0)[0]

    def trajectory(self, t: np.ndarray, azimuth0: float, rate0: float = 0.0) -> np.ndarray:
        """(alpha(t), alpha'(t)) (rad, rad/s), shape (2, len(t)), of the exact hunting equation from alpha(0) =
        `azimuth0`, alpha'(0) = `rate0`.

        Integrated with scipy's DOP853 at rtol = atol = 1e-12 of the amplitude: the equation has no closed form in
        elementary functions once B != 0; this is the theory's trajectory, not a simulation of the rigid bodies.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        scale = max(abs(azimuth0), abs(rate0) / self.hunting_frequency, 1e-300)
        end = float(t.max()) if t.size else 0.0
        if end <= 0:
            return np.stack([np.full(t.shape, float(azimuth0)), np.full(t.shape, float(rate0))])
        sol = integrate.solve_ivp(
            lambda _t, y: [y[1], float(self.acceleration(y[0]))],
            (0.0, end),
            [azimuth0, rate0],
            method="DOP853",
            rtol=1e-12,
            atol=1e-12 * scale,
            dense_output=True,
        )
        return sol.sol(t)


def momentum_along_axis(
    inertia_transverse: float,
    inertia_gimbal: float,
    momentum: float,
    omega: float,
    latitude: float,
    azimuth: np.ndarray,
    rate: np.ndarray,
) -> np.ndarray:
    """The gimbal's and rotor's angular momentum (kg m^2/s) along the platform's axis n, about the gimbal centre.

    ``H cos(lat) cos(alpha) + I_t Omega (1 - cos^2(lat) cos^2(alpha)) + I_g Omega - (I_t + I_g) alpha' sin(lat)``:
    the rotor's axial part H e.n, its transverse moment I_t times its angular velocity less the axial part along n,
    and the isotropic gimbal's I_g times its angular velocity along n (the gimbal turns at alpha' about -up, which
    has -sin(lat) along n). The platform's axis is a frictionless hinge: the platform's moment I_p times its rate
    plus this is conserved, so the platform's rate moves by minus the change of this over I_p.
    """
    azimuth, rate = np.asarray(azimuth, dtype=float), np.asarray(rate, dtype=float)
    cl, sl = np.cos(latitude), np.sin(latitude)
    c = np.cos(azimuth)
    return (
        momentum * cl * c
        + inertia_transverse * omega * (1 - cl * cl * c * c)
        + inertia_gimbal * omega
        - (inertia_transverse + inertia_gimbal) * rate * sl
    )


def platform_momentum_swing(
    inertia_transverse: float,
    inertia_gimbal: float,
    momentum: float,
    omega: float,
    latitude: float,
    amplitude: float,
    max_rate: float,
) -> float:
    """A bound (kg m^2/s) on how far the gimbal's and rotor's angular momentum along the platform axis n swings
    over a hunting of turning angle `amplitude` (rad) and largest rate `max_rate` (rad/s).

    Along n the gyro carries ``H cos(lat) cos(alpha) + I_t Omega (1 - cos^2(lat) cos^2(alpha)) + I_g Omega
    - (I_t + I_g) alpha' sin(lat)`` (rotor: H e.n plus I_t times its transverse rate along n; the gimbal
    isotropic; H = `momentum`). The platform's axis is a frictionless hinge, so the total along n is conserved and
    the platform's rate moves by at most this swing over its moment of inertia (`rigidbench.envs.gyrocompass`).
    """
    a = min(abs(amplitude), np.pi)
    cl, sl = np.cos(latitude), np.sin(latitude)
    axial = abs(momentum) * abs(cl) * (1 - np.cos(a))
    transverse = inertia_transverse * abs(omega) * cl * cl * np.sin(min(a, np.pi / 2)) ** 2
    tilt = 2 * (inertia_transverse + inertia_gimbal) * abs(sl) * abs(max_rate)
    return float(axial + transverse + tilt)


# ---------------------------------------------------------------------------------------------------------
# The compass as built: its moments and the platform axis' latitude; rates, round-off and sensitivity of a run
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Geometry:
    """The gyrocompass as compiled: moments (kg m^2) and the platform axis' latitude ([T] G1).

    Attributes
    ----------
    inertia_axial, inertia_transverse : float
        The rotor's moments about its spin axis and about a transverse axis (its CM).
    inertia_gimbal : float
        The gimbal's moment about its (vertical) hinge axis.
    inertia_platform : float
        The platform's moment about its axis n.
    latitude : float
        asin(n . up) (rad).
    horizontal : float
        |n - (n . up) up| = cos(lat): Omega_perp / Omega.
    north : float
        The gimbal angle (rad) at which the spin axis lies along the horizontal part of n: the equilibrium for H > 0.
    """

    inertia_axial: float
    inertia_transverse: float
    inertia_gimbal: float
    inertia_platform: float
    latitude: float
    horizontal: float
    north: float


def axes_geometry(platform_axis: np.ndarray, up: np.ndarray, spin0: np.ndarray) -> tuple[float, float, float]:
    """Latitude, horizontal fraction and North of the compass from its axes ([T] section 0, "Earth frames", G1).

    Parameters
    ----------
    platform_axis : ndarray, shape (3,)
        The platform's hinge axis n in the platform frame (any length).
    up : ndarray, shape (3,)
        The unit local vertical in the platform frame (the gimbal's hinge axis, pointing up).
    spin0 : ndarray, shape (3,)
        The rotor's unit spin axis at zero gimbal angle, in the platform frame.

    Returns
    -------
    latitude : float
        asin(n . up) (rad).
    horizontal : float
        |n_h| = cos(lat), n_h = n - (n . up) up.
    north : float
        The gimbal angle (rad, towards East = -up x spin0) at which the spin axis lies along n_h.
    """
    east0 = np.cross(-up, spin0)
    n = platform_axis / np.linalg.norm(platform_axis)  # the platform's axis in its own frame (East, North, Up)
    sin_lat = float(np.dot(n, up))
    n_h = n - sin_lat * up
    return (
        float(np.arcsin(np.clip(sin_lat, -1.0, 1.0))),
        float(np.linalg.norm(n_h)),
        float(np.arctan2(np.dot(n_h, east0), np.dot(n_h, spin0))),
    )


def fastest_rate(theory: Gyrocompass, amplitude: float) -> float:
    """The hunting's fastest rate (rad/s): omega_g, or the azimuth's rate through North if larger ([T] G1).

    Parameters
    ----------
    theory : Gyrocompass
        The closed form.
    amplitude : float
        The turning angle (rad).
    """
    return max(theory.hunting_frequency, theory.max_rate(amplitude))


def gyroscopic_roundoff(spin_rate: float, omega_perp: float, amplitude: float) -> float:
    """rho = eps |chi'| / (|Omega_perp| sin|a|): the relative double-precision error of a simulator's gyroscopic
    torque against the restoring torque H Omega_perp sin(a) of a hunting of turning angle a ([T] G1).

    A gyroscopic torque computed in world axes from a spin chi' far faster than the platform carries a round-off
    ~eps I chi'^2, against the restoring torque I_a chi' Omega_perp sin(a).

    Parameters
    ----------
    spin_rate : float
        chi' (rad/s).
    omega_perp : float
        Omega cos(lat) (rad/s).
    amplitude : float
        The turning angle a (rad).

    Returns
    -------
    float
        rho (dimensionless), inf where sin(a) = 0.
    """
    sine = math.sin(min(abs(amplitude), math.pi))
    return float(np.finfo(float).eps) * abs(spin_rate) / (abs(omega_perp) * sine) if sine > 0 else math.inf


def period_sensitivity(theory: Gyrocompass, amplitude: float) -> float:
    """S = |d ln T / d ln a|: the hunting period's sensitivity to the turning angle a ([T] G1), by a central
    difference of `Gyrocompass.period` over a +- 1e-4 a; ~a^2/8 small, ~5 at a = 3 (the separatrix at pi); 0 at
    a = 0.

    Parameters
    ----------
    theory : Gyrocompass
        The closed form.
    amplitude : float
        The turning angle a (rad).
    """
    da = 1e-4 * abs(amplitude)
    return (
        abs(math.log(theory.period(abs(amplitude) + da) / theory.period(abs(amplitude) - da)))
        / math.log((abs(amplitude) + da) / (abs(amplitude) - da))
        if da > 0
        else 0.0
    )
