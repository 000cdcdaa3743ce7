"""The pendulum and coupled-oscillation closed forms alone (docs/theory.md O1-O7): limits, identities, and an
independent reference (scipy's solve_ivp of the full nonlinear equations), before any simulator is involved."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rigidbench.analytic import oscillations as osc

G = 9.81


def _nonlinear_half_period(length: float, g: float, amplitude: float) -> float:
    """Time from release at rest at `amplitude` to the opposite turning point: DOP853, rtol = atol = 1e-12."""

    def rhs(_t, y):
        return [y[1], -(g / length) * np.sin(y[0])]

    def turning(_t, y):
        return y[1]

    turning.direction = 1.0  # theta' goes from negative to zero at -amplitude
    t_max = 10 * osc.pendulum_period(length, g, amplitude)
    sol = solve_ivp(rhs, (0, t_max), [amplitude, 0.0], method="DOP853", rtol=1e-12, atol=1e-12, events=turning)
    return float(sol.t_events[0][0])


# ---- O1: the exact pendulum --------------------------------------------------------------------------------


def test_small_amplitude_period_tends_to_2_pi_sqrt_l_over_g():
    for length in (0.1, 1.0, 7.0):
        t0 = 2 * np.pi * np.sqrt(length / G)
        assert osc.pendulum_period(length, G, 1e-8) == pytest.approx(t0, rel=1e-15)
        assert osc.small_amplitude_period(length, G) == pytest.approx(t0, rel=1e-15)


def test_exact_period_follows_its_series_with_the_stated_error():
    """docs/theory.md O1: the two-term series errs by 2.4e-4 at 1 rad and 7 % at 2.5 rad; by ~a^6 at small a."""
    for amplitude, err in ((1.0, 2.4e-4), (2.5, 0.07)):
        exact = osc.pendulum_period(1.0, G, amplitude)
        assert abs(osc.pendulum_period_series(1.0, G, amplitude) / exact - 1) == pytest.approx(err, rel=0.05)
    exact = osc.pendulum_period(1.0, G, 0.05)
    assert abs(osc.pendulum_period_series(1.0, G, 0.05) / exact - 1) < 0.05**6


@pytest.mark.parametrize("amplitude", [0.1, 1.0, 2.5, 3.0, 3.1])
def test_exact_period_equals_solve_ivp_of_the_nonlinear_pendulum(amplitude):
    """docs/theory.md check H1: an independent integration of th'' = -(g/l) sin th gives the same period."""
    period = osc.pendulum_period(0.8, G, amplitude)
    assert 2 * _nonlinear_half_period(0.8, G, amplitude) == pytest.approx(period, rel=1e-9)


def test_jacobi_solution_equals_solve_ivp_of_the_nonlinear_pendulum():
    amplitude, length = 2.5, 1.3
    t = np.linspace(0, 3 * osc.pendulum_period(length, G, amplitude), 200)
    sol = solve_ivp(
        lambda _t, y: [y[1], -(G / length) * np.sin(y[0])],
        (0, t[-1]),
        [amplitude, 0.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        t_eval=t,
    )
    np.testing.assert_allclose(osc.pendulum_angle(t, length, G, amplitude), sol.y[0], atol=1e-9)


def test_amplitude_at_or_beyond_upright_has_no_period():
    with pytest.raises(ValueError, match="amplitude"):
        osc.pendulum_period(1.0, G, np.pi)


# ---- O3, O4: two coupled pendulums -----------------------------------------------------------------------


def test_coupled_pendulums_with_d_equal_l_are_wilcox_coupled_masses():
    """Wilcox section 12.3: omega^2 = k/M (symmetric) and (k + 2 k12)/M, with k = M g / l, k12 the spring."""
    m, length, k12 = 0.7, 1.2, 3.0
    ws, wa = osc.coupled_frequencies(m * length**2, m * G * length, k12, length)
    assert ws**2 == pytest.approx(G / length, rel=1e-15)
    assert wa**2 == pytest.approx((m * G / length + 2 * k12) / m, rel=1e-15)


def test_two_pendulum_chain_is_the_coupled_pair_and_its_modes_are_plus_minus_one():
    i_o, mgl, k, d = 1.1, 9.0, 2.3, 0.4
    modes = osc.normal_modes(*osc.spring_chain_matrices(2, i_o, mgl, k, d))
    np.testing.assert_allclose(modes.frequencies, osc.coupled_frequencies(i_o, mgl, k, d), rtol=1e-14)
    np.testing.assert_allclose(modes.shape_ratios()[1], [1.0, -1.0], atol=1e-14)


def test_beat_formula_is_the_linear_normal_mode_solution():
    """docs/theory.md O4 is exact for the linear system: it equals the O7 modal solution from (A, 0) at rest."""
    i_o, mgl, k, d, a = 1.0, G, 1.0, 0.5, 1e-3
    modes = osc.normal_modes(*osc.spring_chain_matrices(2, i_o, mgl, k, d))
    beats = osc.Beats(a, *osc.coupled_frequencies(i_o, mgl, k, d))
    t = np.linspace(0, 3 * beats.transfer_time, 5000)
    np.testing.assert_allclose(beats.angles(t), modes.angles(t, np.array([a, 0.0])), atol=1e-15)


def test_all_the_energy_is_in_pendulum_2_at_the_transfer_time():
    beats = osc.Beats(1e-3, *osc.coupled_frequencies(1.0, G, 0.7, 0.5))
    assert beats.transfer_time == pytest.approx(np.pi / (beats.omega_a - beats.omega_s), rel=1e-15)
    th1, th2 = beats.angles(np.array([beats.transfer_time]))[0]
    assert abs(th1) < 1e-15  # pendulum 1's envelope A cos(omega_b t) is zero at T_x
    assert beats.envelope2(np.array([beats.transfer_time]))[0] == pytest.approx(1e-3, rel=1e-15)


def test_weak_coupling_beat_rate_tends_to_kappa_over_omega_s():
    """docs/theory.md O4: omega_a - omega_s ~ kappa / omega_s for kappa = k d^2 / (m l^2) << g / l."""
    for k in (1e-2, 1e-3):
        ws, wa = osc.coupled_frequencies(1.0, G, k, 0.5)
        kappa = k * 0.25
        assert (wa - ws) / (kappa / ws) == pytest.approx(1.0, abs=2 * kappa / G)


# ---- O5, O7: the chain --------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [2, 3, 5, 7, 12])
def test_chain_closed_form_equals_the_generalised_eigenproblem(n):
    """docs/theory.md O5 equals O7's det(V - omega^2 T) = 0, frequencies and shapes (check H5)."""
    i_o, mgl, k, d = 0.9, 7.5, 3.7, 0.42
    modes = osc.normal_modes(*osc.spring_chain_matrices(n, i_o, mgl, k, d))
    np.testing.assert_allclose(modes.frequencies, osc.chain_frequencies(n, i_o, mgl, k, d), rtol=1e-13)
    unit = modes.shapes / np.linalg.norm(modes.shapes, axis=0)
    overlap = np.abs(np.sum(unit * osc.chain_shapes(n), axis=0))
    np.testing.assert_allclose(overlap, 1.0, atol=1e-12)


