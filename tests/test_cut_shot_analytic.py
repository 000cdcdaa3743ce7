"""The rolling cut shot's closed forms (docs/theory.md B4) against an independent numerical solution: the cue ball's
slide integrated step by step under Coulomb friction from the hard-sphere impact, and the deflection maximised
numerically."""

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from rigidbench.analytic import cut_shot


def _slide(v, omega, mu=0.2, g=9.81, radius=0.03, gamma=0.4, dt=5e-6):
    """Explicit integration of a sliding ball (friction -mu M g u_hat at the contact point, R below the centre)
    until its slip vanishes: the final velocity (2-D)."""
    v, omega = np.array(v, float), np.array(omega, float)  # omega: (omega_x, omega_y)
    for _ in range(10**7):
        slip = np.array([v[0] - radius * omega[1], v[1] + radius * omega[0]])
        size = np.hypot(*slip)
        if size < 5 * mu * g * dt:
            return v
        f = -mu * g * slip / size  # per unit mass
        v = v + f * dt
        # torque r x F with r = -R z: (-R z) x (f_x, f_y, 0) = (R f_y, -R f_x, 0); alpha = torque / (gamma M R^2)
        omega = omega + np.array([f[1], -f[0]]) * dt / (gamma * radius)
    raise AssertionError("never rolled")


@pytest.mark.parametrize("phi", [0.2, 0.49, 0.5236, 1.0])
def test_deflection_matches_an_integrated_slide(phi):
    speed, radius = 2.0, 0.03
    shot = cut_shot.cut_shot(speed, phi, 0.2, 9.81)
    # the cue ball after the hard impact: V x - V cos(phi) n, spin of rolling along +x (omega_y = V / R) kept
    v_after = np.array([speed, 0.0]) - speed * math.cos(phi) * np.array([math.cos(phi), -math.sin(phi)])
    v_final = _slide(v_after, (0.0, speed / radius), radius=radius)
    assert math.atan2(v_final[1], v_final[0]) == pytest.approx(float(cut_shot.deflection(phi)), abs=1e-4)
    assert math.atan2(v_final[1], v_final[0]) == pytest.approx(shot.deflection, abs=1e-4)
    assert np.allclose(v_final, shot.cue_final, atol=1e-4)


def test_deflection_formula_is_the_seed_form():
    phi = np.linspace(0.01, 1.5, 50)
    s, c = np.sin(phi), np.cos(phi)
    assert np.allclose(np.tan(cut_shot.deflection(phi)), 5 * s * c / (2 * c**2 + 7 * s**2), rtol=1e-13)


def test_largest_deflection_is_33_75_degrees_at_tan_phi_sqrt_2_7():
    best = minimize_scalar(
        lambda p: -float(cut_shot.deflection(p)), bounds=(0.01, 1.5), method="bounded", options={"xatol": 1e-10}
    )
    phi, delta = cut_shot.max_deflection()
    assert phi == pytest.approx(best.x, abs=1e-6)
    assert delta == pytest.approx(-best.fun, abs=1e-12)
    assert math.tan(phi) == pytest.approx(math.sqrt(2 / 7), rel=1e-14)
    assert math.degrees(delta) == pytest.approx(33.749, abs=1e-3)


@pytest.mark.parametrize("phi", [0.1, 0.5, 1.2])
def test_ninety_degrees_final_angle_and_five_sevenths(phi):
    shot = cut_shot.cut_shot(1.5, phi, 0.3, 9.81)
    assert shot.opening_angle == pytest.approx(math.pi / 2, abs=1e-14)
    assert shot.final_angle == pytest.approx(float(cut_shot.final_angle(phi)), abs=1e-14)
    assert shot.final_angle == pytest.approx(math.atan(3.5 * math.tan(phi)), abs=1e-14)
    assert np.hypot(*shot.object_final) == pytest.approx(5 / 7 * 1.5 * math.cos(phi), rel=1e-14)
    assert np.hypot(*shot.cue_final) == pytest.approx(1.5 / 7 * math.sqrt(4 + 45 * math.sin(phi) ** 2), rel=1e-14)
    assert shot.object_direction == pytest.approx(phi, abs=1e-14)


def test_skid_path_is_the_b3_parabola_then_straight():
    skid = cut_shot.cut_shot(2.0, 0.5, 0.2, 9.81).cue
    t_r = skid.time_to_roll
    t = np.array([0.0, 0.5 * t_r, t_r, 2 * t_r])
    x = skid.position(t)
    u = skid.slip / np.hypot(*skid.slip)
    assert np.allclose(x[1], skid.velocity * 0.5 * t_r - 0.5 * 0.2 * 9.81 * u * (0.5 * t_r) ** 2, atol=1e-15)
    assert np.allclose(x[3] - x[2], skid.final_velocity * t_r, atol=1e-15)
