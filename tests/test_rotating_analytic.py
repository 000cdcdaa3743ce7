"""The rotating-frame closed forms alone (`rigidbench.analytic.rotating`, docs/theory.md N1-N3), against independent
numerics: scipy's DOP853 on the rotating-frame equations, written out here again from Wilcox eq. 10.35, and the
swing plane measured here from that integration, not by the scenario's code."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from rigidbench.analytic import rotating as rot

G = 9.81


def _n1(field, w):
    """Wilcox 10.35 with a fixed origin and a constant rate: r'' = g - 2 w x v - w x (w x r)."""

    def rhs(_t, s):
        r, v = s[:3], s[3:]
        return np.concatenate([v, field - 2 * np.cross(w, v) - np.cross(w, np.cross(w, r))])

    return rhs


@pytest.mark.parametrize(
    ("rate", "lat", "r0"),
    [(0.02, np.pi / 4, None), (0.3, 0.0, None), (1.0, -1.0, (1.0, -2.0, 0.5)), (0.05, np.pi / 2, None)],
)
def test_drop_path_is_the_exact_solution_of_the_rotating_frame_equations(rate, lat, r0):
    w, g = rot.rate_vector(rate, lat), np.array([0.0, 0.0, -G])
    r0 = np.zeros(3) if r0 is None else np.array(r0)
    t = np.linspace(0.0, 3.0, 13)
    sol = solve_ivp(
        _n1(g, w), (0, 3.0), np.concatenate([r0, np.zeros(3)]), method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t
    )
    np.testing.assert_allclose(rot.drop_path(t, g, w, r0), sol.y[:3].T, rtol=0, atol=2e-11)


def test_drop_path_at_tiny_and_zero_rates_is_free_fall():
    """The small-argument series keep the closed form exact as Omega t -> 0 (no 0/0)."""
    t = np.linspace(0, 2, 5)
    g = np.array([0.0, 0.0, -G])
    for rate in (0.0, 1e-9, 1e-4):
        r = rot.drop_path(t, g, rot.rate_vector(rate, 0.3))
        np.testing.assert_allclose(r[:, 2], -G * t**2 / 2, rtol=1e-7, atol=1e-15)
        assert np.all(np.abs(r[:, 0]) <= rate * G * t**3 / 3 * 1.000001 + 1e-15)


@pytest.mark.parametrize("lat", [0.0, 0.4, np.pi / 4, -1.2])
@pytest.mark.parametrize("x0", [0.01, 0.04, 0.1, 0.3, 0.5])
def test_eastward_deflection_where_the_body_has_fallen_h_is_n3_within_its_neglected_terms(lat, x0):
    """The exact landing's eastward offset is N3 x (1 + x0^2 (3 cos^2/8 - 1/10) + O(x0^4)), inside the bound."""
    h = 20.0
    rate = x0 / rot.fall_time(G, h)
    _, r_h = rot.landing([0, 0, -G], rot.rate_vector(rate, lat), h)
    n3 = rot.eastward_deflection(rate, G, h, lat)
    rel = r_h[0] / n3 - 1
    assert abs(rel) <= rot.eastward_neglected_terms(rate, G, h)
    series = x0**2 * (3 * np.cos(lat) ** 2 / 8 - 0.1)
    assert abs(rel - series) <= 2 * x0**4  # the next term is O(x0^4)


def test_at_earths_rate_n3_is_the_exact_drop_to_1e8():
    """Earth's rate, h = 100 m, lambda = 45 deg (docs/theory.md K2's example): N3 gives 1.55 cm, and the exact landing
    differs by x0^2 (3 cos^2(lambda)/8 - 1/10) = 9.5e-9 of it (x0 = Omega t0 = 3.3e-4)."""
    rate, h, lat = 7.292e-5, 100.0, np.pi / 4
    n3 = rot.eastward_deflection(rate, G, h, lat)
    assert n3 == pytest.approx(0.0155, abs=5e-5)
    _, r_h = rot.landing([0, 0, -G], rot.rate_vector(rate, lat), h)
    x0 = rate * rot.fall_time(G, h)
    assert r_h[0] / n3 - 1 == pytest.approx(x0**2 * (3 * np.cos(lat) ** 2 / 8 - 0.1), rel=1e-3)