def test_chain_lowest_mode_has_unstretched_springs():
    w = osc.chain_frequencies(6, 1.0, G, 100.0, 0.5)
    assert w[0] == pytest.approx(np.sqrt(G), rel=1e-15)
    np.testing.assert_allclose(osc.chain_shapes(6)[:, 0], 1 / np.sqrt(6), rtol=1e-15)


def test_eigenproblem_reproduces_wilcox_12_5_two_masses_three_springs():
    """Wilcox section 12.5 (wall-k-m-k-m, equivalently the LC circuit): omega^2 = (3 -+ sqrt 5) k / (2 m)."""
    m, k = 2.0, 5.0
    modes = osc.normal_modes(np.diag([m, m]), np.array([[2 * k, -k], [-k, k]]))
    np.testing.assert_allclose(modes.frequencies**2, (3 - np.array([1, -1]) * np.sqrt(5)) * k / (2 * m), rtol=1e-14)
    np.testing.assert_allclose(modes.shapes.T @ modes.inertia @ modes.shapes, np.eye(2), atol=1e-14)  # eq. 12.22


def test_normal_coordinates_decouple_the_linear_motion():
    """O7 / Wilcox eq. 12.26: the modal solution satisfies T th'' + V th = 0 (checked by finite differences)."""
    T, V = osc.double_pendulum_matrices(1.0, 0.4, 1.0, 0.7, G)
    modes = osc.normal_modes(T, V)
    h = 1e-4
    t = np.array([0.3 - h, 0.3, 0.3 + h])
    th = modes.angles(t, np.array([1e-3, -2e-3]), np.array([0.01, 0.0]))
    acc = (th[0] - 2 * th[1] + th[2]) / h**2
    np.testing.assert_allclose(T @ acc, -V @ th[1], atol=1e-8 * np.abs(V @ th[1]).max())


