"""Closed forms for rotating frames: the Foucault pendulum and the eastward deflection of a dropped body.

Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2).

Conventions (docs/theory.md section 0, "Earth frames"): the rotating frame is the local East-North-Up frame of a
point at latitude lambda: x = East, y = North, z = Up, and the frame turns at ``Omega = Omega (0, cos lambda,
sin lambda)`` about an axis through its origin. Gravity is a uniform field fixed in that frame, ``(0, 0, -g)``.
Every vector below is in the rotating frame's axes unless its name says otherwise. Latitudes are signed
(southern hemisphere < 0); azimuths are measured from East towards North (counter-clockwise seen from above).

The rotation axis passes through the pendulum's pivot and through the drop point, so the frame's own origin has
no centripetal acceleration: the only centrifugal terms are those of the moving body, O(Omega^2) and kept in the
exact forms (`plumb_line`, `rotating_pendulum`, `drop_path`).

References
----------
[W] Wilcox, *Modern Introductory Mechanics Part II*, ch. 10 (seed 000): section 10.2-10.3 eqs 10.32-10.35 (the
    rotating-frame acceleration), 10.5 (eastward deflection), 10.6 (Foucault pendulum).
[T] docs/theory.md, entries N1-N3 (and O1 for the spherical pendulum's own period).
[A] G. B. Airy, "On the vibration of a free pendulum in an oval differing little from a straight line",
    Mem. R. Astron. Soc. 20, 121 (1851): an elliptic swing of semi-axes a, b precesses at (3/8) omega0 a b / l^2
    in the sense of its motion.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rigidbench import lazy

integrate = lazy.module("scipy.integrate")
optimize = lazy.module("scipy.optimize")


# ---------------------------------------------------------------------------------------------------------
# N1 Rotating-frame kinematics
# ---------------------------------------------------------------------------------------------------------


def rate_vector(rate: float, latitude: float) -> np.ndarray:
    """The frame's angular velocity Omega (0, cos lambda, sin lambda) (rad/s) in local East-North-Up axes.

    docs/theory.md section 0 ("Earth frames"). `rate` is Omega (rad/s), `latitude` lambda (rad, signed).
    """
    return float(rate) * np.array([0.0, np.cos(latitude), np.sin(latitude)])


def rotating_frame_acceleration(r: np.ndarray, v: np.ndarray, field: np.ndarray, rate_vec: np.ndarray) -> np.ndarray:
    """Acceleration relative to a frame turning at the constant rate `rate_vec` about its origin (m/s^2).

    docs/theory.md N1 (Wilcox 10.35) with R'' = 0 and Omega' = 0: ``a_rel = g - 2 Omega x v - Omega x (Omega x r)``.
    `r`, `v` (shape (..., 3)) are position (m) and velocity (m/s) relative to the frame; `field` the uniform field
    g (m/s^2) fixed in it.
    """
    w = np.broadcast_to(rate_vec, np.shape(r))
    return field - 2 * np.cross(w, v) - np.cross(w, np.cross(w, r))


# ---------------------------------------------------------------------------------------------------------
# N2 Foucault pendulum
# ---------------------------------------------------------------------------------------------------------


def foucault_precession_rate(rate: float, latitude: float) -> float:
    """Rate (rad/s) at which the swing plane turns about the local vertical, counter-clockwise seen from above.

    docs/theory.md N2 (Wilcox section 10.6): ``-Omega sin(lambda)``: clockwise in the northern hemisphere, counter-
    clockwise in the southern, zero on the equator. Small amplitude; O((Omega/omega0)^2) neglected
    (`precession_neglected_terms` sizes what is left out).
    """
    return -float(rate) * float(np.sin(latitude))


def foucault_swing(
    t: np.ndarray, omega0: float, vertical_rate: float, amplitude: float, azimuth: float = 0.0
) -> np.ndarray:
    """Horizontal position q = x + i y (m) of the small-amplitude Foucault pendulum released from rest.

    docs/theory.md N2: ``q'' + 2 i Omega_z q' + omega0^2 q = 0``, with ``Omega_z = Omega sin(lambda)`` (here
    `vertical_rate`, rad/s: the frame's rate about the vertical), solved by ``q = A e^{i az} (cos w't + i
    (Omega_z / w') sin w't) e^{-i Omega_z t}``, ``w' = sqrt(omega0^2 + Omega_z^2)``, which starts at ``A e^{i az}``
    with q' = 0. `amplitude` A (m) is the release's horizontal distance from the vertical through the pivot,
    `azimuth` its direction (rad from East towards North).

    Returns
    -------
    ndarray of complex, shape of `t`
    """
    t = np.asarray(t, dtype=float)
    wz = float(vertical_rate)
    wp = np.hypot(omega0, wz)
    return amplitude * np.exp(1j * azimuth) * (np.cos(wp * t) + 1j * (wz / wp) * np.sin(wp * t)) * np.exp(-1j * wz * t)


def plumb_line(field: np.ndarray, rate_vec: np.ndarray, length: float, *, tol: float = 1e-15) -> np.ndarray:
    """Unit vector from the pivot to the bob of a pendulum at rest in the rotating frame (the plumb line).

    docs/theory.md N1 at rest (v = 0): the bob hangs along ``g - Omega x (Omega x l u)``, the field plus the bob's
    own centrifugal acceleration, ``u`` being the unit vector sought; solved by fixed-point iteration, which
    contracts by ~ Omega^2 l / g per step.

    Raises
    ------
    ValueError
        If the iteration does not converge (centrifugal acceleration comparable with g: no plumb line near g).
    """
    g = np.asarray(field, dtype=float)
    u = g / np.linalg.norm(g)
    for _ in range(200):
        a = g - np.cross(rate_vec, np.cross(rate_vec, length * u))
        new = a / np.linalg.norm(a)
        if np.linalg.norm(new - u) <= tol:
            return new
        u = new
    raise ValueError(f"no plumb line: |Omega|^2 l / g = {np.dot(rate_vec, rate_vec) * length / np.linalg.norm(g):g}")


def horizontal_axes(down: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The axes (e_east, e_north) of the plane perpendicular to the plumb line `down` (unit): East projected onto
    the plane, and ``up x e_east``, so that (e_east, e_north, up) is right-handed and azimuths count from East
    towards North. For a vertical plumb line they are x and y."""
    up = -np.asarray(down, dtype=float)
    east = np.array([1.0, 0.0, 0.0]) - up[0] * up
    east /= np.linalg.norm(east)
    return east, np.cross(up, east)


