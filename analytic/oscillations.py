"""Closed forms for pendulums and coupled oscillations: the exact pendulum, coupled pendulums and beats, the
pendulum chain, the double pendulum, and the general small-oscillation eigenproblem.

Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2).

Conventions: angles in radians from the downward vertical; every pendulum swings in one vertical plane.
``inertia_pivot`` is a pendulum's moment of inertia about its pivot axis (kg m^2): a point bob of mass m on a
massless rod of length l has ``m l^2``; a bob with its own small moment ``I_cm`` has ``I_cm + m l^2`` (docs/theory.md
O2, R4), and every formula here takes the pivot moment so that a bob's residual inertia is accounted for
exactly rather than neglected. Springs are attached at distance d below the pivots, horizontal and relaxed at
equilibrium, so that to first order in the angles a spring of stiffness k exerts the torque ``k d^2 (th_i -
th_j)`` (docs/theory.md O3).

References
----------
[W] Wilcox, *Modern Introductory Mechanics Part II*, ch. 12 (seed 000): sections 12.1-12.5, eqs 12.10-12.26.
[T] docs/theory.md, entries O1-O7.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigidbench import lazy
from rigidbench.analytic.pendulum import (  # noqa: F401 (O1, re-exported: this module's names before the split)
    pendulum_angle,
    pendulum_period,
    pendulum_period_series,
    small_amplitude_period,
)

linalg = lazy.module("scipy.linalg")
special = lazy.module("scipy.special")


# ---------------------------------------------------------------------------------------------------------
# O7 General small-oscillation eigenproblem, and the linear solution in normal modes
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class NormalModes:
    """Normal modes of ``T th'' + V th = 0`` ([T] O7; [W] section 12.2, eqs 12.15-12.26).

    Attributes
    ----------
    frequencies : ndarray, shape (n,)
        Angular frequencies omega_r (rad/s), ascending.
    shapes : ndarray, shape (n, n)
        Column r is the mode vector a_r, normalised ``a_r^T T a_s = delta_rs`` ([W] eq. 12.22) and signed so
        that its first non-negligible component is positive.
    inertia : ndarray, shape (n, n)
        T, the kinetic-energy matrix (kg m^2).
    stiffness : ndarray, shape (n, n)
        V, the potential-energy matrix (N m / rad).
    """

    frequencies: np.ndarray
    shapes: np.ndarray
    inertia: np.ndarray
    stiffness: np.ndarray

    def coordinates(self, angles: np.ndarray) -> np.ndarray:
        """Normal coordinates ``q_r = a_r^T T th`` of angles shaped (..., n): the modal filter of eq. 12.26."""
        return np.asarray(angles) @ self.inertia @ self.shapes

    def angles(self, t: np.ndarray, angles0: np.ndarray, rates0: np.ndarray | None = None) -> np.ndarray:
        """Linear solution th(t) (rad), shape (len(t), n), from th(0) = angles0 and th'(0) = rates0 (default 0).

        Each normal coordinate oscillates alone: ``q_r(t) = q_r(0) cos(omega_r t) + q_r'(0) sin(omega_r t) /
        omega_r`` ([W] eq. 12.26).
        """
        t = np.asarray(t, dtype=float)[:, None]
        q0 = self.coordinates(angles0)
        v0 = self.coordinates(np.zeros_like(angles0) if rates0 is None else rates0)
        w = self.frequencies
        q = q0 * np.cos(w * t) + v0 * np.sin(w * t) / w
        return q @ self.shapes.T

    def shape_ratios(self) -> np.ndarray:
        """Each mode vector divided by its first component, shape (n, n) (column r: th_j / th_1 in mode r);
        +-inf or NaN where pendulum 1 is (numerically) a node of the mode."""
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            return self.shapes / self.shapes[0]


def normal_modes(inertia: np.ndarray, stiffness: np.ndarray) -> NormalModes:
    """Solve ``det(V - omega^2 T) = 0`` for a positive-definite T and V ([T] O7; [W] eqs 12.15-12.22).

    Parameters
    ----------
    inertia : array_like, shape (n, n)
        T (kg m^2), symmetric positive definite.
    stiffness : array_like, shape (n, n)
        V (N m / rad), symmetric positive definite (a stable equilibrium).

    Raises
    ------
    ValueError
        If V is not positive definite (no oscillation about this equilibrium).
    """
    T = np.atleast_2d(np.asarray(inertia, dtype=float))
    V = np.atleast_2d(np.asarray(stiffness, dtype=float))
    w2, a = linalg.eigh(V, T)  # generalised symmetric problem; eigh normalises a^T T a = 1
    if w2[0] <= 0:
        raise ValueError(f"stiffness matrix is not positive definite (omega^2 = {w2[0]:g}): no stable equilibrium")
    for r in range(a.shape[1]):
        lead = a[np.argmax(np.abs(a[:, r]) > 1e-9 * np.abs(a[:, r]).max()), r]
        a[:, r] *= np.sign(lead)
    return NormalModes(frequencies=np.sqrt(w2), shapes=a, inertia=T, stiffness=V)


# ---------------------------------------------------------------------------------------------------------
# O3-O5 Identical pendulums coupled by springs (two, or a chain of N with free ends)
# ---------------------------------------------------------------------------------------------------------


def spring_chain_matrices(
    n: int, inertia_pivot: float, mgl: float, stiffness: float, height: float
) -> tuple[np.ndarray, np.ndarray]:
    """T and V of N identical pendulums in a row, nearest neighbours joined by springs (free ends).

    ``T = I_O 1``, ``V = M g l 1 + k d^2 L`` with L the path-graph Laplacian: the linearisation of [T] O3
    (``m l^2 th_i'' = -m g l th_i - k d^2 (th_i - th_j)`` per spring), N = 2 being the coupled pair.

    Parameters
    ----------
    n : int
        Number of pendulums (>= 1).
    inertia_pivot : float
        I_O of each pendulum about its pivot (kg m^2).
    mgl : float
        Gravitational stiffness M g h of each (N m / rad).
    stiffness, height : float
        Spring constant k (N/m) and attachment distance d below the pivots (m).
    """
    lap = np.zeros((n, n))
    for i in range(n - 1):
        lap[[i, i + 1], [i, i + 1]] += 1.0
        lap[[i, i + 1], [i + 1, i]] -= 1.0
    return inertia_pivot * np.eye(n), mgl * np.eye(n) + stiffness * height**2 * lap


def coupled_frequencies(inertia_pivot: float, mgl: float, stiffness: float, height: float) -> tuple[float, float]:
    """(omega_s, omega_a) (rad/s) of two identical pendulums joined by a spring at d below the pivots.

    ``omega_s^2 = M g h / I_O`` (in phase), ``omega_a^2 = omega_s^2 + 2 k d^2 / I_O`` (anti-phase): [T] O3 (rigid
    form); for a point bob ``g/l`` and ``g/l + 2 k d^2/(m l^2)``, [W] eqs 12.10-12.24 with d = l.
    """
    ws2 = mgl / inertia_pivot
    return float(np.sqrt(ws2)), float(np.sqrt(ws2 + 2 * stiffness * height**2 / inertia_pivot))


def coupled_modes(inertia_pivot: float, mgl: float, stiffness: float, height: float) -> NormalModes:
    """Normal modes of the coupled pair with the shapes fixed by symmetry: (1, 1) and (1, -1) over sqrt(2 I_O)
    ([T] O3). The same as `normal_modes` of `spring_chain_matrices` (2, ...), but exact however weak the coupling:
    an eigensolver's vectors turn arbitrarily in the plane of two (numerically) equal frequencies."""
    T, V = spring_chain_matrices(2, inertia_pivot, mgl, stiffness, height)
    shapes = np.array([[1.0, 1.0], [1.0, -1.0]]) / np.sqrt(2 * inertia_pivot)
    return NormalModes(np.array(coupled_frequencies(inertia_pivot, mgl, stiffness, height)), shapes, T, V)