def test_foucault_swing_solves_n2_from_rest():
    """q = ... of docs/theory.md N2 satisfies q'' + 2 i Omega_z q' + omega0^2 q = 0 and starts at rest at A e^{i az}."""
    w0, wz, a, az = 3.0, 0.1, 0.02, 0.7
    t = np.linspace(0, 10, 20001)
    q = rot.foucault_swing(t, w0, wz, a, az)
    dt = t[1] - t[0]
    qd = np.gradient(q, dt, edge_order=2)
    qdd = np.gradient(qd, dt, edge_order=2)
    residual = qdd + 2j * wz * qd + w0**2 * q
    assert np.max(np.abs(residual[5:-5])) < 1e-5 * w0**2 * a
    assert q[0] == pytest.approx(a * np.exp(1j * az))
    assert abs(qd[0]) < 1e-6 * a * w0
    # The line of swing turns at -Omega_z: the turning points lie on azimuth az - Omega_z t.
    tp = np.pi * np.arange(1, 6) / np.hypot(w0, wz)
    az_tp = np.angle(rot.foucault_swing(tp, w0, wz, a, az) ** 2) / 2
    np.testing.assert_allclose(np.unwrap(2 * az_tp) / 2 % np.pi, (az - wz * tp) % np.pi, atol=1e-12)


@pytest.mark.parametrize("lat", [np.pi / 2, 0.8, 0.0, -0.5])
def test_plumb_line_is_the_pendulums_rest_direction(lat):
    w, g, length = rot.rate_vector(0.3, lat), np.array([0.0, 0.0, -G]), 1.5
    d = rot.plumb_line(g, w, length)
    a = rot.rotating_frame_acceleration(length * d, np.zeros(3), g, w)
    assert np.linalg.norm(np.cross(a, d)) < 1e-14 * G  # the rod's tension can balance it: no tangential part
    lean = np.arccos(-d[2])
    expected = (0.3**2 * length / G) * abs(np.sin(lat) * np.cos(lat))  # (Omega/omega0)^2 sin cos, first order
    assert lean == pytest.approx(expected, rel=0.01, abs=1e-15)
    east, north = rot.horizontal_axes(d)
    assert abs(east @ d) < 1e-15 and abs(north @ d) < 1e-15 and np.cross(east, north) @ -d == pytest.approx(1)


def test_rotating_pendulum_keeps_its_rod_and_its_jacobi_integral():
    """The constrained integration keeps |r| = l and E = v^2/2 - g.r - |w x r|^2/2 (the rotating frame's Jacobi
    integral, conserved because the frame turns steadily) to ~rtol."""
    w, g, length = rot.rate_vector(0.2, 0.7), np.array([0.0, 0.0, -G]), 1.0
    r0 = length * np.array([np.sin(0.3), 0.0, -np.cos(0.3)])
    motion = rot.rotating_pendulum(length, g, w, r0, np.zeros(3), 30.0)
    r, v = motion(np.linspace(0, 30, 3001))

    def jacobi(r, v):
        wr = np.cross(w[:, None], r, axis=0)
        return 0.5 * np.sum(v * v, axis=0) - g @ r - 0.5 * np.sum(wr * wr, axis=0)

    assert np.max(np.abs(np.linalg.norm(r, axis=0) - length)) < 1e-9
    e = jacobi(r, v)
    assert np.max(np.abs(e - e[0])) < 1e-9 * G * length