def precession_neglected_terms(
    rate_vec: np.ndarray, down: np.ndarray, omega0: float, amplitude: float, latitude: float
) -> dict[str, float]:
    """Sizes of what N2 leaves out, each relative to ``Omega sin(lambda)`` (`precession_tolerance` adds them).

    Parameters
    ----------
    rate_vec : ndarray, shape (3,)
        The frame's rate Omega (rad/s), East-North-Up axes.
    down : ndarray, shape (3,)
        The plumb line (`plumb_line`).
    omega0 : float
        sqrt(g/l) (rad/s).
    amplitude : float
        Release angle from the plumb line (rad).
    latitude : float
        lambda (rad), |lambda| > 0.

    Returns
    -------
    dict
        ``"tilt"``: the plumb line leans from the geographic vertical by ~ (Omega/omega0)^2 sin(lambda) cos(lambda)
        (the bob's own centrifugal acceleration), so the swing turns at the rate about the plumb line, Omega . up,
        not Omega sin(lambda): ``|Omega . up - Omega sin(lambda)| / |Omega sin(lambda)|`` ~ (Omega/omega0)^2
        cos^2(lambda), computed exactly.
        ``"airy"``: a pendulum released from rest in the frame swings in an ellipse of minor semi-axis b = a
        Omega_z / omega0 (N2), which precesses at (3/8) omega0 a b / l^2 against the Foucault turn (Airy [A]):
        relative (3/8) sin^2(amplitude); the centrifugal anisotropy (below) modulates b by up to cot^2(lambda)
        of itself as the plane turns, hence ``(3/8) sin^2(a) (1 + cot^2 lambda)``.
        ``"anisotropy"``: the centrifugal term stiffens the swing differently along East and North, by
        ``Delta(omega^2) = Omega^2 cos^2(lambda)``; against the Coriolis splitting 2 Omega_z it makes the plane's
        rate vary with its azimuth by kappa = (Omega/omega0) cos^2(lambda) / (2 |sin lambda|), and the mean over
        a half turn moves by O(kappa^2): ``kappa^2``.
    """
    wz_geo = abs(float(np.linalg.norm(rate_vec)) * np.sin(latitude))
    wz = abs(float(-np.dot(rate_vec, down)))
    ratio = float(np.linalg.norm(rate_vec)) / omega0
    cot2 = (np.cos(latitude) / np.sin(latitude)) ** 2
    kappa = ratio * np.cos(latitude) ** 2 / (2 * abs(np.sin(latitude)))
    return {
        "tilt": abs(wz - wz_geo) / wz_geo,
        "airy": 0.375 * np.sin(amplitude) ** 2 * (1 + cot2),
        "anisotropy": float(kappa**2),
    }