def chain_frequencies(n: int, inertia_pivot: float, mgl: float, stiffness: float, height: float) -> np.ndarray:
    """Mode frequencies (rad/s), ascending, of the free-ended chain: [T] O5.

    ``omega_r^2 = M g h / I_O + 4 kappa sin^2(r pi / (2 N))``, r = 0 ... N-1, ``kappa = k d^2 / I_O``.
    """
    r = np.arange(n)
    kappa = stiffness * height**2 / inertia_pivot
    return np.sqrt(mgl / inertia_pivot + 4 * kappa * np.sin(r * np.pi / (2 * n)) ** 2)


def chain_modes(n: int, inertia_pivot: float, mgl: float, stiffness: float, height: float) -> NormalModes:
    """Normal modes of the free-ended chain with the O5 shapes (`chain_shapes`, normalised ``a^T T a = 1``) and the
    O5 frequencies: exact however weak the coupling ([T] O5), where an eigensolver's vectors turn arbitrarily
    among (numerically) equal frequencies."""
    T, V = spring_chain_matrices(n, inertia_pivot, mgl, stiffness, height)
    shapes = chain_shapes(n) / np.sqrt(inertia_pivot)
    return NormalModes(chain_frequencies(n, inertia_pivot, mgl, stiffness, height), shapes, T, V)


