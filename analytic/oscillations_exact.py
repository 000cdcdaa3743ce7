"""The pendulum family's nonlinear equations of motion, solved to high precision: the exact reference of the
linear-regime cases' companion checks (docs/theory.md O3-O7, "exact").

The closed forms of `rigidbench.analytic.oscillations` are linear (small angles); their checks' tolerances are sized by
the neglected amplitude^2 terms. The companions compare the simulation with the exact solution of the same idealised
model instead: rigid pendulums with point bobs (and their small own moments), exact gravity torques ``M g h sin th``,
and springs of stiffness k along the straight line between their attachment points, with the rest length the model
declares. Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2).

The solution is Picard's iteration of the variation-of-constants (Duhamel) formula in the normal coordinates of the
linearisation (Hochbruck & Ostermann, "Exponential integrators", Acta Numerica 19, 2010, section 2.1): with
``T0 th'' + V0 th = R(th, th')`` (R the exact equations' nonlinear remainder, O(a^3)),

    q_r(t) = q_r(0) cos w_r t + q_r'(0) sin(w_r t) / w_r + int_0^t sin(w_r (t - s)) / w_r  a_r^T R(s) ds,

iterated from the linear solution. Each iteration contracts the error by ~ (relative amplitude shift) x w_max t_run,
<= 1e-3 in the linear regimes the cases keep, so a few iterations reach double precision; the integrals are taken on
the caller's sample grid (refined until w_max h <= 0.02) by a sixth-order interval rule. It reports an error bound
(`ExactMotion.bound`); where it does not contract (amplitudes beyond the linear regime) it returns NaN and an
infinite bound. The tests compare it with scipy's DOP853 at rtol 1e-13 on equations written in other coordinates.

References
----------
[T] docs/theory.md, entries O3-O7.
[HO] M. Hochbruck and A. Ostermann, Exponential integrators, Acta Numerica 19 (2010) 209-286.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rigidbench.analytic.oscillations import NormalModes

# Largest w_max h of the quadrature grid (the caller's grid is refined by a whole factor until it holds).
MAX_PHASE_STEP = 0.02
# Picard iterations before giving up; converged when an iteration changes th by <= this x amplitude.
MAX_ITERATIONS = 25
CONVERGED = 1e-15


@dataclass(frozen=True)
class SpringRow:
    """Pendulums hinged side by side about parallel horizontal axes, springs between them ([T] O3, O5).

    Pendulum i turns about a hinge at ``(pivot_x[i], 0)`` (x, z; z up); ``th_i`` from the downward vertical, positive
    towards -x. Its attachment point is at ``d (-sin th_i, -cos th_i)`` from its hinge; spring s joins the points of
    pendulums ``pairs[s]`` with stiffness ``stiffness[s]`` (N/m) and rest length ``rest_length[s]`` (m), its force
    along the straight line between them. Equations of motion (exact, no small angle):

        I_O,i th_i'' = - M g h_i sin th_i - sum_s k_s (L_s - L0_s) dL_s/dth_i.
    """

    inertia_pivot: np.ndarray  # I_O of each pendulum about its hinge (kg m^2), shape (n,)
    mgl: np.ndarray  # M g h of each (N m), shape (n,)
    pivot_x: np.ndarray  # hinge positions along x (m), shape (n,)
    height: float  # d, the attachment points' distance below the hinges (m)
    pairs: Sequence[tuple[int, int]]
    stiffness: np.ndarray  # k of each spring (N/m)
    rest_length: np.ndarray  # L0 of each spring (m)

    def acceleration(self, angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
        """th'' (rad/s^2), shaped like `angles` (..., n); rates unused (no velocity-dependent force).

        The stretch ``L - L0`` is formed as ``(L^2 - L0^2) / (L + L0)`` with ``L^2 - L0^2 = (s - L0)(s + L0) + 2 s
        dx + dx^2 + dz^2`` (s the pivots' distance, dx, dz the attachment points' displacements written with
        half-angle products): no cancellation at microradian angles.
        """
        th = np.asarray(angles, dtype=float)
        torque = -np.asarray(self.mgl) * np.sin(th)
        d = self.height
        for (i, j), k, rest in zip(self.pairs, self.stiffness, self.rest_length, strict=True):
            a, b = th[..., i], th[..., j]
            s = self.pivot_x[j] - self.pivot_x[i]
            half_sum, half_diff = 0.5 * (a + b), 0.5 * (a - b)
            dx = 2 * d * np.cos(half_sum) * np.sin(half_diff)  # d (sin a - sin b)
            dz = -2 * d * np.sin(half_sum) * np.sin(half_diff)  # d (cos a - cos b)
            length2_minus = (s - rest) * (s + rest) + 2 * s * dx + dx * dx + dz * dz
            length = np.sqrt((s + dx) ** 2 + dz * dz)
            tension = k * length2_minus / (length + rest) / length  # k (L - L0) / L
            gx, gz = s + dx, dz  # P_j - P_i
            # dL/da = -(P_j - P_i) . dP_i/da / L, dP_i/da = d (-cos a, sin a); dL/db = (P_j - P_i) . dP_j/db / L
            torque[..., i] -= tension * (-(gx * (-d * np.cos(a)) + gz * (d * np.sin(a))))
            torque[..., j] -= tension * (gx * (-d * np.cos(b)) + gz * (d * np.sin(b)))
        return torque / np.asarray(self.inertia_pivot)


@dataclass(frozen=True)
class DoublePendulumModel:
    """Two rigid links in a vertical plane ([T] O6): link 1 hinged at the origin, link 2 hinged on link 1 at distance
    `hinge2` below the origin along link 1. Link i: `mass` (kg), centre of mass at `com` (m) below its hinge, own
    moment `inertia_cm` (kg m^2) about it. Absolute angles th1, th2 from the downward vertical. Lagrange's equations
    (exact; Delta = th1 - th2, c = m2 e1 c2):

        (m1 c1^2 + I1 + m2 e1^2) th1'' + c cos(Delta) th2'' + c sin(Delta) th2'^2 + (m1 c1 + m2 e1) g sin th1 = 0
        c cos(Delta) th1'' + (m2 c2^2 + I2) th2'' - c sin(Delta) th1'^2 + m2 g c2 sin th2 = 0.
    """

    mass: tuple[float, float]
    com: tuple[float, float]
    inertia_cm: tuple[float, float]
    hinge2: float
    g: float

    def acceleration(self, angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
        """(th1'', th2'') (rad/s^2), shaped like `angles` (..., 2)."""
        (m1, m2), (c1, c2), (i1, i2), e1, g = self.mass, self.com, self.inertia_cm, self.hinge2, self.g
        th, w = np.asarray(angles, dtype=float), np.asarray(rates, dtype=float)
        delta = th[..., 0] - th[..., 1]
        a11 = m1 * c1 * c1 + i1 + m2 * e1 * e1
        a22 = m2 * c2 * c2 + i2
        a12 = m2 * e1 * c2 * np.cos(delta)
        coupling = m2 * e1 * c2 * np.sin(delta)
        f1 = -coupling * w[..., 1] ** 2 - (m1 * c1 + m2 * e1) * g * np.sin(th[..., 0])
        f2 = coupling * w[..., 0] ** 2 - m2 * g * c2 * np.sin(th[..., 1])
        det = a11 * a22 - a12 * a12
        return np.stack([(a22 * f1 - a12 * f2) / det, (a11 * f2 - a12 * f1) / det], axis=-1)


@dataclass(frozen=True)
class ExactMotion:
    """The exact motion sampled at the caller's times.

    Attributes
    ----------
    angles, rates : ndarray, shape (len(t), n)
        th (rad) and th' (rad/s).
    bound : float
        Bound on max |th - th_exact| over the samples, relative to the largest initial angle: the iteration's
        remaining change (geometric tail of the last increments), the quadrature's error (the difference from a
        fourth-order rule on the same grid, an overestimate of the sixth-order rule's) and the phases' rounding
        2 eps max(1, w_max t_end); inf if not converged.
    method : str
        ``"duhamel-picard"``.
    iterations : int
    """

    angles: np.ndarray
    rates: np.ndarray
    bound: float
    method: str
    iterations: int


def _interval_weights(order: int) -> np.ndarray:
    """Weights w[o, j] of the integral over [o, o + 1] of the polynomial through nodes 0 .. order - 1 (unit step)."""
    nodes = np.arange(order, dtype=float)
    vander = np.vander(nodes, order, increasing=True).T  # row p: nodes^p
    out = np.empty((order - 1, order))
    for o in range(order - 1):
        moments = np.array([((o + 1) ** (p + 1) - o ** (p + 1)) / (p + 1) for p in range(order)])
        out[o] = np.linalg.solve(vander, moments)
    return out


_W6 = _interval_weights(6)
_W4 = _interval_weights(4)


def cumulative_integral(f: np.ndarray, h: float, order: int = 6) -> np.ndarray:
    """``F_k = int_0^{t_k} f`` on a uniform grid (step h) along axis 0, F_0 = 0: each interval by the polynomial
    through `order` neighbouring samples (centred where it can be), error O(h^(order + 1)) per interval."""
    w = _W6 if order == 6 else _W4
    n = f.shape[0]
    if n < order:
        raise ValueError(f"cumulative_integral needs at least {order} samples, got {n}")
    centre = order // 2 - 1  # the interval [centre, centre + 1] of the stencil
    pieces = np.zeros((n - 1,) + f.shape[1:])
    interior = slice(centre, n - 1 - (order - 2 - centre))
    m = interior.stop - interior.start
    for j in range(order):
        pieces[interior] += w[centre, j] * f[j : j + m]
    for k in range(0, centre):  # first intervals: stencil 0 .. order - 1
        pieces[k] = np.tensordot(w[k], f[:order], axes=1)
    for k in range(interior.stop, n - 1):  # last intervals: stencil n - order .. n - 1
        pieces[k] = np.tensordot(w[k - (n - order)], f[n - order :], axes=1)
    out = np.zeros_like(f)
    np.cumsum(pieces * h, axis=0, out=out[1:])
    return out


def motion(
    t: np.ndarray,
    acceleration: Callable[[np.ndarray, np.ndarray], np.ndarray],
    modes: NormalModes,
    angles0: np.ndarray,
    rates0: np.ndarray | None = None,
) -> ExactMotion:
    """The exact motion th(t) of ``th'' = acceleration(th, th')`` from (angles0, rates0), at the uniformly spaced
    times `t` (s, t[0] = 0), with `modes` the normal modes of its linearisation about th = 0 (module docstring).

    Raises
    ------
    ValueError
        If `t` is not uniformly spaced from 0.
    """
    t = np.asarray(t, dtype=float)
    angles0 = np.asarray(angles0, dtype=float)
    rates0 = np.zeros_like(angles0) if rates0 is None else np.asarray(rates0, dtype=float)
    n = len(t) - 1
    h = t[-1] / n
    if abs(t[0]) > 1e-12 * t[-1] or np.abs(t - h * np.arange(n + 1)).max() > 1e-9 * t[-1]:
        raise ValueError("the exact motion needs uniformly spaced times from 0")
    w = modes.frequencies
    refine = max(1, math.ceil(w.max() * h / MAX_PHASE_STEP))
    grid = np.arange(n * refine + 1) * (h / refine)
    scale = float(max(np.abs(angles0).max(), np.abs(rates0 / w.min()).max()))
    result = _picard(grid, acceleration, modes, angles0, rates0, scale)
    if result is None:  # no contraction: beyond the linear regime the caller's cases keep
        nan = np.full((n + 1, len(angles0)), np.nan)
        return ExactMotion(nan, nan, math.inf, "duhamel-picard (not converged)", MAX_ITERATIONS)
    return ExactMotion(result.angles[::refine], result.rates[::refine], result.bound, result.method, result.iterations)


def _times(a: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """``a @ matrix`` for a long (samples, n) array and a small matrix: einsum (a multithreaded BLAS spends ~10x longer
    starting its threads on such thin products than it computes)."""
    return np.einsum("ij,jk->ik", a, matrix)


def _picard(grid, acceleration, modes, angles0, rates0, scale) -> ExactMotion | None:
    w = modes.frequencies
    shapes, inertia, stiffness = modes.shapes, modes.inertia, modes.stiffness
    h = grid[1] - grid[0]
    phase = grid[:, None] * w
    cos, sin = np.cos(phase), np.sin(phase)
    q0, v0 = modes.coordinates(angles0), modes.coordinates(rates0)
    q_lin = q0 * cos + v0 * sin / w
    v_lin = -q0 * w * sin + v0 * cos
    q, v = q_lin, v_lin
    theta, rate = _times(q, shapes.T), _times(v, shapes.T)
    increments: list[float] = []
    # Double precision: an iteration's change stalls at a few eps (the remainder, a difference of O(a) terms, is
    # rounded to ~eps a); the phases w t are rounded to <= eps w t (the product and t's own rounding).
    eps = float(np.finfo(float).eps)
    floor = 64 * eps
    phase_rounding = 2 * eps * max(1.0, float(w.max()) * float(grid[-1]))
    for _ in range(MAX_ITERATIONS):
        remainder = _times(acceleration(theta, rate), inertia) + _times(theta, stiffness)  # T0 th'' + V0 th, O(a^3)
        force = _times(remainder, shapes)  # a_r^T R
        c_int = cumulative_integral(cos * force, h)
        s_int = cumulative_integral(sin * force, h)
        q = q_lin + (sin * c_int - cos * s_int) / w
        v = v_lin + cos * c_int + sin * s_int
        new_theta, new_rate = _times(q, shapes.T), _times(v, shapes.T)
        increments.append(float(np.abs(new_theta - theta).max()) / scale)
        theta, rate = new_theta, new_rate
        if not increments[-1] > max(CONVERGED, floor):
            break
        if len(increments) > 2 and increments[-1] >= increments[-2]:  # stagnated above the floor: no contraction
            break
    last = increments[-1]
    if not math.isfinite(last):
        return None
    if last <= floor:
        tail = last
    else:
        ratio = last / increments[-2] if len(increments) > 1 and increments[-2] > 0 else 1.0
        if ratio >= 0.5 or last > 1e-13:
            return None
        tail = last * ratio / (1 - ratio) + last
    # Quadrature: the fourth-order rule's difference from the sixth-order one bounds the latter's error.
    c4 = cumulative_integral(cos * force, h, order=4)
    s4 = cumulative_integral(sin * force, h, order=4)
    quad = float(np.abs(_times((sin * (c4 - c_int) - cos * (s4 - s_int)) / w, shapes.T)).max()) / scale
    return ExactMotion(theta, rate, tail + quad + phase_rounding, "duhamel-picard", len(increments))