# The cross terms between the neglected terms: the largest error of N2 against the full nonlinear rotating-frame
# pendulum (`rotating_pendulum`) on a grid over the scenario's domain (|lambda| 30-90 deg, Omega/omega0 0.01-0.05,
# amplitude 0.01-0.05 rad, three release azimuths) is 0.94 of the terms' plain sum (tests/test_rotating_analytic.py).
PRECESSION_MARGIN = 1.25


def precession_tolerance(terms: dict[str, float]) -> float:
    """The relative error N2 may show from the terms it neglects: ``PRECESSION_MARGIN`` x their sum."""
    return PRECESSION_MARGIN * float(sum(terms.values()))


def rotating_pendulum(
    length: float,
    field: np.ndarray,
    rate_vec: np.ndarray,
    r0: np.ndarray,
    v0: np.ndarray,
    t_end: float,
    *,
    rtol: float = 1e-12,
    inertia_ratio: float = 0.0,
    spin: float | None = None,
) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The spherical pendulum in the rotating frame, integrated without approximation (docs/theory.md N1).

    The bob (point mass on a massless rod of length l from the pivot at the origin) obeys ``r'' = a_N1(r, v) +
    lambda r``, the tension multiplier ``lambda = -(|v|^2 + r . a_N1) / l^2`` keeping |r| = l; integrated by
    scipy's DOP853 at `rtol` (absolute tolerance `rtol` x l), the same rod constraint as docs/theory.md N2's
    independent check.

    A bob of moment of inertia I about its centre, the same about every axis (`inertia_ratio` k = I / (m l^2)),
    makes the pendulum a rigid body: its spin s = omega . r/l about the rod (inertial angular velocity) is then
    constant, and the moment of m r x a + I omega' = m r x g about the pivot gives the tangential acceleration
    ``(m r x g - I s v_I / l) x r / (m l^2 + I)`` -- gravity reduced by 1/(1 + k) against the inertial terms
    (the rotating frame's Coriolis and centrifugal accelerations are kinematic: they keep their full size), and a
    gyroscopic ``-(k s / ((1 + k) l)) v_I x r``, v_I = v + Omega x r the inertial velocity. `spin` s (rad/s)
    defaults to ``Omega . r0 / l``: released without turning about its rod relative to the frame.

    Returns
    -------
    callable
        ``t -> (r, v)`` (m, m/s), each of shape (3, len(t)), for ``0 <= t <= t_end``.
    """
    k = float(inertia_ratio)
    gx, gy, gz = (float(c) / (1 + k) for c in field)
    wx, wy, wz = (float(c) for c in rate_vec)
    if spin is None:
        spin = float(np.dot(rate_vec, r0)) / float(np.linalg.norm(r0))
    gyro = k * float(spin) / ((1 + k) * float(length))

    def rhs(_t, s):
        # N1 written out in floats (np.cross costs ~5 us a call; the solver calls this ~1e5 times a run).
        x, y, z, vx, vy, vz = s.tolist()
        cx, cy, cz = wy * z - wz * y, wz * x - wx * z, wx * y - wy * x  # w x r
        ax = gx - 2 * (wy * vz - wz * vy) - (wy * cz - wz * cy)
        ay = gy - 2 * (wz * vx - wx * vz) - (wz * cx - wx * cz)
        az = gz - 2 * (wx * vy - wy * vx) - (wx * cy - wy * cx)
        if gyro:
            ux, uy, uz = vx + cx, vy + cy, vz + cz  # v_I
            ax -= gyro * (uy * z - uz * y)
            ay -= gyro * (uz * x - ux * z)
            az -= gyro * (ux * y - uy * x)
        tension = -(vx * vx + vy * vy + vz * vz + x * ax + y * ay + z * az) / (x * x + y * y + z * z)
        return np.array([vx, vy, vz, ax + tension * x, ay + tension * y, az + tension * z])

    sol = integrate.solve_ivp(
        rhs,
        (0.0, float(t_end)),
        np.concatenate([r0, v0]),
        method="DOP853",
        rtol=rtol,
        atol=rtol * length,
        dense_output=True,
    )
    if not sol.success:
        raise RuntimeError(f"rotating_pendulum: {sol.message}")

    def motion(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s = sol.sol(np.atleast_1d(np.asarray(t, dtype=float)))
        return s[:3], s[3:]

    return motion


# ---------------------------------------------------------------------------------------------------------
# N3 Eastward deflection
# ---------------------------------------------------------------------------------------------------------


def fall_time(g: float, height: float) -> float:
    """t0 = sqrt(2 h / g) (s), the time to fall h from rest in a field g, ignoring the rotation."""
    return float(np.sqrt(2 * height / g))


def eastward_deflection(rate: float, g: float, height: float, latitude: float) -> float:
    """Eastward displacement (m) of a body dropped from rest through height h (docs/theory.md N3, Wilcox section 10.5).

    ``d_E = (1/3) Omega g t0^3 cos(lambda) = (1/3) Omega cos(lambda) sqrt(8 h^3 / g)``: first order in Omega
    (the Coriolis force of the free-fall velocity); `eastward_neglected_terms` sizes the rest.
    """
    return float(rate * np.cos(latitude) * np.sqrt(8 * height**3 / g) / 3)


def eastward_neglected_terms(rate: float, g: float, height: float) -> float:
    """Relative size of what N3 leaves out, measured where the body has fallen h (not at the fixed time t0).

    The exact motion (`drop_path`) expanded in x = Omega t: East ``(1/3) Omega g t^3 cos(lambda) (1 - x^2/10 +
    O(x^4))``, Up ``-(g t^2/2)(1 - x^2 cos^2(lambda)/4 + O(x^4))``, so the body reaches -h later, at t0 (1 +
    x0^2 cos^2(lambda)/8), and its eastward displacement there is N3 times ``1 + x0^2 (3 cos^2(lambda)/8 - 1/10)
    + O(x0^4)``: at most (3/8) x0^2 in size (x0 = Omega t0); the O(x0^4) remainder is bounded by x0^4 for x0 <= 0.5
    (tests/test_rotating_analytic.py). Returns ``(3/8) x0^2 + x0^4``.
    """
    x0 = rate * fall_time(g, height)
    return float(0.375 * x0**2 + x0**4)


def _one_minus_cos_over_sq(x: np.ndarray) -> np.ndarray:
    """(1 - cos x) / x^2, accurate at small x."""
    return np.where(
        np.abs(x) > 1e-3, 2 * np.sin(x / 2) ** 2 / np.where(x == 0, 1, x) ** 2, 0.5 - x**2 / 24 + x**4 / 720
    )


def _x_minus_sin_over_cube(x: np.ndarray) -> np.ndarray:
    """(x - sin x) / x^3, accurate at small x."""
    safe = np.where(np.abs(x) > 1e-2, x, 1.0)
    return np.where(np.abs(x) > 1e-2, (safe - np.sin(safe)) / safe**3, 1 / 6 - x**2 / 120 + x**4 / 5040)


def drop_path(t: np.ndarray, field: np.ndarray, rate_vec: np.ndarray, r0: np.ndarray | None = None) -> np.ndarray:
    """Exact position (m, rotating-frame axes) of a body released at rest in the frame, in a field fixed in it.

    docs/theory.md N1 integrated in closed form: in the inertial frame (coinciding with the rotating one at t = 0) the
    field turns, ``g_I(s) = R(s) g`` with R the rotation by Omega s about Omega's axis, so ``r_I(t) = r0 + (Omega
    x r0) t + integral_0^t (t - s) R(s) g ds``; with ``g = g_par + g_perp`` (along and across the axis n) the
    integral is ``g_par t^2/2 + g_perp (1 - cos Omega t)/Omega^2 + (n x g_perp)(Omega t - sin Omega t)/Omega^2``,
    and ``r(t) = R(t)^T r_I(t)``. Includes every order in Omega: Coriolis, centrifugal and their products.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Times (s) from the release.
    field : ndarray, shape (3,)
        g (m/s^2), fixed in the rotating frame.
    rate_vec : ndarray, shape (3,)
        Omega (rad/s).
    r0 : ndarray, shape (3,), optional
        Release point (m) relative to a point of the axis; default the origin.

    Returns
    -------
    ndarray, shape (n, 3)
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    g = np.asarray(field, dtype=float)
    r0 = np.zeros(3) if r0 is None else np.asarray(r0, dtype=float)
    w = float(np.linalg.norm(rate_vec))
    n = np.asarray(rate_vec, dtype=float) / w if w > 0 else np.array([0.0, 0.0, 1.0])
    g_par = np.dot(g, n) * n
    g_perp = g - g_par
    x = w * t
    tt = t[:, None]
    r_inertial = (
        r0
        + np.cross(np.asarray(rate_vec, dtype=float), r0) * tt
        + g_par * tt**2 / 2
        + g_perp * (tt**2 * _one_minus_cos_over_sq(x)[:, None])
        + np.cross(n, g_perp) * (w * tt**3 * _x_minus_sin_over_cube(x)[:, None])
    )
    # r = R(t)^T r_I: rotate each back by -Omega t.
    c, s = np.cos(-x)[:, None], np.sin(-x)[:, None]
    return r_inertial * c + np.cross(n, r_inertial) * s + n * (r_inertial @ n)[:, None] * (1 - c)


def landing(
    field: np.ndarray, rate_vec: np.ndarray, height: float, r0: np.ndarray | None = None
) -> tuple[float, np.ndarray]:
    """Time (s) and position (m) at which the exact drop (`drop_path`) has fallen `height` along the field from
    its release point.

    Returns
    -------
    (t_h, r_h)
        The first time at which ``r . g_hat = height`` (g_hat the field's direction), and r there.
    """
    g = np.asarray(field, dtype=float)
    ghat = g / np.linalg.norm(g)
    t0 = fall_time(float(np.linalg.norm(g)), height)
    start = np.zeros(3) if r0 is None else np.asarray(r0, dtype=float)

    def fallen(t: float) -> float:
        return float((drop_path(np.array([t]), g, rate_vec, r0)[0] - start) @ ghat) - height

    t_h = optimize.brentq(fallen, 0.5 * t0, 2.0 * t0, xtol=1e-15 * t0, rtol=4 * np.finfo(float).eps)
    return float(t_h), drop_path(np.array([t_h]), g, rate_vec, r0)[0]
