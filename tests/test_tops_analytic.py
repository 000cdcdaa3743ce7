"""The tops' closed forms alone (docs/theory.md sections 2-4), against limits, identities and an independent ODE.

The independent reference integrates Euler's equations (torque-free) or the Euler-angle Lagrange equations of
the heavy top with scipy's DOP853 at rtol = atol = 1e-12; its own error (~1e-10 over these spans) sets the
tolerances below.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rigidbench.analytic import tops

ODE = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-12, "dense_output": True}


def euler_torque_free(inertia):
    i1, i2, i3 = inertia

    def rhs(_t, w):
        return [(i2 - i3) * w[1] * w[2] / i1, (i3 - i1) * w[2] * w[0] / i2, (i1 - i2) * w[0] * w[1] / i3]

    return rhs


@pytest.mark.parametrize(("i_perp", "i_3"), [(2.0, 0.8), (1.0, 1.7)], ids=["prolate", "oblate"])
def test_symmetric_top_omega_matches_euler_equations(i_perp, i_3):
    omega0 = [0.3, -0.2, 5.0]
    top = tops.symmetric_top(i_perp, i_3, omega0)
    sol = solve_ivp(euler_torque_free((i_perp, i_perp, i_3)), (0, 10), omega0, **ODE)
    t = np.linspace(0, 10, 501)
    assert np.abs(top.omega_body(t) - sol.sol(t).T).max() < 1e-9


def test_symmetric_top_cone_angles_obey_wilcox_11_45():
    """tan(beta) / tan(alpha) = I_perp / I3: prolate beta > alpha, oblate beta < alpha."""
    prolate = tops.symmetric_top(2.0, 0.8, [0.3, 0.2, 5.0])
    oblate = tops.symmetric_top(1.0, 1.7, [0.3, 0.2, 5.0])
    for top in (prolate, oblate):
        ratio = np.tan(top.beta) / np.tan(top.alpha)
        assert ratio == pytest.approx(top.inertia_perp / top.inertia_axial, rel=1e-14)
    assert prolate.beta > prolate.alpha
    assert oblate.beta < oblate.alpha


def test_symmetric_top_precession_rate_matches_wilcox_11_51():
    """phi_dot = |Omega_b| sin(alpha) / |sin(beta - alpha)| (Wilcox 11.51) equals |L| / I_perp."""
    top = tops.symmetric_top(2.0, 0.8, [0.3, 0.2, 5.0])
    wilcox = abs(top.body_rate) * np.sin(top.alpha) / abs(np.sin(top.beta - top.alpha))
    assert top.precession_rate == pytest.approx(wilcox, rel=1e-13)


SIGN_PATTERNS = [[0.3, 1.0, 2.0], [-0.3, 0.5, -2.0], [1.0, -2.0, -0.3], [2.0, 0.5, 0.3], [-2.0, -0.5, 0.3]]


@pytest.mark.parametrize("omega0", SIGN_PATTERNS)
def test_asymmetric_top_elliptic_solution_matches_euler_equations(omega0):
    inertia = (1.0, 2.0, 2.5)
    top = tops.asymmetric_top(inertia, omega0)
    sol = solve_ivp(euler_torque_free(inertia), (0, 30), omega0, **ODE)
    t = np.linspace(0, 30, 1501)
    assert np.abs(top.omega_body(t) - sol.sol(t).T).max() < 1e-8


def test_asymmetric_top_period_is_time_for_omega2_to_repeat():
    inertia = (1.0, 2.0, 2.5)
    top = tops.asymmetric_top(inertia, [0.05, 0.1, 3.0])
    w_later = top.omega_body(np.array([0.3 + top.period]))
    assert np.allclose(w_later, top.omega_body(np.array([0.3])), atol=1e-12, rtol=0)
    half = top.omega_body(np.array([0.3 + top.reversal_time]))[0]
    assert half[1] == pytest.approx(-top.omega_body(np.array([0.3]))[0, 1], rel=1e-10)


@pytest.mark.parametrize("eps", [np.radians(10), np.radians(1), np.radians(0.1)])
def test_harter_kim_flip_time_equals_half_period_of_elliptic_solution(eps):
    """docs/theory.md A3: T_rev = 2 K / s from W (0, cos eps, sin eps) (Harter & Kim eqs 14-17)."""
    inertia = (1.0, 2.0, 2.5)
    spin = 3.0
    top = tops.asymmetric_top(inertia, [0.0, spin * np.cos(eps), spin * np.sin(eps)])
    assert top.about_major
    assert tops.flip_time(inertia, spin, eps) == pytest.approx(top.reversal_time, rel=1e-13)


def test_flip_time_tends_to_logarithmic_law_as_tilt_vanishes():
    """docs/theory.md A3/C6: T_rev ~ (2/lambda) ln(4/k'), with an error that falls like eps^2."""
    inertia = (1.0, 2.0, 2.5)
    i1, i2, i3 = inertia
    lam = tops.intermediate_axis_growth_rate(inertia, 1.0)
    errors = []
    for eps in (1e-2, 1e-3):
        k_prime = eps * np.sqrt(i3 * (i3 - i1) / (i2 * (i2 - i1)))
        approx = 2 / lam * np.log(4 / k_prime)
        errors.append(abs(tops.flip_time(inertia, 1.0, eps) / approx - 1))
    assert errors[1] < errors[0] / 50  # eps^2 scaling would give /100


def test_intermediate_axis_growth_rate_matches_linearised_euler_equations():
    """A4: from omega = (1e-9, 1, 0) the growth over t in [15, 25] is lambda to O(e^{-2 lambda t}) ~ 1e-6."""
    inertia = (1.0, 2.0, 2.5)
    ode = {**ODE, "atol": 1e-22}
    sol = solve_ivp(euler_torque_free(inertia), (0, 25), [1e-9, 1.0, 0.0], **ode)
    t = np.linspace(15, 25, 50)
    slope = np.polyfit(t, np.log(np.abs(sol.sol(t)[0])), 1)[0]
    assert slope == pytest.approx(tops.intermediate_axis_growth_rate(inertia, 1.0), rel=1e-5)


def test_separatrix_start_is_refused():
    with pytest.raises(ValueError, match="separatrix"):
        tops.asymmetric_top((1.0, 2.0, 2.5), [0.0, 1.0, 0.0])


# ---- heavy top ---------------------------------------------------------------------------------------------

I1, I3, MGH = 1.2e-4, 4.5e-5, 0.1 * 9.81 * 0.03


def lagrange_top(i1, i3, mgh, spin):
    """theta, phi, theta_dot with p_phi, p_psi conserved (Wilcox 11.59-11.62), u = cos(theta)."""

    def rhs(_t, y, p_phi):
        theta, _phi, theta_dot = y
        s, c = np.sin(theta), np.cos(theta)
        p_psi = i3 * spin
        phi_dot = (p_phi - p_psi * c) / (i1 * s * s)
        theta_ddot = (phi_dot**2 * s * c * i1 - p_psi * phi_dot * s + mgh * s) / i1
        return [theta_dot, phi_dot, theta_ddot]

    return rhs


@pytest.mark.parametrize(
    ("tilt", "precession", "tilt_rate", "spin"),
    [(0.5, 0.0, 0.0, 150.0), (0.5, -4.7, 0.0, 150.0), (0.7, 3.0, 2.0, 80.0), (0.7, 0.0, 0.0, 40.0)],
    ids=["cusped", "looping", "monotonic-moving-start", "slow-spin"],
)
def test_heavy_top_closed_form_matches_lagrange_equations(tilt, precession, tilt_rate, spin):
    top = tops.heavy_top(I1, I3, MGH, tilt=tilt, tilt_rate=tilt_rate, precession=precession, spin=spin)
    p_phi = I1 * precession * np.sin(tilt) ** 2 + I3 * spin * np.cos(tilt)
    T = 3 * top.nutation_period
    sol = solve_ivp(lagrange_top(I1, I3, MGH, spin), (0, T), [tilt, 0.0, tilt_rate], args=(p_phi,), **ODE)
    t = np.linspace(0, T, 2001)
    theta = sol.sol(t)[0]
    assert np.abs(np.cos(theta) - top.u(t)).max() < 1e-9  # T3: u(t) = u1 + (u2 - u1) sn^2(nu (t - t1))
    assert theta.max() == pytest.approx(top.theta_max, rel=1e-6)  # sampled maximum: grid-limited
    ta = top.t_max_tilt % top.nutation_period  # a time of largest tilt within the first period
    advance = sol.sol(ta + top.nutation_period)[1] - sol.sol(ta)[1]
    assert advance / top.nutation_period == pytest.approx(top.mean_precession_rate, rel=1e-8)


def test_heavy_top_turning_points_are_roots_of_the_cubic():
    top = tops.heavy_top(I1, I3, MGH, tilt=0.7, tilt_rate=2.0, precession=3.0, spin=80.0)
    alpha = top.beta * top.u0 + (2.0**2 + 3.0**2 * np.sin(0.7) ** 2)

    def f(u):
        return (1 - u * u) * (alpha - top.beta * u) - (top.b - top.a * u) ** 2

    for u in top.roots:
        assert abs(f(u)) < 1e-9 * alpha
    u1, u2, u3 = top.roots
    assert -1 <= u1 <= np.cos(0.7) <= u2 <= 1 <= u3


def test_steady_precession_roots_keep_tilt_constant():
    """T4: at either root the cubic has a double root at u0, so theta_max = theta_min = theta0."""
    for root in tops.steady_precession_rates(I1, I3, MGH, 150.0, 0.5):
        top = tops.heavy_top(I1, I3, MGH, tilt=0.5, tilt_rate=0.0, precession=root, spin=150.0)
        assert top.theta_max == pytest.approx(0.5, abs=1e-12)
        assert top.theta_min == pytest.approx(0.5, abs=1e-12)


def test_slow_precession_tends_to_gyroscopic_limit():
    """T4: slow root -> M g h / (I3 omega3) as the spin grows; relative gap O(I1 M g h / (I3 omega3)^2)."""
    gaps = []
    for spin in (1e3, 1e4):
        slow, _fast = tops.steady_precession_rates(I1, I3, MGH, spin, 0.5)
        gaps.append(abs(slow / (MGH / (I3 * spin)) - 1))
    assert gaps[1] < gaps[0] / 90


def test_steady_precession_needs_enough_spin_above_horizontal():
    with pytest.raises(ValueError, match="no steady precession"):
        tops.steady_precession_rates(I1, I3, MGH, 10.0, 0.3)


def test_sleeping_threshold_of_spinning_sphere_is_wilcox_problem_11_13():
    """A solid sphere spinning on its bottom point: I1 = 7MR^2/5, I3 = 2MR^2/5, h = R => omega = sqrt(35 g / R)."""
    m, r, g = 0.2, 0.05, 9.81
    threshold = tops.sleeping_threshold(7 * m * r * r / 5, 2 * m * r * r / 5, m * g * r)
    assert threshold == pytest.approx(np.sqrt(35 * g / r), rel=1e-14)


def test_sleeping_max_tilt_approaches_exact_cubic_root_as_tilt_vanishes():
    spin = 1.5 * tops.sleeping_threshold(I1, I3, MGH)
    errors = []
    for tilt in (1e-2, 1e-3):
        exact = tops.heavy_top(I1, I3, MGH, tilt=tilt, tilt_rate=0.0, precession=0.0, spin=spin).theta_max
        errors.append(abs(tops.sleeping_max_tilt(I1, I3, MGH, spin, tilt) / exact - 1))
    assert errors[1] < errors[0] / 50  # O(theta0^2)


def test_fast_top_nutation_frequency_tends_to_a():
    """T7: for a fast top released at rest, the nutation frequency -> a = I3 omega3 / I1 (error O(beta/a^2))."""
    for spin in (1e3, 1e4):
        top = tops.heavy_top(I1, I3, MGH, tilt=0.5, tilt_rate=0.0, precession=0.0, spin=spin)
        a = I3 * spin / I1
        assert 2 * np.pi / top.nutation_period == pytest.approx(a, rel=3 * top.beta / a**2)


def _exact_precession_rate(top, precession, w):
    """phi_dot = (b - a u)/(1 - u^2) in exact rational arithmetic on the float inputs: b = phi_dot0 s2 + a u0,
    u = u0 - w, 1 - u^2 = s2 + 2 u0 w - w^2 (s2 = sin^2(theta0) as the closed form holds it)."""
    from fractions import Fraction as F

    a, u0, s2, w = F(top.a), F(top.u0), F(top.sin2_tilt), F(float(w))
    b = F(precession) * s2 + a * u0
    return (b - a * (u0 - w)) / (s2 + 2 * u0 * w - w * w)


def test_precession_rate_at_w_keeps_its_digits_near_the_inverted_top():
    """T2: phi_dot = (b - a u)/(1 - u^2) lost the digits of b - a u0 = phi_dot0 sin^2(theta0) to a u0 when the
    top hangs nearly inverted with a slow precession (7.5e-9 in a census). Against exact rational arithmetic at
    many states (turning points and points between), the error is a few ulps times the conditioning of the
    sums c + a w and 1 - u^2 themselves."""
    eps = np.finfo(float).eps
    rng = np.random.default_rng(13)
    worst = 0.0
    for _ in range(300):
        tilt = np.pi - 10 ** rng.uniform(-6, -1) if rng.random() < 0.7 else rng.uniform(0.05, 3.0)
        spin = 10 ** rng.uniform(0, 4) * rng.choice([-1, 1])
        precession = 10 ** rng.uniform(-4, 1) * rng.choice([-1, 1])
        try:
            top = tops.heavy_top(I1, I3, MGH, tilt=tilt, tilt_rate=0.0, precession=precession, spin=spin)
        except ValueError:
            continue
        w1, w2, _ = top.w_roots
        for w in (w1, w2, *np.linspace(w2, w1, 5)[1:-1]):
            exact = _exact_precession_rate(top, precession, w)
            got = float(top.precession_rate_at_w(w))
            num = (abs(top.c) + abs(top.a * w)) / abs(top.c + top.a * w)
            den = (top.sin2_tilt + abs(2 * top.u0 * w) + w * w) / abs(top.sin2_tilt + 2 * top.u0 * w - w * w)
            err = abs(got - float(exact)) / abs(float(exact))
            worst = max(worst, err / (eps * (num + den)))
    assert worst <= 4, worst


def test_inverted_top_precession_rate_agrees_with_the_steady_root_to_round_off():
    """A top hanging nearly inverted released at its slow steady rate stays steady: the closed form's phi_dot at
    w = 0 returns that rate to round-off (before the fix: 1e-9 relative, the digits of a u0 that c lacks)."""
    for tilt in (np.pi - 1e-3, np.pi - 1e-5):
        slow, _ = tops.steady_precession_rates(I1, I3, MGH, 1e3, tilt)
        top = tops.heavy_top(I1, I3, MGH, tilt=tilt, tilt_rate=0.0, precession=slow, spin=1e3)
        assert float(top.precession_rate_at_w(0.0)) == pytest.approx(slow, rel=4 * np.finfo(float).eps)


def test_mean_precession_keeps_the_spike_where_the_axis_passes_near_the_vertical():
    """T3: Delta phi / T_nut in closed form (elliptic integrals of the third kind) against a trapezoid rule fine
    enough to resolve phi_dot's spike ~|omega_perp| / theta_min at the pass (2^21 points); the 4096 points of a
    smooth-integrand rule miss it (a census found 391 rad/s predicted for ~0)."""
    # thrown toward the vertical with b = p_phi / I1 a hair above a: passes within 8e-4 rad of it once a nutation
    spin, tilt = 20.0, 0.5
    a = I3 * spin / I1
    precession = a * (1 - np.cos(tilt)) / np.sin(tilt) ** 2 + 0.1
    top = tops.heavy_top(I1, I3, MGH, tilt=tilt, tilt_rate=-30.0, precession=precession, spin=spin)
    assert top.theta_min < 1e-3
    t = top.t_max_tilt + top.nutation_period * np.arange(2**21) / 2**21
    fine = float(np.mean(top.precession_rate_at_w(top.w(t))))
    coarse = float(np.mean(top.precession_rate_at_w(top.w(t[:: 2**9]))))
    assert top.mean_precession_rate == pytest.approx(fine, rel=1e-10)
    assert abs(coarse / fine - 1) > 1e-2


def test_mean_precession_of_a_steady_top_is_its_rate():
    """At a double root (steady precession, T4) Pi(0 | m) = K(m): the mean rate is phi_dot0 to round-off."""
    slow, fast = tops.steady_precession_rates(I1, I3, MGH, 150.0, 0.5)
    for rate in (slow, fast):
        top = tops.heavy_top(I1, I3, MGH, tilt=0.5, tilt_rate=0.0, precession=rate, spin=150.0)
        assert top.mean_precession_rate == pytest.approx(rate, rel=1e-13)


def test_separatrix_sensitivity_grows_like_the_inverse_gap_off_the_intermediate_axis():
    """A3: off the intermediate axis by eps the gap L^2 - 2 E I2 ~ eps^2, so S ~ 1/eps^2; S >= 2 always."""
    inertia = (1.0, 2.0, 2.5)
    s = [tops.separatrix_sensitivity(inertia, [0.0, 3 * np.cos(e), 3 * np.sin(e)]) for e in (1e-2, 1e-3)]
    assert s[1] / s[0] == pytest.approx(100, rel=1e-3)
    assert tops.separatrix_sensitivity(inertia, [0.05, 0.1, 3.0]) >= 2


def test_slender_body_is_far_from_the_separatrix_in_sensitivity_though_its_gap_is_small():
    """A body with I1 << I2 ~ I3 has |L^2 - 2 E I2| << L^2 in every state, but its phase is insensitive to the
    rates there: S stays O(1) (a gap-based domain refused 20 % of a census's valid draws)."""
    inertia, omega = (0.358, 360.0, 360.3), [1.0, 2.0, 3.0]
    w = np.array(omega)
    i = np.array(inertia)
    assert abs(np.sum(i * (i - i[1]) * w**2)) / np.sum((i * w) ** 2) < 1e-2
    assert tops.separatrix_sensitivity(inertia, omega) < 10


# ---- the heavy top's rates, reference step and round-off scales (rigidbench.analytic.heavy_top) ---------------


def test_heavy_top_transverse_scale_is_the_largest_transverse_rate_of_the_motion():
    """Scales.transverse, from the energy (T2), is the largest sqrt(theta_dot^2 + phi_dot^2 sin^2 theta) along the
    integrated motion (to the ODE's tolerance)."""
    from rigidbench.analytic import heavy_top

    tilt, precession, tilt_rate, spin = 0.7, 3.0, 2.0, 80.0
    top = tops.heavy_top(I1, I3, MGH, tilt=tilt, tilt_rate=tilt_rate, precession=precession, spin=spin)
    transverse0 = float(np.hypot(tilt_rate, precession * np.sin(tilt)))
    sc = heavy_top.scales(top, I1, I3, spin, transverse0)
    p_phi = I1 * precession * np.sin(tilt) ** 2 + I3 * spin * np.cos(tilt)
    T = top.nutation_period
    sol = solve_ivp(lagrange_top(I1, I3, MGH, spin), (0, T), [tilt, 0.0, tilt_rate], args=(p_phi,), **ODE)
    theta, _, theta_dot = sol.sol(np.linspace(0, T, 4001))
    phi_dot = (p_phi - I3 * spin * np.cos(theta)) / (I1 * np.sin(theta) ** 2)
    measured = np.sqrt(theta_dot**2 + (phi_dot * np.sin(theta)) ** 2).max()
    assert sc.transverse == pytest.approx(measured, rel=1e-6)
    assert sc.fastest >= max(sc.omega, sc.nutation, sc.pendulum)


def test_heavy_top_momentum_scale_of_a_top_at_rest_is_the_fall_through_the_potential():
    from rigidbench.analytic import heavy_top

    assert heavy_top.momentum_scale(I1, I3, MGH, 0.0, 0.0) == pytest.approx(np.sqrt(2 * I1 * MGH), rel=1e-15)


def test_heavy_top_rk4_step_limit_meets_the_drift_target_exactly():
    """At the RK4 limit the drift estimate r Omega T (Omega h)^4 / 120 equals RK4_TARGET; the step is the smallest
    of the three limits; the rule names it."""
    from rigidbench.analytic import heavy_top

    top = tops.heavy_top(I1, I3, MGH, tilt=0.5, tilt_rate=0.0, precession=0.0, spin=150.0)
    lim = heavy_top.step_limits(top, I1, I3, MGH, tilt=0.5, tilt_rate=0.0, precession=0.0, spin=150.0, nutations=3.3)
    h = lim.limits["RK4 drift"]
    assert lim.r * lim.omega * lim.duration * (lim.omega * h) ** 4 / 120 == pytest.approx(heavy_top.RK4_TARGET)
    assert lim.duration == pytest.approx(3.3 * top.nutation_period, rel=1e-15)
    assert lim.limits["azimuth unwrap"] == np.inf  # a nutating top's azimuth is not unwrapped
    assert lim.step == min(lim.limits.values()) and f"({lim.which})" in lim.rule(1e-4)


def test_heavy_top_acceleration_bound_without_spin_is_the_gravity_torque_over_inertia():
    from rigidbench.analytic import heavy_top

    assert heavy_top.acceleration_bound(I1, I3, MGH, 0.0, 5.0) == MGH / I1
    assert heavy_top.acceleration_bound(I1, I3, MGH, 10.0, 5.0) == pytest.approx(abs(I1 - I3) * 50 / I1 + MGH / I1)


def test_heavy_top_roundoff_scales_are_never_below_one():
    from rigidbench.analytic import heavy_top

    top = tops.heavy_top(I1, I3, MGH, tilt=0.5, tilt_rate=0.0, precession=-4.7, spin=150.0)
    scales = heavy_top.roundoff_scales(
        top, duration=3.3 * top.nutation_period, nutations=3.3, precession_rate=-4.7, tilt=0.5, falling=False
    )
    assert set(scales) >= {"mean-precession", "precession-rate", "nutation-period", "precession-at-theta-min"}
    assert "tilt-growth-rate" not in scales and all(v >= 1.0 for v in scales.values())
