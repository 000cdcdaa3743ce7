"""The percussion closed forms alone (docs/theory.md P1-P6, B1-B2): limits, identities and independent references."""

import ast
import inspect

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rigidbench.analytic import percussion as pc

M, L = 0.25, 1.0  # a meter stick
I_CM = pc.uniform_rod_inertia(M, L)


def test_uniform_rod_inertia_uses_the_full_length():
    half = L / 2
    assert I_CM == pytest.approx(M * half**2 / 3, rel=1e-15)  # docs/theory.md writes M l^2 / 3 with l = L/2


@pytest.mark.parametrize("offset", [0.05, 0.25, 0.5])
def test_blow_gives_momentum_pi_and_angular_momentum_pi_h(offset):
    s = pc.struck_stick(M, I_CM, 1.3, offset)
    assert M * s.com_velocity == pytest.approx(1.3, rel=1e-15)
    assert I_CM * s.angular_velocity == pytest.approx(-1.3 * offset, rel=1e-15)  # clockwise for h > 0


@pytest.mark.parametrize("offset", [0.05, 0.25, 0.5])
def test_centre_of_percussion_is_at_rest_just_after_the_blow(offset):
    s = pc.struck_stick(M, I_CM, 1.0, offset)
    half = L / 2
    assert s.percussion_distance == pytest.approx(half**2 / (3 * offset), rel=1e-15)  # p = l^2 / (3h)
    assert s.point_velocity(-s.percussion_distance) == pytest.approx(0.0, abs=1e-15)
    assert s.point_velocity(-2 * s.percussion_distance) < 0 < s.point_velocity(0.0)  # beyond p it moves back


def test_strike_at_a_third_of_the_half_length_leaves_the_far_end_at_rest():
    """docs/theory.md P6 rule 2: a marble at one end is not pushed if the stick is struck at h = l/3 (66.7 cm from
    it)."""
    half = L / 2
    s = pc.struck_stick(M, I_CM, 1.0, half / 3)
    assert s.percussion_distance == pytest.approx(half, rel=1e-15)
    assert s.point_velocity(half) == pytest.approx(2 * s.com_velocity, rel=1e-15)  # the struck end starts at 2V


def test_cycloid_cusps_are_two_pi_p_apart_and_at_rest():
    s = pc.struck_stick(M, I_CM, 1.0, 0.25)
    t_n = s.cusp_period * np.arange(4)
    path = s.cycloid(t_n)
    np.testing.assert_allclose(np.diff(path[:, 0]), s.cusp_spacing, rtol=1e-13)
    np.testing.assert_allclose(path[:, 1], -s.percussion_distance, rtol=1e-13)
    h = 1e-6 * s.cusp_period
    speed = np.linalg.norm((s.cycloid(t_n + h) - s.cycloid(t_n - h)) / (2 * h), axis=1)
    assert speed.max() < 1e-5 * s.com_velocity
    # Between cusps the point moves at up to 2V (the top of the rolling circle).
    top = np.linalg.norm(np.diff(s.cycloid(s.cusp_period * np.array([0.5 - 1e-7, 0.5 + 1e-7])), axis=0)) / (
        2e-7 * s.cusp_period
    )
    assert top == pytest.approx(2 * s.com_velocity, rel=1e-6)


def test_cycloid_is_the_rigid_motion_of_the_stick_point():
    """An independent parametrisation: CM at V t, the body point s = -p rotated by omega t."""
    s = pc.struck_stick(M, I_CM, 0.7, 0.2)
    t = np.linspace(0, 3 * s.cusp_period, 50)
    angle = s.angular_velocity * t
    p = s.percussion_distance
    x = s.com_velocity * t + p * np.sin(angle)  # body (0, -p) rotated by angle about z
    y = -p * np.cos(angle)
    np.testing.assert_allclose(s.cycloid(t), np.stack([x, y], axis=1), atol=1e-13)


