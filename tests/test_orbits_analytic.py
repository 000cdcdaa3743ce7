"""The two-body closed forms alone (docs/theory.md K1-K5), against independent numerics: scipy's DOP853 on Newton's
equations (the relative coordinate, or both bodies in the LAB frame), and quadrature."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from rigidbench.analytic import orbits

M1, M2 = 1.0, 3.0
MU = orbits.reduced_mass(M1, M2)
K_KEPLER, K_HOOKE = 2.0, 5.0
RTOL = 1e-12  # DOP853's tolerances below; its global error over a few periods stays ~1e-10 of the orbit


def _force(law: str, k: float, exponent: float = 2.0):
    """F(r) on the relative coordinate: -k r / r^(n + 1) (n = exponent) or -k r (hooke)."""
    if law == "hooke":
        return lambda r: -k * r
    return lambda r: -k * r / np.linalg.norm(r) ** (exponent + 1)


def _relative(law: str, k: float, r0, v0, t, exponent: float = 2.0):
    """r(t), v(t) of mu r'' = F(r), integrated by DOP853 (shape (len(t), 3) each)."""
    force = _force(law, k, exponent)

    def rhs(_t, y):
        return np.concatenate([y[3:], force(y[:3]) / MU])

    sol = integrate.solve_ivp(
        rhs, (0, t[-1]), np.concatenate([r0, v0]), method="DOP853", rtol=RTOL, atol=RTOL, t_eval=t, dense_output=True
    )
    return sol.y[:3].T, sol.y[3:].T, sol


@pytest.mark.parametrize("s", [0.6, 0.9, 1.02, 1.2, 1.34])
def test_kepler_equation_follows_newtons_orbit(s):
    """K2: r(t) from Kepler's equation (Wilcox eq. 8.118) is the integrated orbit, at any e and either apsis."""
    r0, v0 = orbits.launch("kepler", MU, K_KEPLER, 1.3, s)
    orbit = orbits.kepler_orbit(MU, K_KEPLER, r0, v0)
    t = np.linspace(0, 2.5 * orbit.period, 801)
    r_ode, v_ode, _ = _relative("kepler", K_KEPLER, r0, v0, t)
    r, v = orbit.position(t)
    scale = orbit.semi_major
    assert np.abs(r - r_ode).max() / scale < 1e-8
    assert np.abs(v - v_ode).max() / (scale * 2 * np.pi / orbit.period) < 1e-7
    assert orbit.eccentricity == pytest.approx(orbits.launch_eccentricity("kepler", s), abs=1e-14)


@pytest.mark.parametrize("s", [0.2, 0.6, 1.02, 2.5])
def test_hooke_oscillator_follows_newtons_orbit(s):
    """K3 (Hooke): r0 cos wt + (v0/w) sin wt is the integrated orbit, an ellipse centred on r = 0."""
    r0, v0 = orbits.launch("hooke", MU, K_HOOKE, 0.7, s)
    orbit = orbits.hooke_orbit(MU, K_HOOKE, r0, v0)
    t = np.linspace(0, 2.5 * orbit.period, 801)
    r_ode, _, _ = _relative("hooke", K_HOOKE, r0, v0, t)
    r, _ = orbit.position(t)
    assert np.abs(r - r_ode).max() / orbit.semi_major < 1e-9
    dist = np.linalg.norm(r_ode, axis=1)
    assert dist.max() == pytest.approx(orbit.semi_major, rel=1e-5)  # sampled: the extremes to ~(2 pi / 320)^2 / 2
    assert dist.min() == pytest.approx(orbit.semi_minor, rel=1e-5)
    assert orbit.eccentricity == pytest.approx(orbits.launch_eccentricity("hooke", s), abs=1e-14)


