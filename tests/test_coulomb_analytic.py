"""The closed forms of `rigidbench.analytic.coulomb` alone (docs/theory.md C2-C4, C6, C7, C9), each against an
independent
computation: the equations of motion integrated by scipy (DOP853), the scattering integral (C8) and the cross-section
integrals by quadrature."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from rigidbench.analytic import coulomb, scattering

D, V = 0.01, 1.0  # distance scale k / (mu v^2) (m) and speed at infinity (m/s)
KAPPA = D * V * V  # k / mu


def _ode(r0, v0, t0, t1, times=None):
    """The relative motion r'' = kappa r / |r|^3 (U = k / r, repulsive), integrated independently."""

    def rhs(_t, y):
        r = y[:3]
        return np.concatenate([y[3:], KAPPA * r / np.linalg.norm(r) ** 3])

    return integrate.solve_ivp(
        rhs, (t0, t1), np.concatenate([r0, v0]), method="DOP853", rtol=1e-12, atol=1e-15, t_eval=times
    )


@pytest.mark.parametrize("b_over_d", [0.0, 0.3, 1.0, 5.0, 30.0])
def test_relative_orbit_is_the_solution_of_the_equations_of_motion(b_over_d):
    """The hyperbola (Kepler's hyperbolic equation) against DOP853 from its own state at -T: positions to 1e-9 D."""
    b = b_over_d * D
    t_end = 50 * D / V
    times = np.linspace(-t_end, t_end, 11)
    r, v = coulomb.relative_orbit(times, b, D, V)
    sol = _ode(r[0], v[0], -t_end, t_end, times)
    np.testing.assert_allclose(sol.y[:3].T, r, rtol=0, atol=1e-9 * D)
    np.testing.assert_allclose(sol.y[3:].T, v, rtol=0, atol=1e-9 * V)


def test_relative_orbit_starts_along_the_beam_with_offset_b():
    """Long before the collision the velocity is v along +x and the offset from the target's line is b along +y."""
    b = 2.0 * D
    r, v = coulomb.relative_orbit(-1e7 * D / V, b, D, V)
    assert abs(r[0, 1] - b) < 1e-6 * b
    np.testing.assert_allclose(v[0] / V, [1.0, 0.0, 0.0], atol=1e-6)


@pytest.mark.parametrize("b_over_d", [0.1, 1.0, 4.0, 50.0])
def test_deflection_is_the_scattering_integral(b_over_d):
    """C7 against C8: theta = pi - 2 int_{rmin}^inf b dr / (r^2 sqrt(1 - b^2/r^2 - 2 D / r)) (U / E = 2 D / r)."""
    b = b_over_d * D
    rmin = coulomb.closest_approach(b, D)

    # r = rmin / (1 - w^2): the inverse-square-root singularity at rmin becomes regular in w.
    def integrand(w):
        r = rmin / (1 - w * w)
        g = 1 - (b / r) ** 2 - 2 * D / r
        return b / (r * r * np.sqrt(g)) * rmin * 2 * w / (1 - w * w) ** 2

    value = integrate.quad(integrand, 0, 1, epsabs=0, epsrel=1e-12, limit=200)[0]
    assert abs((np.pi - 2 * value) - coulomb.cm_angle(b, D)) < 1e-10


def test_closest_approach_head_on_is_k_over_e_and_matches_the_orbit():
    assert coulomb.closest_approach(0.0, D) == pytest.approx(2 * D, rel=1e-15)  # 2 D = k / E
    for b in (0.5 * D, 3 * D):
        r, _ = coulomb.relative_orbit(np.linspace(-1e-3, 1e-3, 2001) * D / V, b, D, V)
        assert np.linalg.norm(r, axis=1).min() == pytest.approx(coulomb.closest_approach(b, D), rel=1e-12)


def test_rutherford_cross_section_is_b_over_sin_theta_times_db_dtheta():
    """C7 eq 9.13 from the deflection function by numerical differentiation: sigma = (b / sin theta) |db / dtheta|."""
    theta = np.linspace(0.1, 3.0, 30)
    h = 1e-6
    db = (coulomb.impact_parameter(theta + h, D) - coulomb.impact_parameter(theta - h, D)) / (2 * h)
    sigma = coulomb.impact_parameter(theta, D) / np.sin(theta) * np.abs(db)
    np.testing.assert_allclose(sigma, coulomb.cm_cross_section(theta, D), rtol=1e-8)


@pytest.mark.parametrize("min_angle", [0.2, 0.5, 2.0])
def test_beam_fraction_is_the_integrated_cross_section(min_angle):
    """P(theta > t) = (1 / (pi b_max^2)) int_t^pi sigma 2 pi sin dtheta; the equal-probability edges split it evenly."""
    area = np.pi * coulomb.beam_radius(min_angle, D) ** 2
    for t in (min_angle, 0.5 * (min_angle + np.pi), 3.0):
        value = integrate.quad(
            lambda th: coulomb.cm_cross_section(th, D) * 2 * np.pi * np.sin(th), t, np.pi, epsrel=1e-12
        )[0]
        assert coulomb.fraction_beyond(t, min_angle) == pytest.approx(value / area, rel=1e-9)
    edges = coulomb.equal_probability_edges(20, min_angle)
    assert edges[0] == pytest.approx(min_angle) and edges[-1] == pytest.approx(np.pi)
    np.testing.assert_allclose(coulomb.cm_angle_probabilities(edges, min_angle), 1 / 20, rtol=1e-12)


def _lab_density(psi, min_angle, x):
    """C6 for Rutherford: sigma_lab(psi) = sum over branches sigma_CM(theta) (x cos psi +- s)^2 / s, inside the cut."""
    s2 = 1 - (x * np.sin(psi)) ** 2
    if s2 <= 0:
        return 0.0
    s = np.sqrt(s2)
    total = 0.0
    stretch, short = coulomb.cm_angles_of_projectile(psi, x)
    for theta, sign in ((stretch, 1.0), (short, -1.0)):
        if np.isfinite(theta) and theta >= min_angle and x * np.cos(psi) + sign * s > 0:
            total += coulomb.cm_cross_section(theta, D) * (x * np.cos(psi) + sign * s) ** 2 / s
    return total * 2 * np.pi * np.sin(psi)


@pytest.mark.parametrize("x", [0.05, 0.5, 2.5])
def test_lab_angle_probabilities_integrate_the_lab_cross_section(x):
    """The bin probabilities (CM angles mapped through C2) against the C6 cross section integrated by quadrature;
    for x > 1 both branches, up to psi_max = arcsin(1/x) (C3)."""
    min_angle = 0.5
    top = scattering.max_lab_angle(x) if x > 1 else np.pi
    low = float(scattering.lab_angles(min_angle, x)[0])
    edges = np.linspace(0.0 if x > 1 else low, top, 9)
    area = np.pi * coulomb.beam_radius(min_angle, D) ** 2
    expected = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        points = [p for p in (low,) if lo < p < hi]
        # psi = top - w^2 near psi_max removes the 1/sqrt singularity of s there.
        value = integrate.quad(
            lambda w: _lab_density(top - w * w, min_angle, x) * 2 * w,
            np.sqrt(top - hi),
            np.sqrt(top - lo),
            points=[np.sqrt(top - p) for p in points] or None,
            epsabs=0,
            epsrel=1e-10,
            limit=400,
        )[0]
        expected.append(value / area)
    got = coulomb.lab_angle_probabilities(edges, min_angle, x)
    np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-12)
    assert got.sum() == pytest.approx(1.0, rel=1e-12)


