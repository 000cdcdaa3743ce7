"""A body about a fixed centre under central power-law forces: apsidal angles, stability, the Runge-Lenz vector and
the pericentre advance of a perturbed Kepler orbit.

Pure numpy/scipy (house rule 2), from docs/theory.md K2, K5 and K6 (Wilcox, *Modern Introductory Mechanics* Part II,
sections 8.3, 8.6 and 8.7). Conventions: a body of mass ``mu`` (the reduced mass of a pair; here the centre is fixed)
feels the radial force ``F(r) = -sum_i k_i / r^n_i`` (``k_i > 0`` attracts; N m^n); its angular momentum about the
centre is ``l`` (kg m^2/s) and ``u = 1 / r``. Binet's orbit equation (Wilcox eq. 8.128)::

    u'' + u = (mu / l^2) sum_i k_i u^(n_i - 2)       (' = d/dphi)

Closed forms:

- ``apsidal_angle_first_order(n)``: pi / sqrt(3 - n), the near-circular apsidal angle (K5);
- ``apsidal_angle_second_order(n, e)``: its Lindstedt correction, pi / sqrt(3 - n) (1 + (n - 2)(n + 1) e^2 / 24):
  the term that sets the first-order check's tolerance, zero at n = 2 and n = -1 whose orbits close (Bertrand);
- ``unstable_growth(mu, k, n, l)``: for n > 3 the circular radius r* of angular momentum l and the e-folding rate
  of a small radial offset, lambda = sqrt((n - 3) k / (mu r*^(n + 1))) (K5, Wilcox eqs 8.132-8.137);
- ``perihelion_advance(mu, k, k4, l, e)``: for F = -k / r^2 - k4 / r^4 the advance per orbit 2 pi eps,
  eps = mu^2 k k4 / l^4 (= 6 pi GM / (c^2 a (1 - e^2)) for k4 = 3 k h^2 / c^2, K6), and its second-order term
  2 pi eps^2 (5/2 + 5 e^2 / 12);
- ``runge_lenz(mu, k, r, v)``: A = p x L - mu k r_hat, constant for the inverse square (K2, eq. 8.64).

The reference the closed forms are tested against, and the exact values the scenario's sharp checks use, come from
integrating the orbit equation at rtol 1e-13 (`apsides`, `trajectory`): a numerical solution of the theory, not
of the simulator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

# The ODE reference's tolerances: DOP853 (8th order) at rtol 1e-13 keeps the apsidal angle and the orbit to ~1e-12,
# four decades below the simulator errors the scenario's checks allow.
RTOL = 1e-13
ATOL = 1e-15


@dataclass(frozen=True)
class Law:
    """The radial force ``F(r) = -sum_i k_i / r^n_i`` (N): strengths ``k`` (N m^n, > 0 attracts), exponents ``n``."""

    k: tuple[float, ...]
    n: tuple[float, ...]

    def force(self, r: ArrayLike) -> np.ndarray:
        """The radial force (N) at distance r (m); negative attracts."""
        r = np.asarray(r, dtype=float)
        return -sum(k * r ** (-n) for k, n in zip(self.k, self.n, strict=True))

    def potential(self, r: ArrayLike) -> np.ndarray:
        """U(r) (J): -k r^(1 - n) / (n - 1) per term, k ln r at n = 1 (U' = -F)."""
        r = np.asarray(r, dtype=float)
        return sum(
            k * np.log(r) if n == 1 else -k * r ** (1 - n) / (n - 1) for k, n in zip(self.k, self.n, strict=True)
        )


def circular_speed(mu: float, law: Law, r: float) -> float:
    """The speed (m/s) of the circular orbit of radius r: mu v^2 / r = -F(r)."""
    f = -float(law.force(r))
    if f <= 0:
        raise ValueError(f"no circular orbit at r = {r:g} m: the force there does not attract (F = {-f:g} N)")
    return math.sqrt(f * r / mu)


@dataclass(frozen=True)
class Apsides:
    """From an apsis at ``r0`` to the next: the azimuth swept (``angle``, rad), the time taken (``time``, s), the
    other apsis ``r1`` (m), and the eccentricity ``(r_max - r_min) / (r_max + r_min)``."""

    r0: float
    r1: float
    angle: float
    time: float

    @property
    def eccentricity(self) -> float:
        return abs(self.r1 - self.r0) / (self.r1 + self.r0)


def apsides(mu: float, law: Law, r0: float, ell: float) -> Apsides:
    """Integrate Binet's equation from the apsis r0 (u' = 0) to the next apsis (module docstring).

    The exact apsidal angle of an orbit of any eccentricity (the closed forms are its limits), and the time
    dt/dphi = mu / (l u^2) (Kepler's second law) to it.

    Raises
    ------
    ValueError
        If no next apsis comes within 100 turns (an unbound orbit or a circle).
    """
    c = mu / (ell * ell)

    def rhs(phi: float, y: np.ndarray) -> list[float]:
        u, du, _ = y
        return [du, -u + c * sum(k * u ** (n - 2) for k, n in zip(law.k, law.n, strict=True)), mu / (ell * u * u)]

    def apsis(phi: float, y: np.ndarray) -> float:
        return y[1]

    from scipy.integrate import solve_ivp  # here, not at import: listing the scenarios must not load scipy

    apsis.terminal = True
    u0 = 1.0 / r0
    # Leave the start's own u' = 0 before looking for the next one.
    first = solve_ivp(rhs, (0.0, 1e-3), [u0, 0.0, 0.0], method="DOP853", rtol=RTOL, atol=ATOL * u0)
    sol = solve_ivp(
        rhs, (1e-3, 200 * math.pi), first.y[:, -1], method="DOP853", rtol=RTOL, atol=ATOL * u0, events=apsis
    )
    if not sol.t_events[0].size:
        raise ValueError(f"no apsis after r0 = {r0:g} m within 100 turns (unbound or circular orbit)")
    phi, (u1, _, t1) = float(sol.t_events[0][0]), sol.y_events[0][0]
    return Apsides(r0, 1.0 / float(u1), phi, float(t1))


def apsidal_angle_first_order(n: float) -> float:
    """pi / sqrt(3 - n) (rad): the apsidal angle of a near-circular orbit in F = -k / r^n (K5)."""
    if n >= 3:
        raise ValueError(f"exponent n = {n:g}: circular orbits are unstable for n >= 3 (K5), no apsidal angle")
    return math.pi / math.sqrt(3 - n)


def apsidal_angle_second_order(n: float, e: float) -> float:
    """pi / sqrt(3 - n) (1 + (n - 2)(n + 1) e^2 / 24) (rad): the apsidal angle to second order in e.

    Lindstedt-Poincare on Binet's equation with u = u0 (1 + x): x'' + w0^2 x + a2 x^2 + a3 x^3 = 0, w0^2 = 3 - n,
    a2 = -m (m - 1) / 2, a3 = -m (m - 1)(m - 2) / 6 (m = n - 2), whose frequency is w0 + (3 a3 / (8 w0) -
    5 a2^2 / (12 w0^3)) A^2 (Nayfeh, *Perturbation Methods* 4.1.4); A = e + O(e^3) for e = (r_max - r_min) /
    (r_max + r_min). The bracket reduces to -(n - 2)(n + 1) / 24.
    """
    return apsidal_angle_first_order(n) * (1 + (n - 2) * (n + 1) * e * e / 24)


def unstable_growth(mu: float, k: float, n: float, ell: float) -> tuple[float, float]:
    """The circular radius r* (m) of angular momentum l in F = -k / r^n, and, for n > 3, the rate (1/s) at which a
    small radial offset grows: mu d''r = (n - 3) k / r*^(n + 1) dr, so dr(t) = dr(0) cosh(lambda t) from rest.

    Raises
    ------
    ValueError
        If n <= 3 (the circular orbit is stable, K5) or k <= 0.
    """
    if n <= 3 or k <= 0:
        raise ValueError(f"n = {n:g}, k = {k:g}: a growing offset needs an attraction (k > 0) with n > 3 (K5)")
    r_star = (ell * ell / (mu * k)) ** (1 / (3 - n))
    return r_star, math.sqrt((n - 3) * k / (mu * r_star ** (n + 1)))


def perihelion_advance(mu: float, k: float, k4: float, ell: float, e: float) -> tuple[float, float]:
    """The pericentre's advance per orbit (rad) in F = -k / r^2 - k4 / r^4, first order, and the second-order term.

    Binet: u'' + u = A + B u^2, A = mu k / l^2 = 1 / p, B = mu k4 / l^2 (GR: A = GM / h^2, B = 3 GM / c^2). The
    first order is 2 pi A B = 2 pi eps (K6: 6 pi GM / (c^2 a (1 - e^2))). About the circular u0 = A + B u0^2,
    x'' + (1 - 2 beta) x - beta x^2 = 0 with beta = B u0 = eps (1 + eps + ...), and Lindstedt's frequency gives
    2 pi / w - 2 pi = 2 pi (beta + 3 beta^2 / 2 + 5 beta^2 e^2 / 12) + O(eps^3), so the second-order term is
    2 pi eps^2 (5/2 + 5 e^2 / 12).
    """
    eps = mu * mu * k * k4 / ell**4
    return 2 * math.pi * eps, 2 * math.pi * eps * eps * (2.5 + 5 * e * e / 12)


def runge_lenz(mu: float, k: float, r: ArrayLike, v: ArrayLike) -> np.ndarray:
    """A = p x L - mu k r_hat (kg^2 m^3 / s^2), rows of r, v (n, 3); |A| = mu k e (K2, Wilcox eqs 8.64, 8.77)."""
    r, v = np.atleast_2d(np.asarray(r, dtype=float)), np.atleast_2d(np.asarray(v, dtype=float))
    p = mu * v
    big_l = np.cross(r, p)
    return np.cross(p, big_l) - mu * k * r / np.linalg.norm(r, axis=1)[:, None]


def trajectory(mu: float, law: Law, r0: ArrayLike, v0: ArrayLike, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity (m, m/s), shape (len(t), 3), of the orbit from r0, v0 at t = 0: the equations of
    motion integrated at rtol 1e-13 (DOP853), the reference trajectory where no closed form exists (n != 2, -1)."""
    from scipy.integrate import solve_ivp  # here, not at import (`apsides`)

    t = np.asarray(t, dtype=float)
    r0, v0 = np.asarray(r0, dtype=float), np.asarray(v0, dtype=float)
    scale = float(np.linalg.norm(r0))

    def rhs(_: float, y: np.ndarray) -> np.ndarray:
        r = y[:3]
        d = math.sqrt(r @ r)
        return np.concatenate([y[3:], float(law.force(d)) / (mu * d) * r])

    sol = solve_ivp(
        rhs,
        (0.0, float(t[-1])),
        np.concatenate([r0, v0]),
        method="DOP853",
        rtol=RTOL,
        atol=ATOL * scale,
        t_eval=t,
    )
    if not sol.success:
        raise ValueError(f"the reference orbit failed: {sol.message}")
    return sol.y[:3].T, sol.y[3:].T