def test_pivot_reaction_vanishes_at_two_thirds_of_the_length():
    inertia_pivot = I_CM + M * (L / 2) ** 2
    d_star = pc.sweet_spot(M, inertia_pivot, L / 2)
    assert d_star == pytest.approx(2 * L / 3, rel=1e-15)
    assert pc.pivot_reaction_impulse(M, inertia_pivot, L / 2, d_star, 1.0) == pytest.approx(0.0, abs=1e-15)
    assert pc.pivot_reaction_impulse(M, inertia_pivot, L / 2, L / 2, 1.0) == pytest.approx(-0.25, rel=1e-14)
    assert pc.pivot_reaction_impulse(M, inertia_pivot, L / 2, L, 1.0) == pytest.approx(0.5, rel=1e-14)


@pytest.mark.parametrize("d_cm", [0.1, 0.3, 0.5])
def test_sweet_spot_is_the_centre_of_percussion_referred_to_the_pivot(d_cm):
    inertia_pivot = I_CM + M * d_cm**2
    assert pc.sweet_spot(M, inertia_pivot, d_cm) == pytest.approx(d_cm + I_CM / (M * d_cm), rel=1e-14)


def test_ball_stops_when_its_mass_equals_the_effective_mass():
    h = 0.25
    m_eff = 1 / (1 / M + h**2 / I_CM)
    r = pc.ball_on_stick(M, I_CM, h, m_eff, 2.0)
    assert r.effective_mass == pytest.approx(m_eff, rel=1e-15)
    assert r.ball_velocity == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("ball_mass", [0.05, 0.25, 1.0])
def test_elastic_ball_on_stick_conserves_momentum_energy_and_angular_momentum(ball_mass):
    h, u = 0.3, 2.0
    r = pc.ball_on_stick(M, I_CM, h, ball_mass, u)
    s = r.stick
    assert ball_mass * r.ball_velocity + M * s.com_velocity == pytest.approx(ball_mass * u, rel=1e-14)
    energy = 0.5 * ball_mass * r.ball_velocity**2 + 0.5 * M * s.com_velocity**2 + 0.5 * I_CM * s.angular_velocity**2
    assert energy == pytest.approx(0.5 * ball_mass * u**2, rel=1e-14)
    # about the CM's initial position: the ball's line at y = h
    assert -ball_mass * r.ball_velocity * h + I_CM * s.angular_velocity == pytest.approx(-ball_mass * u * h, rel=1e-13)


@pytest.mark.parametrize("ball_mass", [0.05, 0.25, 1.0])
def test_ball_on_stick_matches_a_stiff_spring_collision(ball_mass):
    """Independent reference (docs/theory.md check F4): the planar ball-stick collision through a stiff linear spring,
    with the stick free to turn during the contact, integrated by DOP853."""
    h, u, k = 0.3, 2.0, 1e10  # contact time ~ pi sqrt(m_red / k) ~ 1e-6 s: the stick turns by ~1e-5 rad

    def rhs(_t, y):
        xb, vb, xs, vs, th, w = y
        gap = xb - (xs - h * np.sin(th))  # penetration of the ball into the face point at body (0, h)
        f = k * gap if gap > 0 else 0.0
        return [vb, -f / ball_mass, vs, f / M, w, -h * np.cos(th) * f / I_CM]

    sol = solve_ivp(rhs, (0, 2e-4), [-1e-5, u, 0, 0, 0, 0], method="DOP853", rtol=1e-12, atol=1e-15, max_step=2e-8)
    _, vb, _, vs, _, w = sol.y[:, -1]
    r = pc.ball_on_stick(M, I_CM, h, ball_mass, u)
    assert vb == pytest.approx(r.ball_velocity, abs=1e-6 * u)
    assert vs == pytest.approx(r.stick.com_velocity, rel=1e-6)
    assert w == pytest.approx(r.stick.angular_velocity, rel=1e-6)


def test_no_skid_height_is_seven_tenths_of_the_diameter():
    radius = 0.028575
    h = pc.no_skid_height(radius)
    assert radius + h == pytest.approx(0.7 * 2 * radius, rel=1e-15)
    assert pc.slip_after_impulse(radius, h, 3.0) == pytest.approx(0.0, abs=1e-15)
    b = pc.cue_strike(radius, 0.2, 9.81, 2.0, h)
    assert b.slip == pytest.approx(0.0, abs=1e-14) and b.time_to_roll == pytest.approx(0.0, abs=1e-14)
    assert b.final_speed == pytest.approx(2.0, rel=1e-14) and b.energy_lost == pytest.approx(0.0, abs=1e-14)