def test_unstable_equilibrium_is_refused():
    with pytest.raises(ValueError, match="positive definite"):
        osc.normal_modes(np.eye(2), -np.eye(2))


# ---- O6: the double pendulum --------------------------------------------------------------------------------


def test_double_pendulum_equal_masses_and_lengths_give_2_minus_plus_sqrt_2():
    """Wilcox prob. 12.4: omega^2 = (g/l)(2 -+ sqrt 2), shapes th2/th1 = +-sqrt 2."""
    length = 0.8
    w = osc.double_pendulum_frequencies(1.3, 1.3, length, length, G)
    np.testing.assert_allclose(w**2, (G / length) * (2 - np.array([1, -1]) * np.sqrt(2)), rtol=1e-14)
    modes = osc.normal_modes(*osc.double_pendulum_matrices(1.3, 1.3, length, length, G))
    np.testing.assert_allclose(modes.shape_ratios()[1], [np.sqrt(2), -np.sqrt(2)], rtol=1e-13)


@pytest.mark.parametrize("m1, m2, l1, l2", [(1.0, 0.3, 1.0, 0.6), (0.2, 5.0, 0.3, 2.0), (1.0, 1e-3, 1.0, 1.0)])
def test_double_pendulum_quartic_equals_the_eigenproblem(m1, m2, l1, l2):
    """docs/theory.md O6's quartic is O7 for point bobs (check H6a-d)."""
    modes = osc.normal_modes(*osc.double_pendulum_matrices(m1, m2, l1, l2, G))
    np.testing.assert_allclose(osc.double_pendulum_frequencies(m1, m2, l1, l2, G), modes.frequencies, rtol=1e-13)


def test_light_lower_bob_leaves_two_independent_pendulums():
    """m2 -> 0: the upper pendulum swings at sqrt(g/l1), the lower one on it at sqrt(g/l2)."""
    w = osc.double_pendulum_frequencies(1.0, 1e-9, 1.0, 0.5, G)
    np.testing.assert_allclose(w, np.sqrt([G / 1.0, G / 0.5]), rtol=1e-6)


def test_double_pendulum_small_oscillations_equal_solve_ivp_of_the_nonlinear_equations():
    """An independent reference: the full Lagrange equations of the double pendulum (point bobs), integrated by
    DOP853 from the slow mode's shape at 1e-5 rad, return to the start after one predicted period."""
    m1, m2, l1, l2 = 1.0, 0.5, 1.0, 0.7
    modes = osc.normal_modes(*osc.double_pendulum_matrices(m1, m2, l1, l2, G))

    def rhs(_t, y):
        a, b, wa, wb = y
        c, s = np.cos(a - b), np.sin(a - b)
        mass = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2 * c], [m2 * l1 * l2 * c, m2 * l2**2]])
        force = np.array(
            [
                -m2 * l1 * l2 * s * wb**2 - (m1 + m2) * G * l1 * np.sin(a),
                m2 * l1 * l2 * s * wa**2 - m2 * G * l2 * np.sin(b),
            ]
        )
        return [wa, wb, *np.linalg.solve(mass, force)]

    for r in range(2):
        y0 = [*(1e-5 * modes.shape_ratios()[:, r]), 0.0, 0.0]
        period = 2 * np.pi / modes.frequencies[r]
        sol = solve_ivp(rhs, (0, period), y0, method="DOP853", rtol=1e-13, atol=1e-16)
        np.testing.assert_allclose(sol.y[:2, -1], y0[:2], atol=1e-5 * 1e-6)


# ---- beyond the linear theory (issue 13) ---------------------------------------------------------------------


