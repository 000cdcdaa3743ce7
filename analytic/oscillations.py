"""Closed forms for pendulums and coupled oscillations: the exact pendulum, coupled pendulums and beats, the
pendulum chain, the double pendulum, and the general small-oscillation eigenproblem.

Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2).

Conventions: angles in radians from the downward vertical; every pendulum swings in one vertical plane.
``inertia_pivot`` is a pendulum's moment of inertia about its pivot axis (kg m^2): a point bob of mass m on a
massless rod of length l has ``m l^2``; a bob with its own small moment ``I_cm`` has ``I_cm + m l^2`` (THEORY.md
O2, R4), and every formula here takes the pivot moment so that a bob's residual inertia is accounted for
exactly rather than neglected. Springs are attached at distance d below the pivots, horizontal and relaxed at
equilibrium, so that to first order in the angles a spring of stiffness k exerts the torque ``k d^2 (th_i -
th_j)`` (THEORY.md O3).

References
----------
[W] Wilcox, *Modern Introductory Mechanics Part II*, ch. 12 (seed 000): sections 12.1-12.5, eqs 12.10-12.26.
[T] ../shared/THEORY.md, entries O1-O7.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg, special

# ---------------------------------------------------------------------------------------------------------
# O1 Exact large-amplitude pendulum period
# ---------------------------------------------------------------------------------------------------------


def small_amplitude_period(length: float, g: float) -> float:
    """T0 = 2 pi sqrt(l/g) (s), the small-amplitude limit of O1."""
    return 2 * np.pi * np.sqrt(length / g)


def pendulum_period(length: float, g: float, amplitude: float) -> float:
    """Exact period (s) of a simple pendulum released from rest at `amplitude` (rad), 0 <= amplitude < pi.

    ``T = 4 sqrt(l/g) K(k)``, ``k = sin(amplitude/2)`` ([T] O1; [W] section 12 intro, the elliptic integral of
    the pendulum). For a physical pendulum pass the equivalent length ``I_O/(M h)`` ([T] O2).

    Raises
    ------
    ValueError
        If the amplitude is not in [0, pi) (at pi the pendulum balances upright: no period).
    """
    if not 0.0 <= amplitude < np.pi:
        raise ValueError(f"amplitude = {amplitude!r} rad is outside [0, pi)")
    k = np.sin(amplitude / 2)
    return float(4 * np.sqrt(length / g) * special.ellipk(k * k))  # scipy takes m = k^2


def pendulum_period_series(length: float, g: float, amplitude: float) -> float:
    """Two-term series ``T0 (1 + a^2/16 + 11 a^4/3072)`` of O1 (rel. error 2.4e-4 at 1 rad, 7 % at 2.5 rad)."""
    return small_amplitude_period(length, g) * (1 + amplitude**2 / 16 + 11 * amplitude**4 / 3072)


def pendulum_angle(t: np.ndarray, length: float, g: float, amplitude: float) -> np.ndarray:
    """Exact angle (rad) of a pendulum released from rest at `amplitude` at t = 0.

    ``sin(th/2) = k cd(omega0 t, k)`` with ``k = sin(amplitude/2)``, ``omega0 = sqrt(g/l)``: the Jacobi form of
    the solution behind O1 (cd = cn/dn, quarter period K(k)/omega0).
    """
    k = np.sin(amplitude / 2)
    sn, cn, dn, _ = special.ellipj(np.sqrt(g / length) * np.asarray(t, dtype=float), k * k)
    return 2 * np.arcsin(np.clip(k * cn / dn, -1.0, 1.0))


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


def chain_frequencies(n: int, inertia_pivot: float, mgl: float, stiffness: float, height: float) -> np.ndarray:
    """Mode frequencies (rad/s), ascending, of the free-ended chain: [T] O5.

    ``omega_r^2 = M g h / I_O + 4 kappa sin^2(r pi / (2 N))``, r = 0 ... N-1, ``kappa = k d^2 / I_O``.
    """
    r = np.arange(n)
    kappa = stiffness * height**2 / inertia_pivot
    return np.sqrt(mgl / inertia_pivot + 4 * kappa * np.sin(r * np.pi / (2 * n)) ** 2)


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
        """T_x = pi / (omega_a - omega_s) (s): all the energy is in pendulum 2 ([T] O4)."""
        return np.pi / (self.omega_a - self.omega_s)

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