@pytest.mark.parametrize("s", [0.6, 1.2])
def test_kepler_elements_are_those_of_the_integrated_orbit(s):
    """K2: r_min,max = a (1 -+ e) (eqs 8.70-8.72), T = 2 pi sqrt(mu a^3 / k), the pericentre along the Runge-Lenz
    vector (8.64), and b the orbit's largest extent across its apse line, all read off the DOP853 orbit."""
    r0, v0 = orbits.launch("kepler", MU, K_KEPLER, 1.3, s)
    orbit = orbits.kepler_orbit(MU, K_KEPLER, r0, v0)

    def radial(_t, y):
        return y[:3] @ y[3:]

    force = _force("kepler", K_KEPLER)
    sol = integrate.solve_ivp(
        lambda _t, y: np.concatenate([y[3:], force(y[:3]) / MU]),
        (0, 1.6 * orbit.period),
        np.concatenate([r0, v0]),
        method="DOP853",
        rtol=RTOL,
        atol=RTOL,
        events=radial,
        dense_output=True,
    )
    apsides = sol.y_events[0][:, :3]
    dist = np.linalg.norm(apsides, axis=1)
    a, e = orbit.semi_major, orbit.eccentricity
    assert dist.max() == pytest.approx(a * (1 + e), rel=1e-10)
    assert dist.min() == pytest.approx(a * (1 - e), rel=1e-10)
    peri = apsides[np.argmin(dist)]
    assert np.allclose(peri / np.linalg.norm(peri), orbit.apse, atol=1e-9)
    times = sol.t_events[0]
    same = times[np.isclose(np.linalg.norm(apsides, axis=1), dist[0], rtol=1e-8)]  # returns to the first apsis
    assert same[1] - same[0] == pytest.approx(orbit.period, rel=1e-10)
    t = np.linspace(0, orbit.period, 200_001)
    y = sol.sol(t)[:3].T @ np.cross(orbit.momentum / np.linalg.norm(orbit.momentum), orbit.apse)
    assert np.abs(y).max() == pytest.approx(orbit.semi_minor, rel=1e-9)


@pytest.mark.parametrize(
    ("law", "k", "s"), [("kepler", K_KEPLER, 1.3), ("kepler", K_KEPLER, 0.7), ("hooke", K_HOOKE, 0.5)]
)
def test_lab_frame_bodies_trace_mass_scaled_copies_with_partitioned_energy(law, k, s):
    """K1, K3: integrating both bodies in the LAB frame (12 equations, the CM moving), r_i - R(t) = +-(m_j/M) r(t),
    a_i m_i = a mu, and E_i = (mu / m_i) E with the one-body potentials of K3 [DONE], conserved along the orbit."""
    r0, v0 = orbits.launch(law, MU, k, 0.9, s)
    orbit = (orbits.kepler_orbit if law == "kepler" else orbits.hooke_orbit)(MU, k, r0, v0)
    total = M1 + M2
    cm_velocity = np.array([0.3, -0.2, 0.1])
    x0 = np.concatenate(
        [M2 / total * r0, -M1 / total * r0, cm_velocity + M2 / total * v0, cm_velocity - M1 / total * v0]
    )
    force = _force(law, k)

    def rhs(_t, y):
        f1 = force(y[0:3] - y[3:6])  # on body 1, from body 2
        return np.concatenate([y[6:12], f1 / M1, -f1 / M2])

    t = np.linspace(0, 2 * orbit.period, 1601)
    sol = integrate.solve_ivp(rhs, (0, t[-1]), x0, method="DOP853", rtol=RTOL, atol=RTOL, t_eval=t)
    x1, x2, u1, u2 = sol.y[0:3].T, sol.y[3:6].T, sol.y[6:9].T, sol.y[9:12].T
    centre = cm_velocity * t[:, None]
    rel, _ = orbit.position(t)
    b1, b2 = orbits.body_orbits(M1, M2, orbit)
    assert b1.scale == pytest.approx(M2 / total) and b2.scale == pytest.approx(-M1 / total)
    for x, u, b, m in ((x1, u1, b1, M1), (x2, u2, b2, M2)):
        assert np.abs(x - centre - b.scale * rel).max() / b.semi_major < 1e-8
        assert b.semi_major * m == pytest.approx(orbit.semi_major * MU, rel=1e-14)
        energy = orbits.body_energy(m, b, law, x - centre, u - cm_velocity)
        np.testing.assert_allclose(energy, MU / m * orbit.energy, rtol=1e-9)
    assert b1.energy + b2.energy == pytest.approx(orbit.energy, rel=1e-14)


@pytest.mark.parametrize(
    ("law", "k", "s"), [("kepler", K_KEPLER, 1.3), ("kepler", K_KEPLER, 0.8), ("hooke", K_HOOKE, 0.4)]
)
def test_virial_means_over_a_period(law, k, s):
    """K4 (Wilcox eq. 8.148): <T> = -<U>/2 = -E (Kepler), <T> = <U> = E/2 (Hooke), by quadrature of the
    integrated orbit over one period."""
    r0, v0 = orbits.launch(law, MU, k, 1.1, s)
    orbit = (orbits.kepler_orbit if law == "kepler" else orbits.hooke_orbit)(MU, k, r0, v0)
    _, _, sol = _relative(law, k, r0, v0, np.array([0.0, orbit.period]))

    def mean(f):
        value, _ = integrate.quad(lambda t: f(sol.sol(t)), 0, orbit.period, epsabs=0, epsrel=1e-12, limit=400)
        return value / orbit.period

    kinetic = mean(lambda y: 0.5 * MU * y[3:] @ y[3:])
    potential = mean(lambda y: float(orbit.potential(np.linalg.norm(y[:3]))))
    want_t, want_u = orbit.mean_kinetic_and_potential()
    assert kinetic == pytest.approx(want_t, rel=1e-9)
    assert potential == pytest.approx(want_u, rel=1e-9)


