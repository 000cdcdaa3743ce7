"""Two-body elastic scattering: hard spheres, and the soft contact spring MuJoCo actually simulates.

Pure numpy/scipy closed forms (house rule 2), from docs/theory.md section 9 (Wilcox, *Modern Introductory Mechanics*
Part II, chapter 9). Conventions (docs/theory.md section 0): projectile m1, target m2 at rest in the LAB frame,
``x = m1 / m2``; ``theta`` is the CM scattering angle, ``psi`` the LAB angle of the projectile, ``zeta`` the LAB
recoil angle of the target, all positive; ``b`` the impact parameter; ``a = r1 + r2`` the contact distance.

The soft sphere
---------------
MuJoCo's elastic contact (`rigidbench.contact`) is a linear spring on the penetration ``delta = a - r`` of the
relative coordinate: ``delta'' = -k delta`` along the line of centres, i.e. the potential

    V(r) = 1/2 mu k (a - r)^2  for r < a,   0 otherwise,

with mu the reduced mass and k (1/s^2) the constraint-space stiffness. Its deflection function follows from the
classical scattering integral (docs/theory.md C8, Wilcox eq. 9.16) with ``V / E = kappa (a - r)^2``,
``kappa = k / u^2`` (u the relative speed at infinity); it depends on k, u and a only, not on the masses. As
``k -> inf`` it tends to the hard-sphere ``theta = 2 arccos(b / a)`` (C5) with a shift of first order in the
largest penetration ``u / sqrt(k)``: ``theta_hard - theta_soft = pi (b / a) u / (a sqrt(k)) + O(k^-1)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from rigidbench import lazy

integrate = lazy.module("scipy.integrate")


# Gauss-Legendre order for the soft-sphere integral: after the substitution r = r_min + t^2 the integrand is
# analytic on the closed interval, so the rule converges geometrically; 64 nodes reach ~1e-15 rad for
# penetrations up to 30 % of a (tests/test_scattering_analytic.py compares with adaptive quadrature).
_GAUSS_ORDER = 64
_GAUSS_T, _GAUSS_W = np.polynomial.legendre.leggauss(_GAUSS_ORDER)


# ---- hard spheres (C1-C6) -------------------------------------------------------------------------------


def hard_sphere_cm_angle(impact_parameter: ArrayLike, contact_distance: float) -> np.ndarray:
    """CM scattering angle of smooth hard spheres (rad).

    ``theta = 2 arccos(b / a)`` for ``b < a``, 0 for a miss (docs/theory.md C5; Wilcox section 9.9, "b = a sin(alpha),
    2 alpha + theta = pi").

    Parameters
    ----------
    impact_parameter : array_like
        b (m), >= 0.
    contact_distance : float
        a = r1 + r2 (m).
    """
    b = np.asarray(impact_parameter, dtype=float)
    return 2.0 * np.arccos(np.clip(b / contact_distance, 0.0, 1.0))


def lab_angles(cm_angle: ArrayLike, mass_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """LAB angles (psi, zeta) of projectile and target (rad) for a CM angle theta.

    ``tan(psi) = sin(theta) / (cos(theta) + x)`` (docs/theory.md C2, Wilcox eq. 9.33), taken in [0, pi] with atan2,
    and ``zeta = (pi - theta) / 2`` (C2, from eq. 9.27).

    Parameters
    ----------
    cm_angle : array_like
        theta (rad) in [0, pi].
    mass_ratio : float
        x = m1 / m2.
    """
    theta = np.asarray(cm_angle, dtype=float)
    psi = np.arctan2(np.sin(theta), np.cos(theta) + mass_ratio)
    return psi, 0.5 * (np.pi - theta)


def lab_energy_fractions(cm_angle: ArrayLike, m1: float, m2: float) -> tuple[np.ndarray, np.ndarray]:
    """LAB kinetic energies of projectile and target after the collision, as fractions of T0 = m1 u1^2 / 2.

    ``T1/T0 = (m1^2 + m2^2 + 2 m1 m2 cos(theta)) / (m1 + m2)^2`` (docs/theory.md C4, Wilcox eq. 9.46) and
    ``T2/T0 = 4 m1 m2 sin^2(theta/2) / (m1 + m2)^2`` (C4, from eqs 9.27 and 9.45); they add up to 1.
    """
    c = np.cos(np.asarray(cm_angle, dtype=float))
    m = (m1 + m2) ** 2
    return (m1 * m1 + m2 * m2 + 2 * m1 * m2 * c) / m, 2 * m1 * m2 * (1 - c) / m


def max_lab_angle(mass_ratio: float) -> float:
    """Largest LAB angle of the projectile (rad): ``arcsin(m2/m1)`` for x > 1 (docs/theory.md C3, Wilcox eq. 9.36),
    pi otherwise (every direction is reachable)."""
    return float(np.arcsin(1.0 / mass_ratio)) if mass_ratio > 1 else float(np.pi)


def critical_impact_parameter(contact_distance: float, mass_ratio: float) -> float:
    """Impact parameter b0 (m) at which a heavy projectile (x > 1) reaches psi_max, ``a sqrt((x - 1) / (2 x))``.

    It separates the two branches (docs/theory.md C3): b > b0 gives theta < arccos(-1/x) ("stretch", the fast
    projectile of eq. 9.53 with +), b < b0 the "short" branch (the slow one, with -).

    Raises
    ------
    ValueError
        If x <= 1 (no maximum angle, one branch).
    """
    if not mass_ratio > 1:
        raise ValueError(f"mass ratio m1/m2 = {mass_ratio:g} has no critical impact parameter (needs > 1)")
    return contact_distance * float(np.sqrt((mass_ratio - 1) / (2 * mass_ratio)))


def lab_cross_section_projectile(psi: ArrayLike, contact_distance: float, mass_ratio: float) -> np.ndarray:
    """Hard-sphere LAB differential cross section of the projectile, dsigma/dOmega (m^2/sr), both branches.

    ``sigma_lab(psi) = sum over branches of sigma_CM(theta) (x cos(psi) +- s)^2 / s``, ``s = sqrt(1 - x^2 sin^2
    psi)``, with ``sigma_CM = a^2 / 4`` (docs/theory.md C6; Wilcox eqs 9.62 for x < 1, 9.64 for x > 1; C5). For x < 1
    only the + branch exists; for x > 1 both, up to psi_max where s -> 0 (an integrable singularity); x = 1
    gives ``a^2 cos(psi)`` for psi < pi/2.
    """
    psi = np.asarray(psi, dtype=float)
    x = mass_ratio
    sigma_cm = contact_distance**2 / 4
    s2 = 1.0 - x * x * np.sin(psi) ** 2
    ok = s2 > 0
    s = np.sqrt(np.where(ok, s2, 1.0))
    xc = x * np.cos(psi)
    plus = (xc + s) ** 2 / s
    minus = (xc - s) ** 2 / s
    # A branch exists where its v1/u1 = (x cos(psi) +- s)/(1 + x) (eq. 9.53) is positive.
    out = np.where(ok & (xc + s > 0), plus, 0.0) + np.where(ok & (xc - s > 0), minus, 0.0)
    return sigma_cm * out


def lab_cross_section_target(zeta: ArrayLike, contact_distance: float) -> np.ndarray:
    """Hard-sphere LAB cross section of the recoiling target (m^2/sr): ``a^2 cos(zeta)`` for zeta < pi/2
    (docs/theory.md C6, ``4 cos(zeta) sigma_CM(pi - 2 zeta)``)."""
    zeta = np.asarray(zeta, dtype=float)
    return np.where(zeta < np.pi / 2, contact_distance**2 * np.cos(zeta), 0.0)


def lab_angle_probabilities(
    edges: ArrayLike, contact_distance: float, mass_ratio: float, *, particle: str = "projectile"
) -> np.ndarray:
    """Probability that a hit scatters the particle into each LAB-angle bin, from C6.

    ``P_i = (1 / (pi a^2)) integral over the bin of sigma_lab(psi) 2 pi sin(psi) dpsi`` (docs/theory.md C6; total
    cross section pi a^2, C5), by adaptive quadrature of `lab_cross_section_projectile` (or `..._target`) in
    ``w = sqrt(psi_top - psi)``, which removes the integrable 1/s singularity at psi_max.

    Parameters
    ----------
    edges : array_like, shape (nbin + 1,)
        Increasing bin edges (rad) in [0, pi].
    particle : {"projectile", "target"}

    Returns
    -------
    ndarray, shape (nbin,)
    """
    edges = np.asarray(edges, dtype=float)
    a = contact_distance
    if particle == "projectile":
        top = max_lab_angle(mass_ratio) if mass_ratio > 1 else np.pi

        def density(p):
            return lab_cross_section_projectile(p, a, mass_ratio) * 2 * np.pi * np.sin(p)
    elif particle == "target":
        top = np.pi / 2

        def density(p):
            return lab_cross_section_target(p, a) * 2 * np.pi * np.sin(p)
    else:
        raise ValueError(f"particle {particle!r} is not 'projectile' or 'target'")

    def regular(w):
        # psi = top - w^2 turns the 1/sqrt(top - psi) singularity at psi_max (x > 1) into a smooth integrand.
        return density(top - w * w) * 2 * w

    out = np.zeros(len(edges) - 1)
    for i, (lo, hi) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        hi = min(hi, top)
        if hi > lo:
            w_lo, w_hi = np.sqrt(top - hi), np.sqrt(top - lo)
            out[i] = integrate.quad(regular, w_lo, w_hi, epsabs=0, epsrel=1e-11, limit=200)[0]
    return out / (np.pi * a * a)


# ---- soft spheres (C8) ----------------------------------------------------------------------------------


def soft_sphere_turning_point(
    impact_parameter: ArrayLike, contact_distance: float, stiffness: float, speed: float
) -> np.ndarray:
    """Distance of closest approach r_min (m) of the soft sphere: the root of ``g(r) = 1 - b^2/r^2 -
    kappa (a - r)^2`` (the radicand of C8), kappa = k / u^2. g increases strictly on (0, a], so the root is
    unique; it is bracketed by [max(b, a - 1/sqrt(kappa)), a] and found by bisection to machine precision.
    r_min = b for a miss (b >= a)."""
    b = np.atleast_1d(np.asarray(impact_parameter, dtype=float))
    a = contact_distance
    kappa = stiffness / speed**2
    lo = np.minimum(np.maximum(b, a - 1.0 / np.sqrt(kappa)), a)
    hi = np.full_like(b, a)
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        neg = 1.0 - (b / mid) ** 2 - kappa * (a - mid) ** 2 < 0
        lo = np.where(neg, mid, lo)
        hi = np.where(neg, hi, mid)
    return np.where(b >= a, b, 0.5 * (lo + hi)).reshape(np.shape(impact_parameter))


def soft_sphere_cm_angle(
    impact_parameter: ArrayLike, contact_distance: float, stiffness: float, speed: float
) -> np.ndarray:
    """CM scattering angle (rad) for the contact spring V = 1/2 mu k (a - r)^2 (r < a).

    docs/theory.md C8 (Wilcox eq. 9.16): ``theta = pi - 2 integral_{r_min}^inf b dr / (r^2 sqrt(g(r)))`` with
    ``g = 1 - b^2/r^2 - V/E``, ``V/E = kappa (a - r)^2``, ``kappa = k / u^2``. Split at r = a: the outer part
    is ``arcsin(b/a)`` exactly. In the inner part g has a simple zero at r_min; writing
    ``g(r) = (r - r_min) h(r)`` with ``h(r) = b^2 (r + r_min) / (r^2 r_min^2) + kappa (2a - r - r_min) > 0``
    (exact, no cancellation) and substituting ``r = r_min + t^2`` gives the regular integral
    ``integral_0^sqrt(a - r_min) 2 b dt / (r^2 sqrt(h(r)))``, done by Gauss-Legendre quadrature.

    Parameters
    ----------
    impact_parameter : array_like
        b (m), >= 0.
    contact_distance : float
        a (m): the spring acts for r < a.
    stiffness : float
        k (1/s^2): relative acceleration per unit penetration (MuJoCo's constraint-space stiffness).
    speed : float
        u (m/s): relative speed at infinity (the projectile's LAB speed, the target at rest).

    Raises
    ------
    ValueError
        If the largest penetration u/sqrt(k) is not below a (the spheres would pass through each other).
    """
    hit, bh, half, r, h = _contact_nodes(impact_parameter, contact_distance, stiffness, speed)
    bb = bh[:, None]
    inner = 0.5 * half * np.sum(_GAUSS_W * 2 * bb / (r * r * np.sqrt(h)), axis=1)
    theta = np.pi - 2.0 * (np.arcsin(bh / contact_distance) + inner)
    theta = np.where(hit, theta, 0.0)
    return theta.reshape(np.shape(impact_parameter))


def soft_sphere_contact_time(
    impact_parameter: ArrayLike, contact_distance: float, stiffness: float, speed: float
) -> np.ndarray:
    """Time (s) the soft spheres spend in contact, |r| < a, under V = 1/2 mu k (a - r)^2 (docs/theory.md C8).

    The radial equation of the same scattering problem, ``r' = u sqrt(g(r))`` with ``g = 1 - b^2/r^2 - kappa (a -
    r)^2``, ``kappa = k / u^2``, gives ``t_c = 2 integral_{r_min}^a dr / (u sqrt(g(r)))``; with ``g = (r - r_min)
    h(r)`` and ``r = r_min + t^2`` (as in `soft_sphere_cm_angle`) it is the regular ``2 integral_0^sqrt(a - r_min) 2
    dt / (u sqrt(h(r)))``, done by the same Gauss-Legendre rule. Head-on (b = 0) it is the half period pi / sqrt(k)
    exactly; obliquely it is shorter (the centrifugal term b^2 / r^2 pushes the spheres apart sooner). 0 for a
    miss (b >= a).

    Raises
    ------
    ValueError
        If the largest penetration u/sqrt(k) is not below a.
    """
    hit, _, half, _, h = _contact_nodes(impact_parameter, contact_distance, stiffness, speed)
    duration = 2.0 * 0.5 * half * np.sum(_GAUSS_W * 2.0 / (speed * np.sqrt(h)), axis=1)
    return np.where(hit, duration, 0.0).reshape(np.shape(impact_parameter))


def soft_sphere_shift_first_order(
    impact_parameter: ArrayLike, contact_distance: float, stiffness: float, speed: float
) -> np.ndarray:
    """First-order soft-contact shift ``theta_hard - theta_soft ~ pi (b / a) delta_max / a`` (rad), with
    ``delta_max = u / sqrt(k)`` the head-on penetration; scales as k^-1/2.

    From C8: near r = a, ``g ~ cos^2(alpha) - kappa (a - r)^2`` (sin(alpha) = b/a), so the inner integral is
    ``(b / a^2) (pi / 2) / sqrt(kappa)``; the relative error of this estimate is O(delta_max / (a cos^2 alpha)),
    larger at grazing incidence (tests/test_scattering_analytic.py measures it)."""
    b = np.asarray(impact_parameter, dtype=float)
    a = contact_distance
    return np.where(b < a, np.pi * (b / a) * speed / np.sqrt(stiffness) / a, 0.0)


def soft_sphere_relative_motion(
    position: ArrayLike, velocity: ArrayLike, contact_distance: float, stiffness: float, duration: float
):
    """The relative coordinate r = r1 - r2 under the contact spring, integrated in time (scipy DOP853).

    ``r'' = k (a - |r|) r / |r|`` for ``|r| < a``, free flight otherwise: the same soft potential as
    `soft_sphere_cm_angle` (C8), solved as an initial-value problem instead of by quadrature, so each checks the
    other. The force's kinks at entry and exit (zero penetration) are resolved by the error control.

    Parameters
    ----------
    position, velocity : array_like, shape (3,)
        r (m) and r' (m/s) at t = 0.
    contact_distance : float
        a (m).
    stiffness : float
        k (1/s^2).
    duration : float
        Seconds.

    Returns
    -------
    callable
        ``f(t) -> (r, r')``, arrays of shape (3,) (or (3, n) for an array t), valid on [0, duration].
    """
    a = contact_distance
    k = stiffness
    y0 = np.concatenate([np.asarray(position, dtype=float), np.asarray(velocity, dtype=float)])

    def rhs(_t, y):
        r = y[:3]
        n = np.linalg.norm(r)
        push = k * (a - n) / n if n < a else 0.0
        return np.concatenate([y[3:], push * r])

    sol = integrate.solve_ivp(
        rhs,
        (0.0, duration),
        y0,
        method="DOP853",
        rtol=1e-12,
        atol=1e-15,
        dense_output=True,
        max_step=np.pi / np.sqrt(k) / 50,  # never step over a contact; error control refines the kinks
    )

    def motion(time):
        y = sol.sol(np.asarray(time, dtype=float))
        return y[:3], y[3:]

    return motion


def _contact_nodes(
    impact_parameter: ArrayLike, contact_distance: float, stiffness: float, speed: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The Gauss-Legendre nodes of C8's contact integrals (`soft_sphere_cm_angle`, `soft_sphere_contact_time`):
    which impacts hit (b < a), b where they do (0 elsewhere), the half-range sqrt(a - r_min) of t, the radii r =
    r_min + t^2 at the nodes and the regular factor h(r) of g = (r - r_min) h(r).

    Raises
    ------
    ValueError
        If the largest penetration u/sqrt(k) is not below a.
    """
    a = contact_distance
    kappa = stiffness / speed**2
    if not 1.0 / np.sqrt(kappa) < a:
        raise ValueError(
            f"largest penetration speed/sqrt(stiffness) = {1 / np.sqrt(kappa):g} m is not below the contact "
            f"distance a = {a:g} m: the soft spheres pass through each other"
        )
    b = np.atleast_1d(np.asarray(impact_parameter, dtype=float))
    hit = b < a
    bh = np.where(hit, b, 0.0)
    rmin = soft_sphere_turning_point(bh, a, stiffness, speed).reshape(bh.shape)
    half = np.sqrt(a - rmin)  # t runs over [0, half]
    t = 0.5 * half[:, None] * (_GAUSS_T[None, :] + 1.0)
    r = rmin[:, None] + t * t
    bb = bh[:, None]
    h = bb * bb * (r + rmin[:, None]) / (r * r * rmin[:, None] ** 2) + kappa * (2 * a - r - rmin[:, None])
    return hit, bh, half, r, h