def test_target_probabilities_integrate_its_cross_section():
    """sigma_2(zeta) = 4 cos(zeta) sigma_CM(pi - 2 zeta) (C6), integrated."""
    min_angle = 0.5
    top = 0.5 * (np.pi - min_angle)
    edges = np.linspace(0.0, top, 7)
    area = np.pi * coulomb.beam_radius(min_angle, D) ** 2

    def density(z):
        return 4 * np.cos(z) * coulomb.cm_cross_section(np.pi - 2 * z, D) * 2 * np.pi * np.sin(z)

    expected = [
        integrate.quad(density, lo, hi, epsrel=1e-11)[0] / area for lo, hi in zip(edges[:-1], edges[1:], strict=True)
    ]
    got = coulomb.lab_angle_probabilities(edges, min_angle, 0.7, particle="target")
    np.testing.assert_allclose(got, expected, rtol=1e-8)


@pytest.mark.parametrize("b_over_d", [0.0, 0.3, 2.0, 20.0])
def test_asymptotes_read_from_any_state_of_the_orbit(b_over_d):
    """The Runge-Lenz asymptotes are the same from every point of an orbit: incoming +x, outgoing at theta (C7)."""
    b = b_over_d * D
    theta = coulomb.cm_angle(b, D)
    r, v = coulomb.relative_orbit(np.array([-30, -1, 0, 0.5, 40]) * D / V, b, D, V)
    np.testing.assert_allclose(coulomb.incoming_direction(r, v, KAPPA), [[1, 0, 0]] * 5, atol=1e-12)
    np.testing.assert_allclose(
        coulomb.outgoing_direction(r, v, KAPPA), [[np.cos(theta), np.sin(theta), 0]] * 5, atol=1e-12
    )