def test_centre_strike_loses_two_sevenths_of_energy():
    v0, mu, g = 2.0, 0.2, 9.81
    b = pc.cue_strike(0.03, mu, g, v0, 0.0)
    assert b.energy_lost == pytest.approx(2 / 7, rel=1e-14)
    assert b.final_speed == pytest.approx(5 * v0 / 7, rel=1e-15)
    assert b.time_to_roll == pytest.approx(2 * v0 / (7 * mu * g), rel=1e-15)
    assert b.skid_distance == pytest.approx(12 * v0**2 / (49 * mu * g), rel=1e-14)


@pytest.mark.parametrize("spin", [-100.0, 0.0, 30.0, 70.0, 200.0])  # backspin ... overspin
def test_final_speed_is_v0_minus_two_sevenths_of_the_slip(spin):
    radius, v0 = 0.03, 2.0
    b = pc.skid_to_roll(radius, 0.2, 9.81, v0, spin)
    assert b.final_speed == pytest.approx(v0 - 2 / 7 * (v0 - radius * spin), rel=1e-14)


@pytest.mark.parametrize("height_over_radius", [-0.5, 0.0, 0.2, 0.6, 0.9])
def test_cue_ball_rolls_at_five_sevenths_of_v0_times_one_plus_h_over_r(height_over_radius):
    radius, v0 = 0.028575, 1.5
    b = pc.cue_strike(radius, 0.2, 9.81, v0, height_over_radius * radius)
    assert b.final_speed == pytest.approx(5 / 7 * v0 * (1 + height_over_radius), rel=1e-14)
    assert b.slip == pytest.approx(v0 * (1 - 2.5 * height_over_radius), rel=1e-14, abs=1e-15)


@pytest.mark.parametrize("gamma", [pc.SOLID_SPHERE, 2 / 3, 1 / 2])  # solid, hollow sphere, cylinder
@pytest.mark.parametrize("height_over_radius", [-0.5, 0.0, 0.8])
def test_skid_matches_an_independent_integration_of_the_sliding_ball(gamma, height_over_radius):
    """Independent reference: Newton's equations of the sliding body, integrated until the slip vanishes."""
    radius, mu, g, v0 = 0.03, 0.2, 9.81, 2.0
    b = pc.cue_strike(radius, mu, g, v0, height_over_radius * radius, gamma)
    sign = np.sign(b.slip)

    def rhs(_t, y):  # x, v, omega; friction -mu M g sgn(u) on the contact point at -R z
        return [y[1], -sign * mu * g, sign * mu * g / (gamma * radius)]

    def rolling(_t, y):
        return y[1] - radius * y[2]

    rolling.terminal = True
    sol = solve_ivp(rhs, (0, 10), [0, v0, b.spin], events=rolling, method="DOP853", rtol=1e-12, atol=1e-14)
    t_r = sol.t_events[0][0]
    x, v, _ = sol.y_events[0][0]
    assert t_r == pytest.approx(b.time_to_roll, rel=1e-10)
    assert x == pytest.approx(b.skid_distance, rel=1e-10)
    assert v == pytest.approx(b.final_speed, rel=1e-10)
    x_th, v_th, u_th = b.state(np.array([0.5 * t_r, t_r, 2 * t_r]))
    assert u_th[1] == pytest.approx(0.0, abs=1e-13) and u_th[2] == pytest.approx(0.0, abs=1e-13)
    assert v_th[2] == pytest.approx(b.final_speed, rel=1e-14)
    assert x_th[2] == pytest.approx(b.skid_distance + b.final_speed * t_r, rel=1e-13)


def test_slip_decreases_at_seven_halves_mu_g_for_a_solid_sphere():
    b = pc.cue_strike(0.03, 0.2, 9.81, 2.0, 0.0)
    assert b.slip_rate == pytest.approx(-3.5 * 0.2 * 9.81, rel=1e-15)


def test_closed_forms_import_no_simulator():
    tree = ast.parse(inspect.getsource(pc))
    names = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    names |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    assert not names & {"mujoco", "gymnasium", "rigidbench"}