def chain_shapes(n: int) -> np.ndarray:
    """Mode shapes of the free-ended chain, column r: ``th_j = cos(r pi (j + 1/2) / N)`` ([T] O5), unit norm."""
    j = np.arange(n)[:, None]
    r = np.arange(n)[None, :]
    a = np.cos(r * np.pi * (j + 0.5) / n)
    return a / np.linalg.norm(a, axis=0)


@dataclass(frozen=True)
class Beats:
    """Two identical coupled pendulums, pendulum 1 released from rest at A, pendulum 2 at rest at 0 ([T] O4).

    ``th1 = A cos(omega0 t) cos(omega_b t)``, ``th2 = A sin(omega0 t) sin(omega_b t)`` with ``omega0 = (omega_a +
    omega_s)/2``, ``omega_b = (omega_a - omega_s)/2`` ([W] section 12.4); exact for the linear system.
    """

    amplitude: float
    omega_s: float
    omega_a: float

    @property
    def carrier(self) -> float:
        """omega0 = (omega_a + omega_s)/2 (rad/s)."""
        return 0.5 * (self.omega_a + self.omega_s)

    @property
    def beat(self) -> float:
        """omega_b = (omega_a - omega_s)/2 (rad/s): each pendulum's envelope is A |cos| or A |sin| of omega_b t."""
        return 0.5 * (self.omega_a - self.omega_s)

    @property
    def transfer_time(self) -> float:
        """T_x = pi / (omega_a - omega_s) (s): all the energy is in pendulum 2 ([T] O4); inf for uncoupled modes."""
        split = self.omega_a - self.omega_s
        return float(np.pi / split) if split > 0 else float("inf")

    def angles(self, t: np.ndarray) -> np.ndarray:
        """(th1, th2) (rad), shape (len(t), 2)."""
        t = np.asarray(t, dtype=float)
        w0, wb = self.carrier, self.beat
        return self.amplitude * np.stack([np.cos(w0 * t) * np.cos(wb * t), np.sin(w0 * t) * np.sin(wb * t)], axis=-1)

    def envelope2(self, t: np.ndarray) -> np.ndarray:
        """Envelope A |sin(omega_b t)| of pendulum 2 (rad)."""
        return self.amplitude * np.abs(np.sin(self.beat * np.asarray(t, dtype=float)))


# ---------------------------------------------------------------------------------------------------------
# O6 Double pendulum
# ---------------------------------------------------------------------------------------------------------


