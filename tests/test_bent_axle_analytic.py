"""The bent axle's closed forms (docs/theory.md R8) alone, against independent numerics: quadrature of a tilted disc's
inertia, Newton's second law summed over a cloud of point masses, and the numerical time derivative of L."""

import numpy as np
import pytest
from scipy import integrate
from scipy.spatial.transform import Rotation

from rigidbench.analytic import bent_axle as ba

RNG = np.random.default_rng(16)


def _cloud(n=7, rng=RNG):
    """n point masses (kg) at positions (m) in the rotor's axes, z along the axle."""
    return rng.uniform(0.1, 2.0, n), rng.uniform(-1.0, 1.0, (n, 3))


def _cloud_inertia(masses, positions):
    """The inertia tensor about O of point masses, summed term by term: sum m (|r|^2 1 - r r^T)."""
    return sum(m * (r @ r * np.eye(3) - np.outer(r, r)) for m, r in zip(masses, positions, strict=True))


def test_harter_fig_6_5_1_point_mass_needs_half_m_r2_omega2():
    """A8a-d: a point mass at r (1/sqrt 2, 1/sqrt 2, 0) on an axle along x. In the axle-z axes used here it sits
    at rho = a = r / sqrt 2: |N| = m omega^2 a rho = 1/2 m r^2 omega^2, perpendicular to the axle and to the arm."""
    m, r, omega = 1.3, 0.7, 4.1
    com = np.array([r / np.sqrt(2), 0.0, r / np.sqrt(2)])
    inertia = ba.inertia_about_point(m, np.zeros(3), np.eye(3), com)
    torque = ba.bearing_torque(inertia, omega)
    harter = ba.point_mass_torque(m, r, omega)
    assert np.linalg.norm(torque) == pytest.approx(np.linalg.norm(harter), rel=1e-15)
    assert torque[2] == 0.0 and torque @ com == pytest.approx(0.0, abs=1e-15)
    # Harter's own axes (axle x, arm in xy): the same tensor algebra gives his -1/2 m r^2 omega^2 z exactly.
    arm = r * np.array([1, 1, 0]) / np.sqrt(2)
    i_harter = m * (arm @ arm * np.eye(3) - np.outer(arm, arm))
    w = np.array([omega, 0.0, 0.0])
    np.testing.assert_allclose(np.cross(w, i_harter @ w), harter, rtol=1e-15, atol=1e-15)


def test_torque_is_newtons_law_summed_over_a_cloud_of_point_masses():
    """N = sum r x m a with a = omega x (omega x r) (Newton, no tensors) equals omega x (I_O omega) (R8)."""
    for _ in range(20):
        masses, positions = _cloud()
        omega = RNG.uniform(-30, 30)
        w = omega * ba.Z_AXIS
        accel = np.cross(w, np.cross(w, positions))
        newton_torque = sum(np.cross(r, m * a) for m, r, a in zip(masses, positions, accel, strict=True))
        newton_force = (masses[:, None] * accel).sum(axis=0)
        inertia = _cloud_inertia(masses, positions)
        scale = omega**2 * np.abs(np.linalg.eigvalsh(inertia)).max()
        np.testing.assert_allclose(ba.bearing_torque(inertia, omega), newton_torque, rtol=0, atol=1e-14 * scale)
        com = (masses[:, None] * positions).sum(axis=0) / masses.sum()
        np.testing.assert_allclose(
            ba.bearing_force(masses.sum(), com, omega), newton_force, rtol=0, atol=1e-14 * np.abs(newton_force).max()
        )


def test_principal_form_with_parallel_axes_rebuilds_the_clouds_tensor():
    """The scenario's route: principal moments about the CoM, their axes, the CoM, then the parallel-axis theorem,
    gives the cloud's tensor about O summed directly."""
    masses, positions = _cloud(9)
    mass = masses.sum()
    com = (masses[:, None] * positions).sum(axis=0) / mass
    inertia_cm = _cloud_inertia(masses, positions - com)
    moments, axes = np.linalg.eigh(inertia_cm)
    rebuilt = ba.inertia_about_point(mass, moments, axes, com)
    np.testing.assert_allclose(rebuilt, _cloud_inertia(masses, positions), rtol=0, atol=1e-14)