@pytest.mark.parametrize("b_over_d", [0.5, 3.0])
def test_asymptote_lag_is_the_orbits_and_falls_as_b_d_over_2_r_squared(b_over_d):
    """delta(R), the velocity's angle short of the asymptote at separation R, against the orbit's own velocity; at
    large R it tends to b D / (2 R^2) (second order in 1/R), while the speed falls short by ~D / R (first order)."""
    b = b_over_d * D
    theta = coulomb.cm_angle(b, D)
    for ratio in (10.0, 100.0, 1000.0):
        rr = ratio * coulomb.closest_approach(b, D)
        t = coulomb.time_at_separation(rr, b, D, V)
        r, v = coulomb.relative_orbit(t, b, D, V)
        assert np.linalg.norm(r) == pytest.approx(rr, rel=1e-12)
        lag = theta - np.arctan2(v[0, 1], v[0, 0])
        assert coulomb.asymptote_lag(rr, b, D) == pytest.approx(lag, rel=1e-7)
        if ratio >= 100:
            assert lag == pytest.approx(b * D / (2 * rr * rr), rel=3 / ratio)
            assert 1 - np.linalg.norm(v) / V == pytest.approx(D / rr, rel=3 / ratio)


def test_lab_log_drift_is_the_exact_orbits_late_slope():
    """C9: the projectile's LAB lateral offset from its asymptotic line grows as C ln t, C = -(m2/M) D sin(theta -
    psi); the slope between two late times of the exact orbit tends to C (error ~ 1/t), and the CM orbit's offset to
    a constant."""
    m1, m2 = 1.0, 3.0
    mass = m1 + m2
    b = D
    theta = float(coulomb.cm_angle(b, D))
    psi = float(scattering.lab_angles(theta, m1 / m2)[0])
    v1 = np.array([m1 * V / mass, 0, 0]) + (m2 / mass) * V * np.array([np.cos(theta), np.sin(theta), 0])
    normal = np.array([-v1[1], v1[0], 0.0]) / np.linalg.norm(v1)
    out = np.array([-np.sin(theta), np.cos(theta), 0.0])
    c = coulomb.lab_log_drift(theta, (m1, m2), D)
    assert c == pytest.approx(-(m2 / mass) * D * np.sin(theta - psi)) and c < 0
    errors = []
    for t_late in (1e3, 1e4, 1e5):
        times = np.array([t_late, 10 * t_late]) * D / V
        r, _ = coulomb.relative_orbit(times, b, D, V)
        x1 = np.array([m1 * V / mass, 0, 0]) * times[:, None] + (m2 / mass) * r
        slope = (x1[1] - x1[0]) @ normal / np.log(10)
        errors.append(abs(slope - c))
        assert abs((r[1] - r[0]) @ out) < 10 * D / t_late  # the CM-frame orbit settles on its asymptote
    assert errors[1] < 0.2 * errors[0] and errors[2] < 0.2 * errors[1]  # converging as ~1/t
    assert errors[-1] < 1e-3 * abs(c)