@pytest.mark.parametrize("exponent", [2.0, 1.0, 0.0, -1.0, 2.5])
def test_apsidal_angle_of_a_near_circular_orbit(exponent):
    """K5: pericentre to apocentre sweeps pi / sqrt(3 - n) for F = -k / r^n near a circular orbit (docs/theory.md check
    J4). Integrated at a 1e-3 perturbation of the circular speed; the closed form is the e -> 0 limit, off by
    O(e^2) ~ 1e-6 for n != 2, -1 (Kepler and Hooke: exact)."""
    k, r0 = 1.0, 1.0
    circular = np.sqrt(k / (MU * r0 ** (exponent - 1)))
    state = np.array([r0, 0, 0, 0, 1.001 * circular, 0, 0])  # r, v and the azimuth (integrated: no unwrapping)
    law = "hooke" if exponent == -1 else "power"
    force = _force(law, k, exponent)

    def radial(_t, y):
        return y[:3] @ y[3:6]

    def rhs(_t, y):
        r, v = y[:3], y[3:6]
        return np.concatenate([v, force(r) / MU, [np.cross(r, v)[2] / (r @ r)]])

    sol = integrate.solve_ivp(rhs, (0, 40.0), state, method="DOP853", rtol=RTOL, atol=RTOL, events=radial)
    azimuth = sol.y_events[0][:, 6]
    assert len(azimuth) >= 3
    np.testing.assert_allclose(np.diff(azimuth), orbits.apsidal_angle(exponent), rtol=1e-5)


def test_no_apsides_without_a_stable_circular_orbit():
    with pytest.raises(ValueError, match="n < 3"):
        orbits.apsidal_angle(3.0)


def test_kepler_refuses_an_unbound_orbit():
    """K2 holds for E < 0 only: at s = sqrt(2) times the circular speed the orbit is a parabola."""
    r0, v0 = orbits.launch("kepler", MU, K_KEPLER, 1.0, np.sqrt(2.0) * 1.0001)
    with pytest.raises(ValueError, match="unbound"):
        orbits.kepler_orbit(MU, K_KEPLER, r0, v0)


def test_a_whole_period_brings_both_orbits_back():
    """Kepler's equation and the oscillator are periodic with the stated periods: r(T) = r(0), v(T) = v(0)."""
    for law, k, s in (("kepler", K_KEPLER, 1.3), ("hooke", K_HOOKE, 0.5)):
        r0, v0 = orbits.launch(law, MU, k, 1.0, s)
        orbit = (orbits.kepler_orbit if law == "kepler" else orbits.hooke_orbit)(MU, k, r0, v0)
        r, v = orbit.position(np.array([0.0, orbit.period, 3 * orbit.period]))
        np.testing.assert_allclose(r, np.tile(r0, (3, 1)), atol=1e-13)
        np.testing.assert_allclose(v, np.tile(v0, (3, 1)), atol=1e-12)


@pytest.mark.parametrize("s", [0.6, 0.9, 1.3])  # e >= 0.19: a circle's e is sqrt of round-off
def test_launch_pericentre_is_the_kepler_orbits(s):
    """r_p = a (1 - e) of the launched orbit, and r_p v_p = r0 v0 (angular momentum at the two apsides)."""
    mu, k, r0 = 0.5, 2.0, 1.5
    orbit = orbits.kepler_orbit(mu, k, *orbits.launch("kepler", mu, k, r0, s))
    r_p, v_p = orbits.launch_pericentre(mu, k, r0, s)
    assert r_p == pytest.approx(orbit.semi_major * (1 - orbit.eccentricity), rel=1e-12)
    assert r_p * v_p == pytest.approx(r0 * s * np.sqrt(k / (mu * r0)), rel=1e-12)


def test_lab_states_put_the_cm_at_the_origin_with_the_cm_velocity():
    m1, m2 = 2.0, 0.5
    r, v, cm_velocity = np.array([1.0, 0.2, 0.0]), np.array([0.0, 1.0, 0.3]), np.array([0.1, 0.0, -0.2])
    x1, x2, v1, v2 = orbits.lab_states(m1, m2, r, v, cm_velocity)
    assert np.allclose(m1 * x1 + m2 * x2, 0.0, atol=1e-15) and np.allclose(x1 - x2, r, atol=1e-15)
    assert np.allclose((m1 * v1 + m2 * v2) / (m1 + m2), cm_velocity, atol=1e-15) and np.allclose(v1 - v2, v)
