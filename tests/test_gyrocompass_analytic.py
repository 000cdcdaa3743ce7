"""The gyrocompass closed forms alone (docs/theory.md G1), before any simulator: the exact hunting equation against an
independent numerical Lagrangian of the two rigid bodies, the quadrature period against scipy's solve_ivp, the
limits (small amplitude, B = 0), the first integral, and the platform's momentum swing."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from rigidbench.analytic import gyrocompass as gc

# The default spin (50 rad/s) gives B / A = 5e-3; the Lagrangian test spins at 2 rad/s, B / A ~ 0.1, so that both
# terms of the hunting equation are large in it.
I_A, I_T, I_G = 0.018, 0.01, 0.005
OMEGA, LAT = 0.5, 0.6


def _compass(spin_rate: float = 50.0, azimuth: float = 0.0) -> gc.Gyrocompass:
    omega_perp = OMEGA * np.cos(LAT)
    return gc.Gyrocompass(I_T, I_G, gc.spin_momentum(I_A, spin_rate, omega_perp, azimuth), omega_perp)


# ---- an independent model: the kinetic energy of gimbal and rotor from rotation matrices ----------------------


def _rot(axis, angle):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


N_AXIS = np.array([0.0, np.cos(LAT), np.sin(LAT)])  # East, North, Up


def _bodies(q, qd, t):
    """World-frame rotations and angular velocities of gimbal and rotor: platform about n at OMEGA t, gimbal about
    the platform's -z by alpha = q[0], rotor about the gimbal's y by chi = q[1]."""
    r_p = _rot(N_AXIS, OMEGA * t)
    r_g = r_p @ _rot([0, 0, -1], q[0])
    r_r = r_g @ _rot([0, 1, 0], q[1])
    w_g = OMEGA * N_AXIS + r_p @ np.array([0, 0, -1.0]) * qd[0]
    w_r = w_g + r_g @ np.array([0, 1.0, 0]) * qd[1]
    return r_g, w_g, r_r, w_r


def _kinetic(q, qd, t):
    r_g, w_g, r_r, w_r = _bodies(q, qd, t)
    inertia_g = np.diag([I_G, I_G, I_G])
    inertia_r = np.diag([I_T, I_A, I_T])  # spin axis = body y
    return 0.5 * w_g @ r_g @ inertia_g @ r_g.T @ w_g + 0.5 * w_r @ r_r @ inertia_r @ r_r.T @ w_r


def _lagrange_acceleration(q, qd, t, h=1e-4):
    """q'' from d/dt dT/dqd - dT/dq = 0, every derivative by central differences (T is quadratic in qd, so the
    mass matrix is exact to round-off; the mixed terms are O(h^2))."""
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    e = np.eye(2)

    def dT_dqd(q_, qd_, t_):
        return np.array(
            [(_kinetic(q_, qd_ + h * e[i], t_) - _kinetic(q_, qd_ - h * e[i], t_)) / (2 * h) for i in (0, 1)]
        )

    mass = np.array([(dT_dqd(q, qd + h * e[j], t) - dT_dqd(q, qd - h * e[j], t)) / (2 * h) for j in (0, 1)]).T
    mixed = sum(qd[j] * (dT_dqd(q + h * e[j], qd, t) - dT_dqd(q - h * e[j], qd, t)) / (2 * h) for j in (0, 1))
    explicit = (dT_dqd(q, qd, t + h) - dT_dqd(q, qd, t - h)) / (2 * h)
    dT_dq = np.array([(_kinetic(q + h * e[i], qd, t) - _kinetic(q - h * e[i], qd, t)) / (2 * h) for i in (0, 1)])
    return np.linalg.solve(mass, dT_dq - mixed - explicit), dT_dqd(q, qd, t)


@pytest.mark.parametrize("alpha", [0.3, 1.2, 2.6, -2.0])
def test_hunting_equation_equals_an_independent_numerical_lagrangian(alpha):
    """docs/theory.md G1's exact equation and H, against Euler-Lagrange of the gimbal and rotor built from rotation
    matrices (no hand algebra): both terms A and B, at B / A ~ 0.1."""
    rng = np.random.default_rng(int(1000 * abs(alpha)))
    alpha_dot, chi_dot, t = rng.normal(0, 2.0), 2.0, rng.uniform(0, 5)
    qdd, momenta = _lagrange_acceleration([alpha, 0.7], [alpha_dot, chi_dot], t)
    compass = _compass(chi_dot, alpha)
    assert 0.05 < compass.B / compass.A < 0.2
    assert momenta[1] == pytest.approx(compass.spin_momentum, rel=1e-9)  # dT/dchi' = H
    # the equation with I_t + I_g on the left, per unit of it: alpha'' = -A sin + B sin cos
    assert qdd[0] == pytest.approx(float(compass.acceleration(alpha)), rel=1e-6, abs=1e-6 * compass.A)
    # H conserved: chi'' = -d/dt (Omega_perp cos alpha) = Omega_perp sin(alpha) alpha'
    assert qdd[1] == pytest.approx(OMEGA * np.cos(LAT) * np.sin(alpha) * alpha_dot, rel=1e-6, abs=1e-6)


def _half_period(compass: gc.Gyrocompass, amplitude: float) -> float:
    """Time from rest at +amplitude to rest at -amplitude: DOP853 on the hunting equation, rtol = atol = 1e-12."""

    def turning(_t, y):
        return y[1]

    turning.direction = 1.0
    sol = solve_ivp(
        lambda _t, y: [y[1], float(compass.acceleration(y[0]))],
        (0, 50.0),
        [amplitude, 0.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        events=turning,
    )
    return float(sol.t_events[0][0])


@pytest.mark.parametrize("amplitude", [0.02, 1.0, 2.5, 3.0])
def test_quadrature_period_equals_solve_ivp_of_the_hunting_equation(amplitude):
    """docs/theory.md check E1c: the period by quadrature at 0.02 .. 3 rad."""
    compass = _compass()
    assert compass.period(amplitude) == pytest.approx(2 * _half_period(compass, amplitude), rel=1e-10)


def test_with_B_zero_the_period_is_the_pendulums_elliptic_one():
    """B = 0 (no transverse rotor moment): V = -A cos alpha, a pendulum, T = 4 K(sin(a/2)) / sqrt(A) (docs/theory.md
    O1)."""
    compass = gc.Gyrocompass(0.0, I_G, 0.9, 0.4)
    for amplitude in (0.1, 1.5, 2.9):
        expected = 4 * ellipk(np.sin(amplitude / 2) ** 2) / np.sqrt(compass.A)
        assert compass.period(amplitude) == pytest.approx(expected, rel=1e-12)


def test_small_amplitude_period_tends_to_2_pi_over_omega_g_with_the_stated_shift():
    """T(a) = T0 (1 + ((A - 4B)/(A - B)) a^2/16 + O(a^4)), T0 = 2 pi / omega_g, omega_g^2 = A - B."""
    compass = _compass()
    t0 = 2 * np.pi / compass.hunting_frequency
    assert compass.hunting_frequency**2 == pytest.approx(
        OMEGA * np.cos(LAT) * (compass.spin_momentum - I_T * OMEGA * np.cos(LAT)) / (I_T + I_G), rel=1e-14
    )
    assert compass.period(1e-7) == pytest.approx(t0, rel=1e-13)
    for a in (0.01, 0.02, 0.05):
        shift = compass.period(a) / t0 - 1
        assert shift == pytest.approx(compass.small_amplitude_shift(a), rel=a**2)  # the next term is O(a^4)


def test_fast_rotor_approaches_the_simple_frequency_within_I_t_Omega_over_2H():
    """docs/theory.md G1: the simple form sqrt(H Omega_perp / (I_t + I_g)) differs by ~ I_t Omega_perp / (2 H)."""
    for spin in (100.0, 1e3, 1e4):
        compass = _compass(spin)
        expected = I_T * compass.omega_perp / (2 * compass.spin_momentum)
        rel = compass.simple_frequency / compass.hunting_frequency - 1
        assert rel == pytest.approx(expected, rel=2 * expected)


@pytest.mark.parametrize(("azimuth0", "rate0"), [(0.5, 0.0), (2.5, 0.0), (0.2, 3.0), (-1.0, -4.0)])
def test_turning_angle_from_the_first_integral_equals_solve_ivp(azimuth0, rate0):
    compass = _compass()
    sol = solve_ivp(
        lambda _t, y: [y[1], float(compass.acceleration(y[0]))],
        (0, 2 * compass.period(2.5)),
        [azimuth0, rate0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        dense_output=True,
    )
    t = np.linspace(0, sol.t[-1], 200_001)
    assert np.abs(sol.sol(t)[0]).max() == pytest.approx(compass.turning_angle(azimuth0, rate0), rel=1e-8)


def test_azimuth_trajectory_returns_after_one_quadrature_period():
    compass = _compass()
    for amplitude in (0.3, 2.5):
        period = compass.period(amplitude)
        alpha = compass.azimuth(np.array([0.0, period / 2, period, 3 * period]), amplitude)
        assert alpha == pytest.approx([amplitude, -amplitude, amplitude, amplitude], abs=1e-9 * amplitude)


def test_a_rotor_too_slow_for_the_platform_has_no_north_seeking_equilibrium():
    omega_perp = OMEGA * np.cos(LAT)
    slow = gc.Gyrocompass(I_T, I_G, 0.5 * I_T * omega_perp, omega_perp)  # H < I_t Omega_perp: A < B
    assert not slow.north_seeking
    with pytest.raises(ValueError, match="North is not a stable equilibrium"):
        slow.period(0.1)
    with pytest.raises(ValueError, match="passes over alpha = pi"):
        _compass().turning_angle(3.0, 40.0)


def test_momentum_along_the_axis_and_its_swing_bound_match_the_rotation_matrices():
    """The gyro's angular momentum along n, closed form against the one computed from rotation matrices along the
    hunting; and the swing bound: never below the swing, and not loose by more than the signed terms it adds (at
    most a factor 1.3 here)."""
    compass = _compass()
    for amplitude in (0.5, 2.5):
        t = np.linspace(0, compass.period(amplitude), 4001)
        sol = solve_ivp(
            lambda _t, y: [y[1], float(compass.acceleration(y[0]))],
            (0, t[-1]),
            [amplitude, 0.0],
            method="DOP853",
            rtol=1e-12,
            atol=1e-12,
            t_eval=t,
        )
        alpha, alpha_dot = sol.y
        omega_perp = compass.omega_perp
        chi_dot = compass.spin_momentum / I_A - omega_perp * np.cos(alpha)  # H conserved
        along = []
        for a, ad, cd, ti in zip(alpha, alpha_dot, chi_dot, t, strict=True):
            r_g, w_g, r_r, w_r = _bodies([a, 0.0], [ad, cd], ti)
            momentum = r_g @ np.diag([I_G] * 3) @ r_g.T @ w_g + r_r @ np.diag([I_T, I_A, I_T]) @ r_r.T @ w_r
            along.append(momentum @ N_AXIS)
        along = np.array(along)
        exact = gc.momentum_along_axis(I_T, I_G, compass.spin_momentum, OMEGA, LAT, alpha, alpha_dot)
        assert exact == pytest.approx(along, rel=1e-13, abs=1e-13 * np.abs(along).max())
        swing = np.max(np.abs(along - along[0]))
        bound = gc.platform_momentum_swing(
            I_T, I_G, compass.spin_momentum, OMEGA, LAT, amplitude, compass.max_rate(amplitude)
        )
        assert swing <= bound <= 1.3 * swing


# ---- the compass as built, and the scales of a run ------------------------------------------------------------


@pytest.mark.parametrize("lat", [0.0, 0.6, -1.2])
def test_axes_geometry_of_a_platform_axis_in_the_meridian_plane(lat):
    """n = (0, cos lat, sin lat) in East-North-Up with the spin axis North at zero gimbal angle: latitude lat,
    horizontal fraction cos(lat), North at gimbal angle 0; turned East by 0.3 rad, North is at -0.3."""
    n, up = np.array([0.0, np.cos(lat), np.sin(lat)]), np.array([0.0, 0.0, 1.0])
    latitude, horizontal, north = gc.axes_geometry(3.0 * n, up, np.array([0.0, 1.0, 0.0]))
    assert latitude == pytest.approx(lat, abs=1e-15)
    assert horizontal == pytest.approx(np.cos(lat), abs=1e-15)
    assert north == pytest.approx(0.0, abs=1e-15)
    spin0 = np.array([np.sin(0.3), np.cos(0.3), 0.0])  # the spin axis 0.3 rad East of North at zero gimbal angle
    assert gc.axes_geometry(n, up, spin0)[2] == pytest.approx(-0.3, abs=1e-15)


def test_gyroscopic_roundoff_is_eps_times_the_spin_over_the_restoring_rate():
    eps = np.finfo(float).eps
    assert gc.gyroscopic_roundoff(50.0, 0.4, np.pi / 2) == pytest.approx(eps * 50.0 / 0.4, rel=1e-15)
    assert gc.gyroscopic_roundoff(50.0, 0.4, 0.0) == np.inf


def test_period_sensitivity_tends_to_a_squared_over_8_for_the_pendulum():
    """With B = 0 the hunting is the pendulum (T ~ T0 (1 + a^2 / 16)): d ln T / d ln a -> a^2 / 8."""
    compass = gc.Gyrocompass(1e-9, 1.0, 2.0, 0.5)  # B / A = I_t Omega_perp / H = 2.5e-10
    a = 0.01
    assert gc.period_sensitivity(compass, a) == pytest.approx(a * a / 8, rel=1e-3)
    assert gc.period_sensitivity(compass, 0.0) == 0.0
    assert gc.fastest_rate(compass, a) == compass.hunting_frequency  # small swings: omega_g is the fastest rate