def test_small_mass_ratio_lab_formula_error_is_second_order():
    """C7: sigma(psi) ~ (k/(4 T0))^2 / sin^4(psi/2) for x << 1, with no first-order term in x (eqs 9.65-9.66): its
    error falls 4x when x halves. Compared through the LAB probability of one angle bin."""
    min_angle, lo, hi = 0.3, 1.0, 1.2
    errors = []
    for x in (0.02, 0.01):
        exact = coulomb.lab_angle_probabilities(np.array([lo, hi]), min_angle, x)[0]
        # (k / (4 T0)) = (D / 2) mu / m1 = (D / 2) / (1 + x), integrated over the bin, over the same beam area.
        scale = 0.5 * D / (1 + x)
        approx = integrate.quad(lambda p, c=scale: c**2 / np.sin(p / 2) ** 4 * 2 * np.pi * np.sin(p), lo, hi)[0]
        errors.append(abs(approx / (np.pi * coulomb.beam_radius(min_angle, D) ** 2) - exact) / exact)
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.05)


def test_time_at_separation_refuses_inside_the_closest_approach():
    with pytest.raises(ValueError, match="below the closest approach"):
        coulomb.time_at_separation(D, D, D, V)


@pytest.mark.parametrize("x", [1.5, 2.0, 2.01479, 4.0, 8.01907, 0.5, 1.0])
def test_beam_bins_cover_the_projectiles_whole_range(x):
    """The beam's projectile bins hold every LAB angle the cut beam can give: for m1 > m2 from 0 (the short branch's
    near-head-on collisions), and the top bin's probability is finite where x sin(psi_max) rounds above 1 (x =
    2.01479, 8.01907)."""
    edges = coulomb.beam_bins(0.5, x, 20)["projectile"]
    p = coulomb.lab_angle_probabilities(edges, 0.5, x)
    assert np.all(np.isfinite(p)) and np.all(p >= 0)
    assert p.sum() == pytest.approx(1.0, abs=1e-8)


@pytest.mark.parametrize("b_over_d", [0.0, 0.3, 5.0])
def test_pair_invariants_recover_the_orbit_from_a_lab_state_on_it(b_over_d):
    """A pair placed on its exact orbit (`lab_pair_states`) gives back its b, D, v and the beam's momentum m1 v."""
    m1, m2 = 2.0, 0.5
    mu = m1 * m2 / (m1 + m2)
    kappa = D * V**2  # k / mu
    x1, v1, x2, v2 = coulomb.lab_pair_states(-3.0 * D / V, np.array([b_over_d * D]), np.array([0.7]), (m1, m2), D, V)
    inv = coulomb.pair_invariants(x1, v1, x2, v2, (m1, m2), kappa)
    assert inv["b"][0] == pytest.approx(b_over_d * D, rel=1e-12, abs=1e-12 * D)
    assert inv["distance"][0] == pytest.approx(D, rel=1e-12) and inv["speed"][0] == pytest.approx(V, rel=1e-12)
    assert np.allclose(inv["momentum"][0], [m1 * V, 0.0, 0.0], rtol=1e-12, atol=1e-12 * m1 * V)
    assert inv["energy"][0] == pytest.approx(0.5 * V**2, rel=1e-12) and mu > 0