def double_pendulum_matrices(
    mass1: float,
    mass2: float,
    length1: float,
    length2: float,
    g: float,
    inertia1: float = 0.0,
    inertia2: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """T and V of the double pendulum in absolute angles (th1, th2) from the downward vertical ([T] O6, O7).

    Bob 1 (mass1, own moment inertia1 about its centre) at length1 below the fixed pivot; bob 2 at length2
    below bob 1. Linearised Lagrangian ([W] prob. 12.4):
    ``T = [[I1 + (m1 + m2) l1^2, m2 l1 l2], [m2 l1 l2, I2 + m2 l2^2]]``, ``V = diag((m1 + m2) g l1, m2 g l2)``.
    """
    c = mass2 * length1 * length2
    T = np.array([[inertia1 + (mass1 + mass2) * length1**2, c], [c, inertia2 + mass2 * length2**2]])
    V = np.diag([(mass1 + mass2) * g * length1, mass2 * g * length2])
    return T, V


def double_pendulum_frequencies(mass1: float, mass2: float, length1: float, length2: float, g: float) -> np.ndarray:
    """(omega_slow, omega_fast) (rad/s) of point bobs: roots of the quartic of [T] O6.

    ``m1 l1 l2 w^4 - (m1 + m2) g (l1 + l2) w^2 + (m1 + m2) g^2 = 0``; equal masses and lengths give
    ``w^2 = (g/l)(2 -+ sqrt 2)`` ([W] prob. 12.4).
    """
    a = mass1 * length1 * length2
    b = -(mass1 + mass2) * g * (length1 + length2)
    c = (mass1 + mass2) * g * g
    disc = np.sqrt(b * b - 4 * a * c)
    # The smaller root as 2c / (-b + disc): no cancellation when the modes are far apart.
    return np.sqrt(np.array([2 * c / (-b + disc), (-b + disc) / (2 * a)]))


# ---------------------------------------------------------------------------------------------------------
# Beyond the linear theory: the symmetric modes of the coupled pair exactly, and the first amplitude correction
# ---------------------------------------------------------------------------------------------------------


def anti_phase_period(inertia_pivot: float, mgl: float, stiffness: float, height: float, amplitude: float) -> float:
    """Exact period (s) of the anti-phase motion th1 = -th2 of two identical pendulums joined by a spring at d
    below the pivots, released from rest at ``th1 = amplitude`` (|amplitude| < pi/2).

    By the mirror symmetry that swaps the pendulums, th1 = -th2 holds at all times. The attachment points then
    stay level, so the spring stays horizontal and is stretched by exactly ``2 d sin th``: a one-degree-of-freedom
    motion with kinetic energy ``I_O th'^2`` and potential ``V(th) = 2 M g h (1 - cos th) + 2 k d^2 sin^2 th``
    ([T] O3 without the small-angle approximation). Its period, ``4 sqrt(I_O) int_0^a dth / sqrt(V(a) - V(th))``,
    is computed with ``th = a sin(phi)`` (no end-point singularity) and ``V(a) - V(th) = 4 M g h sin((a + th)/2)
    sin((a - th)/2) + 2 k d^2 sin(a + th) sin(a - th)`` (no cancellation); ``a - th = 2 a sin^2(pi/4 - phi/2)``.
    With k = 0 (or d = 0) it is the elliptic period of O1; as a -> 0, ``2 pi / omega_a``.

    Raises
    ------
    ValueError
        If |amplitude| is not below pi/2 (beyond it the spring's stretch 2 d sin th decreases again).
    """
    from scipy import integrate

    a = abs(float(amplitude))
    if not a < np.pi / 2:
        raise ValueError(f"amplitude = {amplitude!r} rad: the anti-phase period needs |amplitude| < pi/2")
    if a == 0.0:
        return float(2 * np.pi / coupled_frequencies(inertia_pivot, mgl, stiffness, height)[1])
    kd2 = stiffness * height**2

    def integrand(phi: float) -> float:
        th = a * np.sin(phi)
        diff = 2 * a * np.sin(np.pi / 4 - phi / 2) ** 2  # a - th, without cancellation
        dv = 4 * mgl * np.sin((a + th) / 2) * np.sin(diff / 2) + 2 * kd2 * np.sin(a + th) * np.sin(diff)
        return a * np.cos(phi) / np.sqrt(dv)

    value, _ = integrate.quad(integrand, 0.0, np.pi / 2, epsabs=0.0, epsrel=1e-13, limit=200)
    return float(4 * np.sqrt(inertia_pivot) * value)


def spring_chain_quartic(mgl: float, stiffness: float, height: float):
    """The quartic part L4(th, th') of the Lagrangian of identical pendulums in a row joined by springs ([T] O3, O5).

    Gravity gives ``+ M g h th^4 / 24`` per pendulum (``- M g h (1 - cos th)`` to fourth order); a spring between
    neighbours i, j stretched by ``d (sin th_i - sin th_j)`` (its tilt changes its length only at O(th^4 d^2/s),
    the energy at fifth order) gives ``+ k d^2 (th_i - th_j)(th_i^3 - th_j^3) / 6``. Returns a function of angles
    shaped (..., n) (rates unused) -> L4 shaped (...).
    """

    def quartic(th: np.ndarray, rate: np.ndarray) -> np.ndarray:
        grav = mgl * (th**4).sum(-1) / 24
        a, b = th[..., :-1], th[..., 1:]
        spring = stiffness * height**2 * ((a - b) * (a**3 - b**3)).sum(-1) / 6
        return grav + spring

    return quartic


def double_pendulum_quartic(mass1: float, mass2: float, length1: float, length2: float, g: float):
    """The quartic part L4(th, th') of the double pendulum's Lagrangian in absolute angles ([T] O6; [W] prob. 12.4).

    ``T = ... + m2 l1 l2 cos(th1 - th2) th1' th2'`` gives ``- m2 l1 l2 (th1 - th2)^2 th1' th2' / 2``; ``V = (m1 +
    m2) g l1 (1 - cos th1) + m2 g l2 (1 - cos th2)`` gives ``+ ((m1 + m2) g l1 th1^4 + m2 g l2 th2^4) / 24``.
    """

    def quartic(th: np.ndarray, rate: np.ndarray) -> np.ndarray:
        t1, t2, w1, w2 = th[..., 0], th[..., 1], rate[..., 0], rate[..., 1]
        kinetic = -0.5 * mass2 * length1 * length2 * (t1 - t2) ** 2 * w1 * w2
        return kinetic + ((mass1 + mass2) * g * length1 * t1**4 + mass2 * g * length2 * t2**4) / 24

    return quartic


def amplitude_shifts(modes: NormalModes, quartic, amplitudes: np.ndarray) -> np.ndarray:
    """First-order relative frequency shifts ``(omega_r - Omega_r) / Omega_r`` of the normal modes oscillating with
    modal amplitudes Q_r (``q_r = Q_r cos(Omega_r t + phi_r)``, mass-normalised modes of `modes`).

    Whitham's averaged Lagrangian: with the quartic part L4 averaged over independent mode phases (no internal
    resonance), ``<L4> = sum_r A_r Q_r^4 + sum_{r<s} B_rs Q_r^2 Q_s^2`` and ``d<L>/dQ_r = 0`` give ``omega_r^2 =
    Omega_r^2 - 8 A_r Q_r^2 - 4 sum_s B_rs Q_s^2`` (Nayfeh & Mook, *Nonlinear Oscillations*, 1979, sections 4.1
    and 6.2 for the single-mode and two-mode cases). A lone pendulum gives ``-a^2/16`` (O1's series). The
    neglected terms are O(Q^4) and, near an internal resonance (omega_r ~ omega_s, 3 omega_s, ...), terms of
    relative size (shift)^2 omega / (detuning). Used to state the linear theory's domain (the amplitudes at which
    this leading correction stays below a check's tolerance).

    Parameters
    ----------
    modes : NormalModes
    quartic : callable
        L4(th, th'), vectorised over leading axes (e.g. `spring_chain_quartic`).
    amplitudes : array_like, shape (n,)
        Q_r (the normal coordinates' amplitudes, e.g. ``modes.coordinates(angles0)`` for a release from rest).

    Returns
    -------
    ndarray, shape (n,)
        Relative shift of each mode's frequency (0 for a mode not excited and not shifted by the others).
    """
    w = modes.frequencies
    n = len(w)
    q = np.asarray(amplitudes, dtype=float)
    # Trigonometric polynomials of degree <= 4 per phase are averaged exactly on 8 equally spaced phases.
    phi = 2 * np.pi * np.arange(8) / 8

    def single(r: int) -> float:
        th = np.cos(phi)[:, None] * modes.shapes[:, r]
        rate = -w[r] * np.sin(phi)[:, None] * modes.shapes[:, r]
        return float(quartic(th, rate).mean())

    A = np.array([single(r) for r in range(n)])
    f1, f2 = np.meshgrid(phi, phi, indexing="ij")
    f1, f2 = f1.ravel(), f2.ravel()
    shift2 = np.zeros(n)
    excited = np.flatnonzero(q != 0)
    for r in range(n):
        total = 8 * A[r] * q[r] ** 2
        for s in excited:
            if s == r:
                continue
            th = np.cos(f1)[:, None] * modes.shapes[:, r] + np.cos(f2)[:, None] * modes.shapes[:, s]
            rate = -(w[r] * np.sin(f1)[:, None] * modes.shapes[:, r] + w[s] * np.sin(f2)[:, None] * modes.shapes[:, s])
            B = float(quartic(th, rate).mean()) - A[r] - A[s]
            total += 4 * B * q[s] ** 2
        shift2[r] = -total  # omega_r^2 - Omega_r^2
    return np.sqrt(1 + shift2 / w**2) - 1