def _half_turn_rate(lat: float, ratio: float, amplitude: float, azimuth: float, length: float = 1.0) -> tuple:
    """The mean rate of the swing plane over its first half turn, measured from an independent integration:
    N1 in Cartesian coordinates with the rod as a Lagrange multiplier (docs/theory.md check K1), the azimuth of each
    maximum excursion across the plumb line, and the time it is back on its first line (spline through them)."""
    w0 = np.sqrt(G / length)
    w, g = rot.rate_vector(ratio * w0, lat), np.array([0.0, 0.0, -G])
    d = rot.plumb_line(g, w, length)
    east, north = rot.horizontal_axes(d)
    u = np.cos(amplitude) * d + np.sin(amplitude) * (np.cos(azimuth) * east + np.sin(azimuth) * north)

    def rhs(_t, s):
        r, v = s[:3], s[3:]
        a = g - 2 * np.cross(w, v) - np.cross(w, np.cross(w, r))
        return np.concatenate([v, a - (v @ v + r @ a) / (r @ r) * r])

    t_end = np.pi / (ratio * w0 * abs(np.sin(lat))) + 4 * np.pi / w0
    ts = np.linspace(0, t_end, int(t_end * w0 / (2 * np.pi) * 60) + 1)
    sol = solve_ivp(
        rhs,
        (0, t_end),
        np.concatenate([length * u, np.zeros(3)]),
        method="DOP853",
        rtol=1e-12,
        atol=1e-13,
        t_eval=ts,
        dense_output=True,
    )

    def radial(t):
        s = sol.sol(t)
        return (east @ s[:3]) * (east @ s[3:]) + (north @ s[:3]) * (north @ s[3:])

    rad = radial(ts)
    idx = np.nonzero((rad[:-1] > 0) & (rad[1:] <= 0))[0]
    tm = np.concatenate([[0.0], [brentq(radial, ts[i], ts[i + 1], xtol=1e-14) for i in idx]])
    s = sol.sol(tm)
    az = np.unwrap(2 * np.arctan2(s[:3].T @ north, s[:3].T @ east)) / 2
    sense = np.sign(az[-1] - az[0])
    k = np.nonzero(sense * (az - az[0]) >= np.pi)[0][0]
    spline = CubicSpline(tm, az)
    t_pi = brentq(lambda t: spline(t) - az[0] - sense * np.pi, tm[k - 1], tm[k])
    measured = sense * np.pi / t_pi
    terms = rot.precession_neglected_terms(w, d, w0, amplitude, lat)
    return measured, rot.foucault_precession_rate(ratio * w0, lat), terms


# Points of the domain (|lambda| 30-90 deg, Omega/omega0 0.01-0.05, amplitude 0.005-0.05 rad); the default run has
# the tightest measured one (0.94 of the plain sum) and the corners, the full grid is slow.
_FAST = [(60, 0.05, 0.01, 0.0), (30, 0.05, 0.05, 0.0), (-40, 0.03, 0.02, np.pi / 2)]
_GRID = [
    (lat, ratio, a, az)
    for lat in (30, 45, 60, 75)
    for ratio in (0.01, 0.05)
    for a in (0.005, 0.05)
    for az in (0.0, np.pi / 4, np.pi / 2)
]


@pytest.mark.parametrize(("lat", "ratio", "amplitude", "azimuth"), _FAST)
def test_n2_precession_is_within_its_sized_neglected_terms(lat, ratio, amplitude, azimuth):
    measured, expected, terms = _half_turn_rate(np.radians(lat), ratio, amplitude, azimuth)
    error = abs(measured / expected - 1)
    plain = sum(terms.values())
    assert error <= rot.precession_tolerance(terms)
    assert error >= 0.3 * plain, "the tolerance should not be vacuous: the neglected terms are really there"


@pytest.mark.slow
@pytest.mark.parametrize(("lat", "ratio", "amplitude", "azimuth"), _GRID)
def test_n2_precession_is_within_its_sized_neglected_terms_on_the_whole_grid(lat, ratio, amplitude, azimuth):
    measured, expected, terms = _half_turn_rate(np.radians(lat), ratio, amplitude, azimuth)
    assert abs(measured / expected - 1) <= rot.precession_tolerance(terms)


def test_at_the_pole_n2_misses_by_airys_precession_alone():
    """At the pole the plumb line is vertical and the swing isotropic: N2's error is Airy's (3/8) a^2 (against the
    turn), to a part in 100 of itself [A]."""
    amplitude = 0.04
    measured, expected, terms = _half_turn_rate(np.pi / 2, 0.03, amplitude, 0.0)
    assert terms["tilt"] < 1e-15 and terms["anisotropy"] < 1e-30
    assert measured / expected - 1 == pytest.approx(-0.375 * np.sin(amplitude) ** 2, rel=0.01)