def test_tilted_disc_products_of_inertia_by_quadrature():
    """A thin uniform disc (radius R, mass m) with its axis tilted by `tilt` from the axle about x: I_yz by scipy's
    double quadrature over the disc, against (I2 - I3) sin cos from the principal form (I2 = m R^2/4, I3 = m R^2/2)."""
    m, radius, tilt = 2.0, 0.3, 0.37
    rot = ba.tilted_principal_frame(tilt)
    sigma = m / (np.pi * radius**2)

    def product(i, j):
        def integrand(s, phi):  # polar coordinates in the disc's plane, turned into the axle frame
            p = rot @ np.array([s * np.cos(phi), s * np.sin(phi), 0.0])
            return -sigma * p[i] * p[j] * s

        return integrate.dblquad(integrand, 0, 2 * np.pi, 0, radius, epsabs=1e-14, epsrel=1e-12)[0]

    principal = np.array([m * radius**2 / 4, m * radius**2 / 4, m * radius**2 / 2])
    inertia = ba.inertia_about_point(m, principal, rot, np.zeros(3))
    assert product(1, 2) == pytest.approx(inertia[1, 2], rel=1e-10)
    assert product(0, 2) == pytest.approx(inertia[0, 2], abs=1e-14)
    assert inertia[1, 2] == pytest.approx((principal[1] - principal[2]) * np.sin(tilt) * np.cos(tilt), rel=1e-14)


def test_torque_is_the_time_derivative_of_the_angular_momentum_in_space():
    """dL_W/dt by a fourth-order central difference of L_W(t) = Rz(omega t) I_O omega equals the rotating N_W(t)
    (error ~ (omega h)^4 / 30 ~ 1e-13 relative at omega h = 1e-3, plus round-off eps / (omega h) ~ 2e-13)."""
    masses, positions = _cloud()
    inertia = _cloud_inertia(masses, positions)
    omega = -7.3
    axle = ba.BentAxle(masses.sum(), inertia, np.zeros(3), omega, angle0=0.4)
    L_B = inertia @ (omega * ba.Z_AXIS)

    def L_W(t):
        return ba.rotate_about_axle(L_B, axle.angle(t))

    t = np.linspace(0, 2, 9)
    h = 1e-3 / abs(omega)
    derivative = (-L_W(t + 2 * h) + 8 * L_W(t + h) - 8 * L_W(t - h) + L_W(t - 2 * h)) / (12 * h)
    np.testing.assert_allclose(derivative, axle.torque_W(t), rtol=0, atol=1e-11 * axle.torque_scale)


@pytest.mark.parametrize("omega", [3.0, -3.0])
def test_torque_and_force_do_not_depend_on_the_sense_of_rotation(omega):
    masses, positions = _cloud()
    inertia = _cloud_inertia(masses, positions)
    com = positions.mean(axis=0)
    np.testing.assert_array_equal(ba.bearing_torque(inertia, omega), ba.bearing_torque(inertia, abs(omega)))
    np.testing.assert_array_equal(ba.bearing_force(1.0, com, omega), ba.bearing_force(1.0, com, abs(omega)))


def test_limits_untilted_or_symmetric_rotor_needs_no_torque_and_45_degrees_the_most():
    principal = np.array([1.0, 1.5, 2.2])
    sizes = {}
    for tilt in (0.0, np.pi / 8, np.pi / 4, 3 * np.pi / 8, np.pi / 2):
        inertia = ba.inertia_about_point(3.0, principal, ba.tilted_principal_frame(tilt), np.zeros(3))
        sizes[tilt] = ba.BentAxle(3.0, inertia, np.zeros(3), 2.0).torque
    assert sizes[0.0] == 0.0 and sizes[np.pi / 2] == pytest.approx(0.0, abs=1e-15)
    assert sizes[np.pi / 4] == pytest.approx(4.0 * (2.2 - 1.5) / 2, rel=1e-15)  # omega^2 (I3 - I2) / 2
    assert sizes[np.pi / 8] == pytest.approx(sizes[3 * np.pi / 8], rel=1e-14)
    assert sizes[np.pi / 8] == pytest.approx(sizes[np.pi / 4] * np.sin(np.pi / 4), rel=1e-14)  # sin(2 tilt)
    sphere = ba.inertia_about_point(3.0, np.full(3, 1.7), ba.tilted_principal_frame(0.6), np.array([0, 0, 0.4]))
    assert ba.unbalance(sphere) <= 4 * np.finfo(float).eps  # CoM on the axle: no parallel-axis product either


def test_unbalance_never_exceeds_one_half():
    """|I_xz|, |I_yz| of a tensor with eigenvalues in [l_min, l_max] combine to at most (l_max - l_min) / 2."""
    for _ in range(200):
        masses, positions = _cloud(int(RNG.integers(1, 6)))
        assert ba.unbalance(_cloud_inertia(masses, positions)) <= 0.5 + 1e-15


def test_rotation_about_the_axle_matches_scipy():
    v = RNG.normal(size=(5, 3))
    angles = RNG.uniform(-10, 10, 5)
    expected = Rotation.from_rotvec(np.outer(angles, ba.Z_AXIS)).apply(v)
    np.testing.assert_allclose(ba.rotate_about_axle(v, angles), expected, rtol=0, atol=1e-14)