def test_anti_phase_period_is_the_elliptic_period_without_spring_and_the_linear_one_at_small_amplitude():
    for a in (1e-3, 0.5, 1.0):
        assert osc.anti_phase_period(1.0, G, 0.0, 0.5, a) == pytest.approx(osc.pendulum_period(1.0, G, a), rel=1e-12)
    linear = 2 * np.pi / osc.coupled_frequencies(1.0, G, 1.0, 0.5)[1]
    assert osc.anti_phase_period(1.0, G, 1.0, 0.5, 1e-6) == pytest.approx(linear, rel=1e-12)


def test_anti_phase_period_equals_solve_ivp_of_the_level_spring_motion():
    """I th'' = -(M g h sin th + 2 k d^2 sin th cos th) (V = 2 M g h (1 - cos th) + 2 k d^2 sin^2 th, kinetic I th'^2),
    from rest at 0.8 rad: the first return to th = 0.8 rad is the period."""
    inertia, mgl, k, d, a = 1.3, 2.0 * G, 7.0, 0.4, 0.8

    def rhs(t, y):
        return [y[1], -(mgl * np.sin(y[0]) + 2 * k * d**2 * np.sin(y[0]) * np.cos(y[0])) / inertia]

    def back(t, y):
        return y[1]

    back.direction = -1  # th' falls through 0 at the release turning point: t = 0, T, 2T, ...
    period = osc.anti_phase_period(inertia, mgl, k, d, a)
    sol = solve_ivp(rhs, (0, 1.5 * period), [a, 0.0], rtol=1e-12, atol=1e-14, events=back, dense_output=True)
    returns = [t for t in sol.t_events[0] if t > 0.5 * period]
    assert returns[0] == pytest.approx(period, rel=1e-9)


def test_first_order_amplitude_shift_is_a_squared_over_16_for_a_lone_pendulum_and_the_closed_forms_for_beats():
    modes = osc.normal_modes(np.eye(1), G * np.eye(1))
    shift = osc.amplitude_shifts(modes, osc.spring_chain_quartic(G, 0.0, 0.0), [1e-3])
    assert shift[0] == pytest.approx(-(1e-3**2) / 16, rel=1e-6)
    for k in (0.25, 1.0, 20.0):
        kappa = k * 0.25 / G
        modes = osc.coupled_modes(1.0, G, k, 0.5)
        q = modes.coordinates(np.array([1e-3, 0.0]))
        s, a = osc.amplitude_shifts(modes, osc.spring_chain_quartic(G, k, 0.5), q), 1e-3
        assert s[0] == pytest.approx(-(0.75 + 2 * kappa) * a**2 / 16, rel=1e-5)
        assert s[1] == pytest.approx(-(0.75 + 4 * kappa) * a**2 / (16 + 32 * kappa), rel=1e-5)


def test_first_order_amplitude_shift_of_the_double_pendulum_fast_mode_is_the_measured_minus_1p85_a1_squared():
    modes = osc.normal_modes(*osc.double_pendulum_matrices(1.0, 1.0, 1.0, 1.0, G))
    a1 = 1e-4
    q = modes.coordinates(np.array([a1, a1 * modes.shape_ratios()[1, 1]]))
    shift = osc.amplitude_shifts(modes, osc.double_pendulum_quartic(1.0, 1.0, 1.0, 1.0, G), q)
    assert shift[1] / a1**2 == pytest.approx(-1.85, abs=0.01)


def test_exact_mode_shapes_hold_however_weak_the_coupling():
    modes = osc.coupled_modes(1.0, G, 1e-20, 0.5)
    np.testing.assert_allclose(modes.shape_ratios()[1], [1.0, -1.0], rtol=0, atol=0)
    assert osc.Beats(1e-3, G, G).transfer_time == np.inf
    chain = osc.chain_modes(6, 1.0, G, 1e-20, 0.5)
    np.testing.assert_allclose(chain.shapes.T @ chain.inertia @ chain.shapes, np.eye(6), atol=1e-14)


def test_the_exact_pendulum_keeps_its_names_in_oscillations():
    """`analytic/pendulum.py` holds O1; `rigidbench.analytic.oscillations` re-exports it (the old import path)."""
    from rigidbench.analytic import pendulum

    for name in ("small_amplitude_period", "pendulum_period", "pendulum_period_series", "pendulum_angle"):
        assert getattr(osc, name) is getattr(pendulum, name)
