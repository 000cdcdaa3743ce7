"""Two bodies under a central force, in the LAB and CM views: the Kepler and Hooke orbits.

Pure numpy closed forms (house rule 2), from docs/theory.md section 10 (Wilcox, *Modern Introductory Mechanics* Part II,
chapter 8; Harter, seed 001, "Ptolemaic vs Copernican views" and the CoulIt pictures). Conventions (docs/theory.md K1):

- masses ``m1``, ``m2``, ``M = m1 + m2``, reduced mass ``mu = m1 m2 / M``;
- relative coordinate ``r = r1 - r2`` (from body 2 to body 1), CM ``R = (m1 r1 + m2 r2) / M`` moving uniformly;
- CM-frame positions ``r1' = (m2 / M) r`` and ``r2' = -(m1 / M) r``: mass-scaled copies of the relative orbit
  (docs/theory.md K3);
- ``kepler``: potential ``U = -k / r`` (k > 0, attraction; N m^2); ``hooke``: ``U = 1/2 k r^2`` (k > 0; N/m),
  the zero-length spring between the two centres.

Every quantity is in SI units; vectors are 3-vectors in the world (LAB) frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

# Newton iterations on Kepler's equation: from psi = M + e sin M the error squares each time for e <= 0.95, so 40
# is far more than the ~8 that reach round-off; the loop stops early once every correction is below 1e-15 rad.
_KEPLER_ITERATIONS = 40


def reduced_mass(m1: float, m2: float) -> float:
    """mu = m1 m2 / (m1 + m2) (kg), docs/theory.md K1 (Wilcox eq. 8.39)."""
    return m1 * m2 / (m1 + m2)


def apsidal_angle(exponent: float) -> float:
    """Apsidal angle (rad, pericentre to apocentre) of a near-circular orbit in a force ``F = -k / r^n``.

    ``pi / sqrt(3 - n)`` (docs/theory.md K5 [DONE]; the stability condition n < 3 is Wilcox section 8.7, eqs
    8.132-8.137). Exact for every eccentricity at n = 2 (Kepler: pi) and n = -1 (Hooke: pi / 2), whose orbits close
    (Bertrand's theorem); for other n it is the limit e -> 0.

    Raises
    ------
    ValueError
        If ``n >= 3``: no stable circular orbit, so no apsides.
    """
    if not exponent < 3:
        raise ValueError(
            f"force exponent n = {exponent:g}: circular orbits are stable only for n < 3 (docs/theory.md K5)"
        )
    return float(np.pi / np.sqrt(3.0 - exponent))


@dataclass(frozen=True)
class Orbit:
    """A bound relative orbit r(t) of two bodies, and the closed forms the scenario checks.

    Attributes
    ----------
    law : {"kepler", "hooke"}
    mu : float
        Reduced mass (kg).
    k : float
        Strength: N m^2 (kepler, U = -k/r) or N/m (hooke, U = k r^2 / 2).
    r0, v0 : ndarray, shape (3,)
        Relative position and velocity at t = 0 (m, m/s).
    energy : float
        E = mu v^2 / 2 + U(r) (J), conserved.
    momentum : ndarray, shape (3,)
        L = mu r x v (kg m^2/s), conserved.
    eccentricity, semi_major, semi_minor : float
        Of the relative orbit (1, m, m): a Kepler ellipse with a focus at r = 0, a Hooke ellipse centred on it.
    period : float
        s: ``2 pi sqrt(mu a^3 / k)`` (K2, Kepler III) or ``2 pi sqrt(mu / k)`` (K3, Hooke).
    exponent : float
        n of ``F = -k / r^n``: 2 (kepler) or -1 (hooke), for `apsidal_angle`.
    apse : ndarray, shape (3,)
        Unit vector along the major axis: towards the pericentre (kepler; the Runge-Lenz vector's direction, K2)
        or towards the point of largest r (hooke); r0's direction for a circle.
    """

    law: str
    mu: float
    k: float
    r0: np.ndarray
    v0: np.ndarray
    energy: float
    momentum: np.ndarray
    eccentricity: float
    semi_major: float
    semi_minor: float
    period: float
    exponent: float
    apse: np.ndarray

    @property
    def apsidal_angle(self) -> float:
        """Angle (rad) swept from a pericentre to the next apocentre (K5): pi (kepler), pi / 2 (hooke)."""
        return apsidal_angle(self.exponent)

    def potential(self, distance: ArrayLike) -> np.ndarray:
        """U(r) (J) at relative distance(s) r (m)."""
        r = np.asarray(distance, dtype=float)
        return -self.k / r if self.law == "kepler" else 0.5 * self.k * r * r

    def mean_kinetic_and_potential(self) -> tuple[float, float]:
        """Time averages over a period (J): ``<T> = -E, <U> = 2E`` (kepler) and ``<T> = <U> = E/2`` (hooke).

        docs/theory.md K4 (Wilcox section 8.8, eq. 8.148; the virial theorem 2 <T> = <r . grad U> = p <U> for
        U ~ r^p, p = -1 and 2), combined with <T> + <U> = E.
        """
        if self.law == "kepler":
            return -self.energy, 2.0 * self.energy
        return 0.5 * self.energy, 0.5 * self.energy

    def position(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """r(t) and v(t) (m, m/s), shape (len(t), 3), from the state at t = 0.

        kepler: Kepler's equation ``n t = psi - e sin psi`` (K2, Wilcox eq. 8.118) solved by Newton's method, then
        ``r = a (cos psi - e) p + b sin psi q`` with p the apse and q = L x p / |L| (the perifocal frame).
        hooke: ``r = r0 cos(w t) + (v0 / w) sin(w t)``, ``w = sqrt(k / mu)`` (the isotropic oscillator).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self.law == "hooke":
            w = np.sqrt(self.k / self.mu)
            c, s = np.cos(w * t)[:, None], np.sin(w * t)[:, None]
            return self.r0 * c + self.v0 / w * s, -self.r0 * w * s + self.v0 * c
        a, e, b = self.semi_major, self.eccentricity, self.semi_minor
        p = self.apse
        q = np.cross(self.momentum, p)
        q /= np.linalg.norm(q)
        n = 2.0 * np.pi / self.period
        x0, y0 = float(self.r0 @ p), float(self.r0 @ q)
        psi0 = np.arctan2(y0 / b, x0 / a + e)  # eccentric anomaly at t = 0 (x = a (cos psi - e), y = b sin psi)
        anomaly = psi0 - e * np.sin(psi0) + n * t  # mean anomaly
        psi = anomaly + e * np.sin(anomaly)
        for _ in range(_KEPLER_ITERATIONS):
            step = (psi - e * np.sin(psi) - anomaly) / (1.0 - e * np.cos(psi))
            psi -= step
            if np.all(np.abs(step) < 1e-15 * np.maximum(1.0, np.abs(psi))):
                break
        cos_psi, sin_psi = np.cos(psi)[:, None], np.sin(psi)[:, None]
        rate = (n / (1.0 - e * np.cos(psi)))[:, None]  # d psi / dt
        r = a * (cos_psi - e) * p + b * sin_psi * q
        v = rate * (-a * sin_psi * p + b * cos_psi * q)
        return r, v


def kepler_orbit(mu: float, k: float, r0: ArrayLike, v0: ArrayLike) -> Orbit:
    """The bound Kepler orbit (U = -k/r) of relative state (r0, v0): docs/theory.md K2.

    ``e = sqrt(1 + 2 E l^2 / (mu k^2))`` (Wilcox eq. 8.78), ``a = -k / (2E)``, ``b = a sqrt(1 - e^2)``,
    ``T = 2 pi sqrt(mu a^3 / k)``; the pericentre lies along the Runge-Lenz vector ``A = p x L - mu k r_hat``
    (eqs 8.64, 8.77).

    Raises
    ------
    ValueError
        If the orbit is not bound (E >= 0: a parabola or hyperbola) or k <= 0.
    """
    r0, v0 = np.asarray(r0, dtype=float), np.asarray(v0, dtype=float)
    if not k > 0:
        raise ValueError(f"k = {k:g} N m^2: an attractive inverse-square force needs k > 0")
    dist = float(np.linalg.norm(r0))
    energy = 0.5 * mu * float(v0 @ v0) - k / dist
    if not energy < 0:
        raise ValueError(f"E = {energy:.6g} J >= 0: the Kepler orbit is unbound (docs/theory.md K2 needs E < 0)")
    momentum = mu * np.cross(r0, v0)
    ell2 = float(momentum @ momentum)
    e = float(np.sqrt(max(0.0, 1.0 + 2.0 * energy * ell2 / (mu * k * k))))
    a = -k / (2.0 * energy)
    runge_lenz = np.cross(mu * v0, momentum) - mu * k * r0 / dist
    norm = float(np.linalg.norm(runge_lenz))
    apse = runge_lenz / norm if norm > 1e-12 * mu * k else r0 / dist
    return Orbit(
        "kepler",
        mu,
        k,
        r0,
        v0,
        energy,
        momentum,
        e,
        a,
        a * np.sqrt(1.0 - e * e),
        float(2.0 * np.pi * np.sqrt(mu * a**3 / k)),
        2.0,
        apse,
    )


def hooke_orbit(mu: float, k: float, r0: ArrayLike, v0: ArrayLike) -> Orbit:
    """The orbit of a zero-length spring (U = k r^2 / 2) from relative state (r0, v0): docs/theory.md K3 (Hooke).

    ``r(t) = r0 cos(w t) + (v0 / w) sin(w t)``, ``w = sqrt(k / mu)``: an ellipse centred on r = 0 whose semi-axes
    are the square roots of the eigenvalues of ``r0 r0^T + (v0/w)(v0/w)^T``; period ``2 pi sqrt(mu / k)``.

    Raises
    ------
    ValueError
        If k <= 0.
    """
    r0, v0 = np.asarray(r0, dtype=float), np.asarray(v0, dtype=float)
    if not k > 0:
        raise ValueError(f"k = {k:g} N/m: a spring needs k > 0")
    w = np.sqrt(k / mu)
    u = v0 / w
    values, vectors = np.linalg.eigh(np.outer(r0, r0) + np.outer(u, u))
    a, b = float(np.sqrt(max(values[2], 0.0))), float(np.sqrt(max(values[1], 0.0)))
    return Orbit(
        "hooke",
        mu,
        k,
        r0,
        v0,
        0.5 * mu * float(v0 @ v0) + 0.5 * k * float(r0 @ r0),
        mu * np.cross(r0, v0),
        float(np.sqrt(max(0.0, 1.0 - (b / a) ** 2))),
        a,
        b,
        float(2.0 * np.pi / w),
        -1.0,
        vectors[:, 2] if a > b * (1 + 1e-12) else r0 / np.linalg.norm(r0),
    )


@dataclass(frozen=True)
class BodyOrbit:
    """One body's orbit about the CM: a mass-scaled copy of the relative orbit (docs/theory.md K3).

    Attributes
    ----------
    scale : float
        r_i' = scale * r: ``m2 / M`` for body 1, ``-m1 / M`` for body 2.
    semi_major, semi_minor : float
        ``a_i = (mu / m_i) a`` and ``b_i = (mu / m_i) b`` (m), K3 ``a_i m_i = a mu``.
    eccentricity, period : float
        The relative orbit's: the copies have the same shape and period.
    energy : float
        ``E_i = (mu / m_i) E`` (J) with the one-body potential of K3 [DONE]: ``U_i = -k_i / r_i'``,
        ``k_i = k (m_j / M)^2`` (kepler) or ``U_i = k_i r_i'^2 / 2``, ``k_i = k M / m_j`` (hooke).
    k : float
        That one-body strength k_i.
    """

    scale: float
    semi_major: float
    semi_minor: float
    eccentricity: float
    period: float
    energy: float
    k: float


def body_orbits(m1: float, m2: float, orbit: Orbit) -> tuple[BodyOrbit, BodyOrbit]:
    """The two CM-frame orbits as mass-scaled copies of `orbit` (docs/theory.md K1, K3)."""
    total = m1 + m2
    out = []
    for mi, mj, sign in ((m1, m2, 1.0), (m2, m1, -1.0)):
        share = orbit.mu / mi  # = m_j / M
        k_i = orbit.k * (mj / total) ** 2 if orbit.law == "kepler" else orbit.k * total / mj
        out.append(
            BodyOrbit(
                sign * share,
                share * orbit.semi_major,
                share * orbit.semi_minor,
                orbit.eccentricity,
                orbit.period,
                share * orbit.energy,
                k_i,
            )
        )
    return out[0], out[1]


def body_energy(mass: float, body: BodyOrbit, law: str, r_cm: np.ndarray, v_cm: np.ndarray) -> np.ndarray:
    """E_i(t) = m_i v_i'^2 / 2 + U_i(r_i') (J) of one body from its CM-frame positions and velocities, shape (n, 3)
    (docs/theory.md K3 [DONE]; conserved, and equal to (mu / m_i) E)."""
    r = np.sqrt(np.einsum("ij,ij->i", r_cm, r_cm))
    u = -body.k / r if law == "kepler" else 0.5 * body.k * r * r
    return 0.5 * mass * np.einsum("ij,ij->i", v_cm, v_cm) + u


def launch(law: str, mu: float, k: float, separation: float, speed_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Relative state (r0, v0) at an apsis: r0 = separation along +x, v0 along +y at ``speed_ratio`` times the
    circular speed there, ``sqrt(k / (mu r0))`` (kepler) or ``r0 sqrt(k / mu)`` (hooke).

    kepler: e = |s^2 - 1|, bound iff s < sqrt(2) (E = k (s^2 / 2 - 1) / r0); s > 1 starts at the pericentre, s < 1
    at the apocentre. hooke: semi-axes r0 and s r0.
    """
    circular = np.sqrt(k / (mu * separation)) if law == "kepler" else separation * np.sqrt(k / mu)
    return np.array([separation, 0.0, 0.0]), np.array([0.0, speed_ratio * circular, 0.0])


def launch_eccentricity(law: str, speed_ratio: float) -> float:
    """e of the orbit `launch` starts: ``|s^2 - 1|`` (kepler), ``sqrt(1 - min(s, 1/s)^2)`` (hooke)."""
    s = float(speed_ratio)
    if law == "kepler":
        return abs(s * s - 1.0)
    return float(np.sqrt(1.0 - min(s, 1.0 / s) ** 2))


def launch_pericentre(mu: float, k: float, separation: float, speed_ratio: float) -> tuple[float, float]:
    """Pericentre distance r_p (m) and speed v_p (m/s) of the Kepler orbit `launch` starts (docs/theory.md K2).

    ``r0`` is the pericentre for s >= 1 (speed s v_c there, v_c = sqrt(k / (mu r0))); the apocentre for s < 1,
    with ``r_p = r0 s^2 / (2 - s^2)``; ``v_p = s v_c r0 / r_p`` (angular momentum). r_p / v_p (s) is the orbit's
    fastest time scale.

    Parameters
    ----------
    mu : float
        Reduced mass (kg).
    k : float
        Strength of the attraction U = -k / r (N m^2), > 0.
    separation : float
        r0 (m), the launch apsis.
    speed_ratio : float
        s, the launch speed over the circular speed at r0; bound for s < sqrt(2).

    Returns
    -------
    r_p, v_p : float
    """
    r0, s = separation, speed_ratio
    circular = math.sqrt(k / (mu * r0))
    r_p = r0 if s >= 1 else r0 * s * s / (2.0 - s * s)
    return r_p, s * circular * r0 / r_p


def lab_states(
    m1: float, m2: float, r: np.ndarray, v: np.ndarray, cm_velocity: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """LAB positions and velocities x1, x2, v1, v2 of the two bodies from the relative state (r, v) and the CM's
    velocity, the CM at the origin (docs/theory.md K1, K3): ``x1 = (m2 / M) r``, ``x2 = -(m1 / M) r``,
    ``v1 = V + (m2 / M) v``, ``v2 = V - (m1 / M) v``; masses in kg, r in m, v and V in m/s.
    """
    total = m1 + m2
    return m2 / total * r, -m1 / total * r, cm_velocity + m2 / total * v, cm_velocity - m1 / total * v
