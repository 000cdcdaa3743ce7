"""Repulsive Coulomb (Rutherford) scattering of two free bodies: the exact orbit, its asymptotes, cross sections.

Pure numpy/scipy closed forms (house rule 2), from docs/theory.md C1-C4, C6, C7 and C9 (Wilcox, *Modern Introductory
Mechanics* Part II, chapter 9, eqs 9.12, 9.13, 9.17, 9.33, 9.46, 9.62-9.66; Harter's LAB orbits, 001, and Am. J.
Phys. 40, 1852 (1972)). Conventions (docs/theory.md section 0): projectile m1, target m2 at rest in the LAB frame long
before the collision, ``x = m1 / m2``; ``theta`` the CM scattering angle, ``psi`` the projectile's LAB angle, ``zeta``
the target's LAB recoil angle, all positive; ``b`` the impact parameter; the relative coordinate is ``r = r1 - r2``
(projectile minus target), with reduced mass ``mu = m1 m2 / (m1 + m2)`` and speed at infinity ``v`` (the
projectile's LAB speed: the target starts at rest). The potential is ``U = k / r``, k > 0 (repulsive).

One length sets every scale: ``D = k / (mu v^2) = k / (2 E)`` (E = mu v^2 / 2 the CM energy). Then (C7, eq 9.17)
``tan(theta / 2) = D / b``, the closest approach is ``r_min = D + sqrt(D^2 + b^2)`` (2 D = k / E head-on), and
``dsigma/dOmega = (D / 2)^2 / sin^4(theta / 2) = (k / (4 E))^2 / sin^4(theta / 2)`` (eq 9.13).

The exact orbit (hyperbolic Kepler problem, repulsive branch)
-------------------------------------------------------------
With ``a = D``, eccentricity ``e = sqrt(1 + (b / D)^2)`` and ``s = b / D = sqrt(e^2 - 1)``, the relative coordinate in
its periapsis frame (x along the closest approach) is

    x = a (e + cosh F),   y = a s sinh F,   r = a (e cosh F + 1),   n t = e sinh F + F,   n = v / D,

t measured from the closest approach. Its incoming asymptotic velocity is along ``(-1, s) / e`` and its offset from
the target along ``(s, 1) / e``; the LAB-aligned frame used throughout (beam along +X, impact offset along +Y) has
those two as its axes, so the outgoing velocity is ``v (cos theta, sin theta)``.

Finite distance (the Coulomb tail)
----------------------------------
A run starts and ends at a finite separation R, where the orbit has not reached its asymptotes. Two effects, both
derived from the hodograph (the relative velocity traces a circle of radius ``k / (mu b v)``, docs/theory.md K2's
Runge-Lenz vector with the sign of a repulsion): the speed is short of v by ``D / R`` relatively (energy), and the
velocity's direction is short of the asymptote by ``delta(R) ~ b D / (2 R^2)`` (`asymptote_lag`, exact there). The
position's polar angle lags by ~ b / R, and in the LAB the projectile's lateral offset never settles (C9,
`lab_log_drift`). rigidbench corrects for all of them exactly: the initial state is placed on the exact orbit
(`relative_orbit`), and the outgoing asymptote is read from the final state's invariants (`outgoing_direction`),
which an exact Coulomb orbit keeps for ever.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from rigidbench.analytic import scattering

# ---- scales and the deflection function (C7) -----------------------------------------------------------------


def distance_scale(strength: float, reduced_mass: float, speed: float) -> float:
    """``D = k / (mu v^2) = k / (2 E)`` (m): half the head-on distance of closest approach (docs/theory.md C7).

    Parameters
    ----------
    strength : float
        k (N m^2), > 0: the potential is k / r.
    reduced_mass : float
        mu = m1 m2 / (m1 + m2) (kg).
    speed : float
        v (m/s): relative speed at infinity.
    """
    return float(strength / (reduced_mass * speed * speed))


def cm_angle(impact_parameter: ArrayLike, distance: float) -> np.ndarray:
    """CM scattering angle (rad): ``theta = 2 arctan(D / b)``, pi head-on (docs/theory.md C7; Wilcox eq 9.17,
    ``b = (k / (2 E)) cot(theta / 2)``)."""
    return 2.0 * np.arctan2(distance, np.asarray(impact_parameter, dtype=float))


def impact_parameter(cm_angle: ArrayLike, distance: float) -> np.ndarray:
    """``b = D cot(theta / 2)`` (m), the inverse of `cm_angle` (docs/theory.md C7, eq 9.17)."""
    return distance / np.tan(0.5 * np.asarray(cm_angle, dtype=float))


def closest_approach(impact_parameter: ArrayLike, distance: float) -> np.ndarray:
    """Distance of closest approach (m): ``r_min = D + sqrt(D^2 + b^2) = a (e + 1)``; ``2 D = k / E`` head-on."""
    return distance + np.hypot(distance, np.asarray(impact_parameter, dtype=float))


def eccentricity(impact_parameter: ArrayLike, distance: float) -> np.ndarray:
    """``e = sqrt(1 + (b / D)^2)`` (docs/theory.md K2's ``sqrt(1 + 2 E l^2 / (mu k^2))`` with l = mu b v)."""
    return np.hypot(1.0, np.asarray(impact_parameter, dtype=float) / distance)


def cm_cross_section(cm_angle: ArrayLike, distance: float) -> np.ndarray:
    """Rutherford's ``dsigma/dOmega = (D / 2)^2 / sin^4(theta / 2)`` (m^2/sr), D / 2 = k / (4 E) (docs/theory.md C7,
    Wilcox eq 9.13)."""
    return (0.5 * distance) ** 2 / np.sin(0.5 * np.asarray(cm_angle, dtype=float)) ** 4


# ---- the cut beam: probabilities of angle bins ------------------------------------------------------------------


def beam_radius(min_angle: float, distance: float) -> float:
    """The impact parameter of the smallest angle a beam keeps, ``b_max = D cot(theta_min / 2)`` (m): the cut that
    makes the total cross section, infinite for Coulomb (Wilcox eqs 9.67-9.68), the finite ``pi b_max^2``."""
    return float(impact_parameter(min_angle, distance))


def fraction_beyond(cm_angle: ArrayLike, min_angle: float) -> np.ndarray:
    """Fraction of a uniform beam of radius b_max = D cot(theta_min / 2) scattered beyond theta (CM):
    ``(b(theta) / b_max)^2 = (tan(theta_min / 2) / tan(theta / 2))^2``, 1 below theta_min, 0 at pi.

    It is Rutherford's cross section integrated, ``(1 / (pi b_max^2)) integral_theta^pi dsigma/dOmega 2 pi sin
    dtheta``, for the repulsive k / r (each theta from one b); tests/test_coulomb_analytic.py does the quadrature.
    """
    theta = np.clip(np.asarray(cm_angle, dtype=float), min_angle, np.pi)
    return (np.tan(0.5 * min_angle) / np.tan(0.5 * theta)) ** 2


def cm_angle_probabilities(edges: ArrayLike, min_angle: float) -> np.ndarray:
    """Probability that a collision of the cut beam scatters into each CM-angle bin (edges in rad, increasing).

    Returns
    -------
    ndarray, shape (len(edges) - 1,)
    """
    f = fraction_beyond(edges, min_angle)
    return f[:-1] - f[1:]


def equal_probability_edges(nbin: int, min_angle: float) -> np.ndarray:
    """CM-angle bin edges of equal probability under Rutherford's law over [theta_min, pi] (rad): each bin expects
    n / nbin collisions (the bins of the goodness-of-fit test; equivalently, equal steps of (b / b_max)^2)."""
    f = 1.0 - np.arange(nbin + 1) / nbin  # fraction beyond each edge
    with np.errstate(divide="ignore"):
        return cm_angle(beam_radius(min_angle, 1.0) * np.sqrt(f), 1.0)


def cm_angles_of_projectile(psi: ArrayLike, mass_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """The CM angles giving the projectile's LAB angle psi (docs/theory.md C2, eq 9.63): the stretch branch ``theta =
    psi + arcsin(x sin psi)`` and, for x > 1, the short branch ``pi - arcsin(x sin psi) + psi`` (NaN where a branch
    does not exist: beyond psi_max, or x <= 1 for the short one)."""
    psi = np.asarray(psi, dtype=float)
    x = mass_ratio
    arg = x * np.sin(psi)
    # At psi_max = arcsin(1/x) itself, x sin(psi) can round to just above 1 (x = 2.01479, 8.01907): both branches
    # meet there (theta = arccos(-1/x)), so a few ulps over count as the limit, not beyond it.
    ok = np.abs(arg) <= 1.0 + 8 * np.finfo(float).eps
    asin = np.arcsin(np.clip(np.where(ok, arg, 0.0), -1.0, 1.0))
    stretch = np.where(ok, psi + asin, np.nan)
    short = np.where(ok & (x > 1), psi + np.pi - asin, np.nan)
    return stretch, short


def lab_angle_probabilities(
    edges: ArrayLike, min_angle: float, mass_ratio: float, *, particle: str = "projectile"
) -> np.ndarray:
    """Probability that a collision of the cut beam sends the particle into each LAB-angle bin (rad).

    Exact, by mapping each bin to the CM angles that land in it (C2) and summing `fraction_beyond` over the
    branches, which is the C6 cross section ``sigma_lab(psi) = sum sigma_CM (x cos psi +- s)^2 / s`` integrated
    (tests/test_coulomb_analytic.py integrates C6 itself). The target recoils at ``zeta = (pi - theta) / 2``
    (decreasing in theta). A bin edge beyond the particle's largest angle counts as that angle.

    Parameters
    ----------
    edges : array_like, shape (nbin + 1,)
        Increasing bin edges (rad).
    min_angle : float
        theta_min, the beam's cut (rad).
    mass_ratio : float
        x = m1 / m2.
    particle : {"projectile", "target"}
    """
    edges = np.asarray(edges, dtype=float)
    x = mass_ratio
    if particle == "target":
        theta = np.clip(np.pi - 2.0 * edges, 0.0, np.pi)  # zeta edges -> theta edges (decreasing)
        f = fraction_beyond(theta, min_angle)
        return f[1:] - f[:-1]
    if particle != "projectile":
        raise ValueError(f"particle {particle!r} is not 'projectile' or 'target'")
    top = scattering.max_lab_angle(x) if x > 1 else (np.pi / 2 if x == 1 else np.pi)
    e = np.minimum(edges, top)
    stretch, short = cm_angles_of_projectile(e, x)
    if x == 1:
        stretch = np.where(e >= top, np.pi, stretch)  # psi = theta / 2: pi/2 only head-on
    f = fraction_beyond(stretch, min_angle)
    p = f[:-1] - f[1:]
    if x > 1:  # the short branch: theta decreases from pi (psi = 0) to the stretch branch's meeting point
        g = fraction_beyond(short, min_angle)
        p = p + (g[1:] - g[:-1])
    return p


# ---- the exact orbit and its asymptotes --------------------------------------------------------------------


def eccentric_anomaly(time: ArrayLike, impact_parameter: ArrayLike, distance: float, speed: float) -> np.ndarray:
    """F solving ``n t = e sinh F + F`` (n = v / D; t from the closest approach; t and b broadcast), by Newton's
    method from the asinh guess: the map is increasing, and convex on each side of 0, so it converges to round-off
    in a few steps."""
    m = np.asarray(time, dtype=float) * speed / distance
    e = eccentricity(impact_parameter, distance)
    m, e = np.broadcast_arrays(m, e)
    f = np.arcsinh(m / (e + 1.0))
    for _ in range(60):
        step = (e * np.sinh(f) + f - m) / (e * np.cosh(f) + 1.0)
        f = f - step
        if np.all(np.abs(step) <= 1e-15 * np.maximum(1.0, np.abs(f))):
            break
    return f


def relative_orbit(
    time: ArrayLike, impact_parameter: ArrayLike, distance: float, speed: float
) -> tuple[np.ndarray, np.ndarray]:
    """The exact relative position r = r1 - r2 (m) and velocity (m/s) at times t (s) from the closest approach.

    In the LAB-aligned frame: the incoming asymptotic velocity is ``v (1, 0, 0)``, the impact offset ``b (0, 1,
    0)``; the orbit lies in z = 0 (module docstring; docs/theory.md C7 with K2's hyperbola). b = 0 is the head-on
    radial orbit. t and b broadcast (many times of one orbit, or one time of many orbits).

    Returns
    -------
    r, rdot : ndarray, shape (m, 3), m the broadcast size of t and b (at least 1)
    """
    t, b = np.broadcast_arrays(np.atleast_1d(np.asarray(time, dtype=float)), np.asarray(impact_parameter, dtype=float))
    t, b = t.ravel(), b.ravel()
    a = distance
    e = eccentricity(b, a)
    s = b / a
    f = eccentric_anomaly(t, b, a, speed)
    fdot = (speed / a) / (e * np.cosh(f) + 1.0)
    x, y = a * (e + np.cosh(f)), a * s * np.sinh(f)
    vx, vy = a * np.sinh(f) * fdot, a * s * np.cosh(f) * fdot
    # Axes (periapsis frame): e1 = (-1, s) / e the incoming velocity's direction, e2 = (s, 1) / e the offset's.
    zero = np.zeros_like(t)
    r = np.stack([(s * y - x) / e, (s * x + y) / e, zero], axis=1)
    v = np.stack([(s * vy - vx) / e, (s * vx + vy) / e, zero], axis=1)
    return r, v


def time_at_separation(separation: float, impact_parameter: float, distance: float, speed: float) -> float:
    """Time (s) after the closest approach at which the separation is r (the orbit is symmetric in time):
    ``F = arccosh((r / D - 1) / e)``, ``t = (e sinh F + F) D / v``.

    Raises
    ------
    ValueError
        If r is below the closest approach.
    """
    e = float(eccentricity(impact_parameter, distance))
    c = (separation / distance - 1.0) / e
    if c < 1.0:
        rmin = float(closest_approach(impact_parameter, distance))
        raise ValueError(f"separation {separation:g} m is below the closest approach {rmin:g} m")
    f = np.arccosh(c)
    return float((e * np.sinh(f) + f) * distance / speed)


def asymptote_lag(separation: ArrayLike, impact_parameter: float, distance: float) -> np.ndarray:
    """Angle (rad) between the relative velocity at separation R (either branch) and its asymptote.

    Exact: in the periapsis frame the velocity is along ``(sinh F, s cosh F)`` and the asymptote along ``(1, s)``,
    so ``delta = atan2(s e^-F, sinh F + s^2 cosh F)`` at ``cosh F = (R / D - 1) / e``; for R >> r_min it is ``b D /
    (2 R^2)``: the force's component across the velocity, ``(k / R^2)(b / R)``, integrated along the way out.
    Second order in 1/R; the speed's shortfall ``D / R`` (first order) does not turn the velocity.
    """
    e = float(eccentricity(impact_parameter, distance))
    s = impact_parameter / distance
    f = np.arccosh(np.maximum((np.asarray(separation, dtype=float) / distance - 1.0) / e, 1.0))
    return np.arctan2(s * np.exp(-f), np.sinh(f) + s * s * np.cosh(f))


def outgoing_direction(position: ArrayLike, velocity: ArrayLike, strength_per_mass: float) -> np.ndarray:
    """Unit vector of the outgoing asymptotic relative velocity, from any state (r, rdot) of the repulsive orbit.

    From the invariants: ``h = r x rdot``, the Runge-Lenz vector ``A = rdot x h + kappa r / |r|`` (kappa = k / mu;
    docs/theory.md K2 with the sign of a repulsion; it points from the target to the closest approach), ``e = |A| /
    kappa``; the asymptote is at ``f_inf = arccos(1 / e)`` from A towards the motion: ``cos f_inf A^ + sin f_inf
    (h^ x A^)``. Exact wherever the orbit is (an exact Coulomb orbit keeps h and A), so it reads the asymptote the
    simulated orbit will reach without integrating to infinity.

    Parameters
    ----------
    position, velocity : array_like, shape (..., 3)
        r = r1 - r2 (m) and its rate (m/s).
    strength_per_mass : float
        kappa = k / mu (m^3/s^2).

    Returns
    -------
    ndarray, shape (..., 3)
    """
    return _asymptote(position, velocity, strength_per_mass, +1.0)


def incoming_direction(position: ArrayLike, velocity: ArrayLike, strength_per_mass: float) -> np.ndarray:
    """Unit vector of the incoming asymptotic relative velocity, from any state (see `outgoing_direction`):
    ``-cos f_inf A^ + sin f_inf (h^ x A^)``."""
    return _asymptote(position, velocity, strength_per_mass, -1.0)


def _asymptote(position: ArrayLike, velocity: ArrayLike, kappa: float, sign: float) -> np.ndarray:
    r = np.asarray(position, dtype=float)
    v = np.asarray(velocity, dtype=float)
    h = np.cross(r, v)
    lenz = np.cross(v, h) + kappa * r / np.linalg.norm(r, axis=-1, keepdims=True)
    ecc = np.linalg.norm(lenz, axis=-1, keepdims=True) / kappa
    a_hat = lenz / (ecc * kappa)
    hn = np.linalg.norm(h, axis=-1, keepdims=True)
    h_hat = np.divide(h, hn, out=np.zeros_like(h), where=hn > 0)
    cos_f = 1.0 / ecc
    sin_f = np.sqrt(np.maximum(0.0, 1.0 - cos_f * cos_f))
    return sign * cos_f * a_hat + sin_f * np.cross(h_hat, a_hat)


# ---- LAB frame (C2-C4, C9) ----------------------------------------------------------------------------------


def lab_log_drift(cm_angle: float, masses: tuple[float, float], distance: float) -> float:
    """Coefficient C (m) of ln t in the projectile's LAB lateral offset from its asymptotic line (docs/theory.md C9):
    ``d_perp(t) ~ const + C ln t``, ``C = -(m2 / M) D sin(theta - psi)``, the offset measured along the
    in-plane normal to the projectile's asymptotic LAB velocity, that velocity turned by +90 degrees towards the
    side it was deflected to (+Y in the LAB-aligned frame of `relative_orbit`).

    Cause: the relative coordinate lags its straight line by ``D ln t`` along the CM direction (the Coulomb
    logarithm of the hyperbola, ``r = D (e cosh F + 1)`` with ``n t ~ e sinh F``), and the projectile carries
    ``m2 / M`` of it; the CM direction is not parallel to the LAB velocity unless theta = psi (infinite target
    mass), so the projectile's LAB path has no straight asymptote. The CM-frame relative orbit has one (C = 0).
    """
    m1, m2 = masses
    psi, _ = scattering.lab_angles(cm_angle, m1 / m2)
    return float(-(m2 / (m1 + m2)) * distance * np.sin(cm_angle - psi))


# ---- a pair in the LAB frame: its state on the exact orbit, its invariants, the beam's bins ------------------


def lab_pair_states(
    time: float,
    impact_parameter: ArrayLike,
    azimuth: ArrayLike,
    masses: tuple[float, float],
    distance: float,
    speed: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """LAB positions and velocities of pairs on their exact orbits at `time` (s) from the closest approach
    (docs/theory.md C7; conventions of the module docstring).

    The beam is along +x, the target at rest at t = -inf; each pair's scattering plane is the x-y plane turned by
    its `azimuth` (rad) about x; the CM moves at (m1 v / M, 0, 0) and passes the origin at t = 0.

    Parameters
    ----------
    time : float
        t (s), negative before the closest approach.
    impact_parameter, azimuth : array_like, shape (n,)
        b (m) and the plane's azimuth (rad) of each pair.
    masses : tuple of float
        (m1, m2) (kg): projectile, target.
    distance : float
        D = k / (mu v^2) (m).
    speed : float
        v (m/s), the projectile's speed at infinity.

    Returns
    -------
    x1, v1, x2, v2 : ndarray, shape (n, 3)
        Projectile and target positions (m) and velocities (m/s).
    """
    m1, m2 = masses
    mass = m1 + m2
    cm_velocity = np.array([m1 * speed / mass, 0.0, 0.0])
    r, v = relative_orbit(time, impact_parameter, distance, speed)  # every pair at once, in its own scattering plane
    c, sn = np.cos(azimuth), np.sin(azimuth)  # the plane turned by the azimuth about the beam (x)
    r = np.stack([r[:, 0], c * r[:, 1] - sn * r[:, 2], sn * r[:, 1] + c * r[:, 2]], axis=1)
    v = np.stack([v[:, 0], c * v[:, 1] - sn * v[:, 2], sn * v[:, 1] + c * v[:, 2]], axis=1)
    centre = time * cm_velocity  # the CM passes the origin at the closest approach
    return (
        centre + (m2 / mass) * r,
        cm_velocity + (m2 / mass) * v,
        centre - (m1 / mass) * r,
        cm_velocity - (m1 / mass) * v,
    )


def pair_invariants(
    x1: np.ndarray, v1: np.ndarray, x2: np.ndarray, v2: np.ndarray, masses: tuple[float, float], kappa: float
) -> dict[str, np.ndarray]:
    """What a pair's state fixes of its whole Coulomb orbit (docs/theory.md C7): energy and angular momentum.

    Parameters
    ----------
    x1, v1, x2, v2 : ndarray, shape (..., 3)
        Projectile and target positions (m) and velocities (m/s), LAB frame.
    masses : tuple of float
        (m1, m2) (kg).
    kappa : float
        k / mu (m^3/s^2).

    Returns
    -------
    dict of str to ndarray
        ``r``, ``rdot``: the relative position and velocity; ``speed``: the speed at infinity v = sqrt(rdot^2 + 2
        kappa / r) (energy); ``b``: the impact parameter |r x rdot| / v (angular momentum); ``distance``: D =
        kappa / v^2; ``energy``: the energy per reduced mass v^2 / 2; ``momentum``: m1 v1 + m2 v2.
    """
    m1, m2 = masses
    r = x1 - x2
    rdot = v1 - v2
    dist = np.linalg.norm(r, axis=-1)
    v_sq = np.einsum("...i,...i", rdot, rdot) + 2 * kappa / dist
    speed = np.sqrt(v_sq)
    return {
        "r": r,
        "rdot": rdot,
        "speed": speed,
        "b": np.linalg.norm(np.cross(r, rdot), axis=-1) / speed,
        "distance": kappa / v_sq,
        "energy": 0.5 * v_sq,
        "momentum": m1 * v1 + m2 * v2,
    }


def beam_bins(min_angle: float, mass_ratio: float, nbins: int) -> dict[str, np.ndarray]:
    """Bin edges (rad) of a beam's three goodness-of-fit tests (docs/theory.md C6, C7).

    Equal probability in theta (`equal_probability_edges`); equal widths in psi over [psi(theta_min), psi_top]
    (from 0 for m1 > m2, whose short branch sends near-head-on collisions to psi -> 0) and in zeta over
    [0, (pi - theta_min) / 2] (the top edge is the largest angle, which a histogram should close, so that the
    head-on pair's psi = pi or zeta = 0 counts).

    Parameters
    ----------
    min_angle : float
        theta_min (rad), the smallest CM angle of the beam.
    mass_ratio : float
        x = m1 / m2.
    nbins : int
        Bins per test.

    Returns
    -------
    dict of str to ndarray
        ``cm``, ``projectile``, ``target``: edges, shape (nbins + 1,) each.
    """
    x = mass_ratio
    psi_low = float(scattering.lab_angles(min_angle, x)[0]) if x <= 1 else 0.0
    psi_top = scattering.max_lab_angle(x) if x > 1 else (np.pi / 2 if x == 1 else np.pi)
    return {
        "cm": equal_probability_edges(nbins, min_angle),
        "projectile": np.linspace(min(psi_low, psi_top), psi_top, nbins + 1),
        "target": np.linspace(0.0, 0.5 * (np.pi - min_angle), nbins + 1),
    }
