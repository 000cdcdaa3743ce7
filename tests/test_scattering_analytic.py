"""The scattering closed forms alone (docs/theory.md C1-C6, C8): identities, limits, independent references."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from rigidbench.analytic import scattering as sc

A = 0.1  # contact distance (m)
THETA = np.linspace(0.01, np.pi - 0.01, 199)


def test_equal_masses_scatter_at_right_angles():
    """C2, eqs 9.37-9.39: psi = theta/2 and psi + zeta = 90 deg for m1 = m2 (Harter's pool-shark rule)."""
    psi, zeta = sc.lab_angles(THETA, 1.0)
    np.testing.assert_allclose(psi, THETA / 2, rtol=0, atol=4e-15)  # a few ulp of atan2
    np.testing.assert_allclose(psi + zeta, np.pi / 2, rtol=0, atol=4e-15)


@pytest.mark.parametrize("x", [1.5, 3.0, 10.0])
def test_lab_angle_never_exceeds_arcsin_m2_over_m1(x):
    """C3, eq 9.36: sin(psi_max) = m2/m1, reached at b0 = a sqrt((x - 1)/(2x)) (cos theta = -1/x)."""
    b = np.linspace(0, A, 100_001)[:-1]
    psi, _ = sc.lab_angles(sc.hard_sphere_cm_angle(b, A), x)
    assert psi.max() <= sc.max_lab_angle(x) + 1e-15
    b0 = sc.critical_impact_parameter(A, x)
    psi_b0, _ = sc.lab_angles(sc.hard_sphere_cm_angle(b0, A), x)
    assert psi_b0 == pytest.approx(np.arcsin(1 / x), abs=1e-14)
    assert np.cos(sc.hard_sphere_cm_angle(b0, A)) == pytest.approx(-1 / x, abs=1e-14)


def test_critical_impact_parameter_refuses_light_projectile():
    with pytest.raises(ValueError, match="mass ratio"):
        sc.critical_impact_parameter(A, 0.5)


@pytest.mark.parametrize(("m1", "m2"), [(1.0, 3.0), (1.0, 1.0), (3.0, 1.0), (2.5, 0.7)])
def test_energy_fractions_add_to_one_and_match_moderator_rule(m1, m2):
    """C4: T1/T0 + T2/T0 = 1 (eq 9.46 with 9.45); head-on T1/T0 = ((m1 - m2)/(m1 + m2))^2."""
    t1, t2 = sc.lab_energy_fractions(THETA, m1, m2)
    np.testing.assert_allclose(t1 + t2, 1.0, rtol=0, atol=1e-15)
    head_on, _ = sc.lab_energy_fractions(np.pi, m1, m2)
    assert head_on == pytest.approx(((m1 - m2) / (m1 + m2)) ** 2, abs=1e-15)


def _sigma_lab_from_deflection(psi: float, x: float) -> float:
    """b |db/dpsi| / sin(psi) summed over the CM angles that give psi (eq 9.49), with b = a cos(theta/2):
    built from the deflection function, independently of C6's closed form."""
    s = np.sqrt(1 - (x * np.sin(psi)) ** 2)
    total = 0.0
    roots = {float(np.arccos(np.clip(-x * np.sin(psi) ** 2 + sign * np.cos(psi) * s, -1, 1))) for sign in (1, -1)}
    for theta in roots:  # a set: at psi = pi/2 the two roots coincide
        if abs(sc.lab_angles(theta, x)[0] - psi) > 1e-9:  # not a branch at this psi (x < 1: the - root)
            continue
        b = A * np.cos(theta / 2)
        db_dtheta = -A / 2 * np.sin(theta / 2)
        dpsi_dtheta = (1 + x * np.cos(theta)) / (1 + x * x + 2 * x * np.cos(theta))
        total += b * abs(db_dtheta / dpsi_dtheta) / np.sin(psi)
    return total


@pytest.mark.parametrize("x", [0.3, 1.0, 2.5])
def test_lab_cross_section_matches_the_deflection_function(x):
    """C6 (eqs 9.62, 9.64) against b |db/dpsi| / sin(psi) from C5's deflection, both branches (THEORY check I5a-b)."""
    top = sc.max_lab_angle(x) if x > 1 else (np.pi / 2 if x == 1 else np.pi)
    psi = np.linspace(0.02, top - 0.02, 41)
    expected = np.array([_sigma_lab_from_deflection(p, x) for p in psi])
    np.testing.assert_allclose(sc.lab_cross_section_projectile(psi, A, x), expected, rtol=1e-9)


def test_equal_mass_lab_cross_section_is_a_squared_cos_psi():
    """C6 for x = 1: sigma_lab = a^2 cos(psi) (THEORY check I5c)."""
    psi = np.linspace(0.01, np.pi / 2 - 0.01, 50)
    np.testing.assert_allclose(sc.lab_cross_section_projectile(psi, A, 1.0), A * A * np.cos(psi), rtol=1e-13)


@pytest.mark.parametrize("x", [0.3, 1.0, 2.5, 10.0])
def test_lab_cross_sections_integrate_to_pi_a_squared(x):
    """Total cross sections are frame-independent: integral sigma_lab dOmega = pi a^2 (C5, C6; check I5d)."""
    top = sc.max_lab_angle(x) if x > 1 else (np.pi / 2 if x == 1 else np.pi)
    p = sc.lab_angle_probabilities(np.linspace(0, top, 31), A, x)
    assert p.sum() == pytest.approx(1.0, abs=1e-10)
    assert (p > 0).all()
    q = sc.lab_angle_probabilities(np.linspace(0, np.pi / 2, 31), A, x, particle="target")
    assert q.sum() == pytest.approx(1.0, abs=1e-12)
    # Recoil: the CDF of a^2 cos(zeta) over the beam is sin^2(zeta).
    np.testing.assert_allclose(np.cumsum(q), np.sin(np.linspace(0, np.pi / 2, 31)[1:]) ** 2, atol=1e-12)


# ---- the soft sphere (C8) ---------------------------------------------------------------------------------


def _soft_angle_ivp(b: float, k: float, u: float) -> float:
    """CM angle of the soft sphere by integrating the relative motion in the plane (DOP853, rtol 1e-12): an
    independent reference for the C8 quadrature."""

    def rhs(_t, y):
        r = np.hypot(y[0], y[1])
        push = k * (A - r) / r if r < A else 0.0
        return [y[2], y[3], push * y[0], push * y[1]]

    x0 = -np.sqrt(A * A - b * b) - 1e-3
    tau = np.pi / np.sqrt(k)
    sol = integrate.solve_ivp(
        rhs, (0, 2e-3 / u + 3 * tau), [x0, b, u, 0.0], method="DOP853", rtol=1e-12, atol=1e-15, max_step=tau / 50
    )
    return float(np.arctan2(sol.y[3, -1], sol.y[2, -1]))


@pytest.mark.parametrize("k", [1e5, 1e7])
@pytest.mark.parametrize("b_over_a", [0.0, 0.2, 0.5, 0.8, 0.99])
def test_soft_sphere_angle_matches_solve_ivp(k, b_over_a):
    """C8 quadrature (after r = r_min + t^2) against an independent ODE integration, to 1e-9 rad."""
    b = b_over_a * A
    theta = float(sc.soft_sphere_cm_angle(b, A, k, 2.0))
    assert theta == pytest.approx(_soft_angle_ivp(b, k, 2.0), abs=1e-9)


@pytest.mark.parametrize("b_over_a", [0.1, 0.5, 0.9, 0.999])
def test_soft_sphere_gauss_rule_matches_adaptive_quadrature(b_over_a):
    """The 64-node Gauss-Legendre rule against scipy.quad of the raw C8 integrand (1/sqrt singularity at r_min,
    which QUADPACK's extrapolation handles), at a penetration of 30 % of a."""
    b, k, u = b_over_a * A, 1e3, 1.0  # u/sqrt(k) = 0.32 a
    rmin = float(sc.soft_sphere_turning_point(b, A, k, u))

    def integrand(r):
        g = 1 - b * b / (r * r) - k / u**2 * (A - r) ** 2
        return b / (r * r * np.sqrt(g))

    inner = integrate.quad(integrand, rmin, A, epsabs=1e-12, epsrel=1e-12, limit=500)[0]
    theta = np.pi - 2 * (np.arcsin(b / A) + inner)
    assert float(sc.soft_sphere_cm_angle(b, A, k, u)) == pytest.approx(theta, abs=1e-9)


def test_soft_sphere_tends_to_hard_sphere_as_k_to_infinity_like_k_to_minus_half():
    """theta_hard - theta_soft = pi (b/a) u / (a sqrt(k)) (1 + O(k^-1/2)): the ratio to the first-order shift
    tends to 1 and the fitted exponent of the shift to -1/2."""
    b = np.array([0.2, 0.5, 0.8, 0.95]) * A
    ks = np.array([1e6, 1e8, 1e10, 1e12])
    shifts = np.array([sc.hard_sphere_cm_angle(b, A) - sc.soft_sphere_cm_angle(b, A, k, 1.0) for k in ks])
    first = np.array([sc.soft_sphere_shift_first_order(b, A, k, 1.0) for k in ks])
    ratio_error = np.abs(shifts / first - 1)
    assert (ratio_error[-1] < 1e-4).all()
    # The relative error of the first-order shift is itself O(k^-1/2): x100 in k divides it by 10.
    np.testing.assert_allclose(ratio_error[2:] / ratio_error[1:-1], 0.1, rtol=0.05)
    exponents = np.diff(np.log(shifts), axis=0) / np.diff(np.log(ks))[:, None]
    np.testing.assert_allclose(exponents[-1], -0.5, atol=1e-4)


def test_soft_sphere_head_on_and_miss():
    """b = 0 bounces straight back for any stiffness; b >= a does not scatter."""
    assert float(sc.soft_sphere_cm_angle(0.0, A, 1e4, 1.0)) == pytest.approx(np.pi, abs=1e-13)
    assert float(sc.soft_sphere_cm_angle(A, A, 1e4, 1.0)) == 0.0


def test_soft_sphere_refuses_pass_through():
    with pytest.raises(ValueError, match="penetration"):
        sc.soft_sphere_cm_angle(0.01, A, 1.0, 1.0)


def test_relative_motion_matches_quadrature():
    """The ODE solution the env scores against gives the C8 deflection."""
    b, k, u = 0.05, 1e8, 1.0
    x0 = -np.sqrt(A * A - b * b) - 1e-4
    motion = sc.soft_sphere_relative_motion([x0, b, 0], [u, 0, 0], A, k, 1e-3)
    _, v = motion(1e-3)
    assert np.arctan2(v[1], v[0]) == pytest.approx(float(sc.soft_sphere_cm_angle(b, A, k, u)), abs=1e-9)
