"""Derivatives under the same theory: each integrator's one-step map of the linearised equations of motion, the
mode frequencies that map carries, and the exact sensitivity of the pendulum's period to its amplitude (issue 37).

Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2).

A state is ``x = (q, v)`` (joint angles and rates, n each); the linearised equations about a stable equilibrium
are ``T q'' + V q = 0`` ([T] O7), i.e. ``x' = J x`` with ``J = [[0, 1], [-K, 0]]``, ``K = T^-1 V``. A simulator
does not follow that flow but its integrator's discrete map ``x_{k+1} = A x_k``; the map's Jacobian is what
``mjd_transitionFD`` returns, so it is the prediction (against the exact flow ``exp(J h)`` the difference is
O(omega h), 1e-3 at the reference steps: issue 37, probed). Maps, for a step h:

- ``Euler`` (MuJoCo's semi-implicit Euler: ``v' = v + h a(q, v)``, ``q' = q + h v'``):
  ``A = [[1 - h^2 K, h], [-h K, 1]]``; its eigenvalues ``exp(+-i theta)`` with ``cos theta = 1 - (omega h)^2 / 2``.
- ``implicit``, ``implicitfast``: the Euler map with ``M - h D`` in place of ``M``; D (the velocity derivative of
  the forces) is 0 at rest in a system without dampers (Coriolis forces are quadratic in the rates), so the map
  at an equilibrium is Euler's.
- ``discrete`` (MuJoCo 3.13+): the velocity increment solved in the metric ``M + h D + h^2 K_s``, K_s the
  stiffness of the model's springs (not gravity's): ``(T + h^2 V_s) (v' - v) = -h V q``, ``q' = q + h v'``
  (measured: ``d v' / d v = 1`` exactly, ``d v' / d q = -h (T + h^2 V_s)^-1 V``); a mode r whose springs' share of
  omega^2 is omega_s,r^2 is Euler's with ``omega^2 / s_r``, ``s_r = 1 + (h omega_s,r)^2`` (when V_s commutes
  with T^-1 V, as in every scenario here).
- ``RK4``: for a linear system the degree-4 Taylor polynomial of ``exp(J h)``; a mode's eigenvalue
  ``R(i omega h)``, ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24``. About a state off equilibrium the RK4 map's
  Jacobian is RK4 applied to the variational equations (Runge-Kutta methods commute with linearisation).

References
----------
[T] docs/theory.md, entries O1 (exact pendulum period), O3-O7 (normal modes).
[H] Hairer, Lubich, Wanner, *Geometric Numerical Integration*, ch. I.1 and VI.5 (linear stability functions, the
    commuting of Runge-Kutta maps with linearisation).
"""

from __future__ import annotations

import numpy as np

from rigidbench import lazy

special = lazy.module("scipy.special")

EULER_FAMILY = ("Euler", "implicit", "implicitfast")


def first_order(stiffness_over_inertia: np.ndarray) -> np.ndarray:
    """``J = [[0, 1], [-K, 0]]`` (2n x 2n) of ``q'' = -K q``."""
    K = np.atleast_2d(np.asarray(stiffness_over_inertia, dtype=float))
    n = len(K)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-K, np.zeros((n, n))]])


def flow_map(inertia: np.ndarray, stiffness: np.ndarray, h: float) -> np.ndarray:
    """The exact flow ``exp(J h)`` of ``T q'' + V q = 0`` over h (2n x 2n): in normal coordinates each mode turns by
    ``omega h`` (``[[cos, sin / omega], [-omega sin, cos]]``) ([T] O7)."""
    from rigidbench.analytic.oscillations import normal_modes

    modes = normal_modes(inertia, stiffness)
    a, w = modes.shapes, modes.frequencies
    n = len(w)
    to_modes = a.T @ modes.inertia  # q_r = a_r^T T q
    c, s = np.diag(np.cos(w * h)), np.diag(np.sin(w * h))
    P = np.block([[a, np.zeros((n, n))], [np.zeros((n, n)), a]])
    Q = np.block([[to_modes, np.zeros((n, n))], [np.zeros((n, n)), to_modes]])
    R = np.block([[c, s @ np.diag(1 / w)], [-np.diag(w) @ s, c]])
    return P @ R @ Q


def transition_map(
    integrator: str, inertia: np.ndarray, stiffness: np.ndarray, h: float, spring_stiffness: np.ndarray | None = None
) -> np.ndarray:
    """The one-step Jacobian ``d x_{k+1} / d x_k`` of `integrator` on ``T q'' + V q = 0`` at step `h` (s).

    Parameters
    ----------
    inertia, stiffness : array_like, shape (n, n)
        T (kg m^2) and V (N m / rad) in the joint coordinates the simulator integrates.
    spring_stiffness : array_like, shape (n, n), optional
        V_s, the springs' share of V (the ``discrete`` integrator's implicit stiffness); 0 by default.

    Raises
    ------
    ValueError
        For an integrator without a map here.
    """
    T = np.atleast_2d(np.asarray(inertia, dtype=float))
    V = np.atleast_2d(np.asarray(stiffness, dtype=float))
    n = len(T)
    eye = np.eye(n)
    if integrator in (*EULER_FAMILY, "discrete"):
        metric = T.copy()
        if integrator == "discrete" and spring_stiffness is not None:
            metric = metric + h * h * np.atleast_2d(spring_stiffness)
        # v' = v - h metric^-1 V q; q' = q + h v'
        dv_dq = -h * np.linalg.solve(metric, V)
        dv_dv = eye
        return np.block([[eye + h * dv_dq, h * dv_dv], [dv_dq, dv_dv]])
    if integrator == "RK4":
        Jh = first_order(np.linalg.solve(T, V)) * h
        out, term = np.eye(2 * n), np.eye(2 * n)
        for k in range(1, 5):
            term = term @ Jh / k
            out = out + term
        return out
    raise ValueError(f"no discrete map for integrator {integrator!r}")


def map_frequency(integrator: str, omega: np.ndarray, h: float, spring_share: np.ndarray | None = None) -> np.ndarray:
    """The angle per step over h (rad/s) of the eigenvalue ``exp(i theta)`` a mode of frequency `omega` has under
    `integrator`'s map (module docstring): what the map's eigenvalues must show for O3-O7's frequencies.

    `spring_share`: each mode's omega_s^2 (the springs' part of omega^2), for ``discrete``; 0 by default.
    """
    w = np.asarray(omega, dtype=float)
    z = w * h
    if integrator in EULER_FAMILY or (integrator == "discrete" and spring_share is None):
        return 2 * np.arcsin(z / 2) / h
    if integrator == "discrete":
        s = 1 + h * h * np.asarray(spring_share, dtype=float)
        return 2 * np.arcsin(z / (2 * np.sqrt(s))) / h
    if integrator == "RK4":
        iz = 1j * z
        return np.angle(1 + iz + iz**2 / 2 + iz**3 / 6 + iz**4 / 24) / h
    raise ValueError(f"no discrete map for integrator {integrator!r}")


def pendulum_transition(integrator: str, omega0_sq: float, angle: float, rate: float, h: float) -> np.ndarray:
    """The exact one-step Jacobian (2 x 2) of `integrator` on the nonlinear pendulum ``q'' = -omega0^2 sin q`` about
    the state (`angle`, `rate`): for the Euler family ``[[1 - h^2 c, h], [-h c, 1]]``, ``c = omega0^2 cos q`` (no
    velocity-dependent force: D = 0, and no spring for ``discrete``); for RK4, RK4 on the variational equations."""

    def f(x: np.ndarray) -> np.ndarray:
        return np.array([x[1], -omega0_sq * np.sin(x[0])])

    def df(x: np.ndarray) -> np.ndarray:
        return np.array([[0.0, 1.0], [-omega0_sq * np.cos(x[0]), 0.0]])

    x = np.array([angle, rate], dtype=float)
    if integrator in (*EULER_FAMILY, "discrete"):
        c = omega0_sq * np.cos(angle)
        return np.array([[1 - h * h * c, h], [-h * c, 1.0]])
    if integrator == "RK4":
        phi = np.eye(2)
        k1, K1 = f(x), df(x) @ phi
        x2, P2 = x + h / 2 * k1, phi + h / 2 * K1
        k2, K2 = f(x2), df(x2) @ P2
        x3, P3 = x + h / 2 * k2, phi + h / 2 * K2
        k3, K3 = f(x3), df(x3) @ P3
        P4 = phi + h * K3
        K4 = df(x + h * k3) @ P4
        return phi + h / 6 * (K1 + 2 * K2 + 2 * K3 + K4)
    raise ValueError(f"no discrete map for integrator {integrator!r}")


def period_amplitude_slope(length: float, g: float, amplitude: float) -> float:
    """dT/da (s/rad) of the exact pendulum period ``T = 4 sqrt(l/g) K(m)``, ``m = sin^2(a/2)`` ([T] O1):
    ``dK/dm = (E(m) - (1 - m) K(m)) / (2 m (1 - m))`` (Abramowitz & Stegun 17.3.11 with 17.3.12), ``dm/da =
    sin(a) / 2``. Exact; its round-off is that of E - (1 - m) K, ~ eps / m (1e-10 relative at a = 0.01 rad)."""
    if not 0.0 < amplitude < np.pi:
        raise ValueError(f"amplitude = {amplitude!r} rad is outside (0, pi)")
    m = np.sin(amplitude / 2) ** 2
    dk_dm = (special.ellipe(m) - (1 - m) * special.ellipk(m)) / (2 * m * (1 - m))
    return float(4 * np.sqrt(length / g) * dk_dm * np.sin(amplitude) / 2)


# ---------------------------------------------------------------------------------------------------------
# A torque-free rigid body: Euler's equations in the body frame ([T] S1)
# ---------------------------------------------------------------------------------------------------------


def _cross_matrix(a: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def euler_rates(inertia: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """``omega' = I^-1 ((I omega) x omega)``: Euler's equations, body frame, principal moments `inertia` (3,)."""
    i = np.asarray(inertia, dtype=float)
    w = np.asarray(omega, dtype=float)
    return np.cross(i * w, w) / i


def euler_jacobian(inertia: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """``d omega' / d omega = I^-1 ([I omega]x - [omega]x I)`` (3 x 3) of Euler's equations."""
    i = np.asarray(inertia, dtype=float)
    w = np.asarray(omega, dtype=float)
    return (_cross_matrix(i * w) - _cross_matrix(w) @ np.diag(i)) / i[:, None]


def rotation_map(integrator: str, inertia: np.ndarray, omega: np.ndarray, h: float) -> np.ndarray:
    """The one-step Jacobian ``d omega_(k+1) / d omega_k`` (3 x 3) of a free body's body-frame rates under
    `integrator` (the rates do not depend on the orientation without torques):

    - ``Euler``: ``1 + h J``, J = `euler_jacobian`;
    - ``implicit``, and as measured ``implicitfast`` and ``discrete`` too (MuJoCo keeps a free body's gyroscopic
      derivative in their D; docs/derivatives.md): D = I J, the Coriolis forces' rate derivative, so
      ``omega' = omega + h (1 - h J)^-1 f``, whose Jacobian is ``1 + h (1 - h J)^-1 (J + h (dJ . (1 - h J)^-1 f))``,
      J linear in omega;
    - ``RK4``: RK4 on the variational equations of Euler's.
    """
    w = np.asarray(omega, dtype=float)
    J = euler_jacobian(inertia, w)
    eye = np.eye(3)
    if integrator == "Euler":
        return eye + h * J
    if integrator in ("implicit", "implicitfast", "discrete"):
        solve = np.linalg.inv(eye - h * J)
        step = solve @ euler_rates(inertia, w)  # (1 - h J)^-1 f
        dJ = np.stack([euler_jacobian(inertia, e) for e in eye])  # dJ / d omega_k (J is linear in omega)
        extra = np.stack([dJ[k] @ step for k in range(3)], axis=1)  # column k: dJ_k (1 - h J)^-1 f
        return eye + h * solve @ (J + h * extra)
    if integrator == "RK4":

        def f(x: np.ndarray) -> np.ndarray:
            return euler_rates(inertia, x)

        def df(x: np.ndarray) -> np.ndarray:
            return euler_jacobian(inertia, x)

        k1, K1 = f(w), df(w)
        w2, P2 = w + h / 2 * k1, eye + h / 2 * K1
        k2, K2 = f(w2), df(w2) @ P2
        w3, P3 = w + h / 2 * k2, eye + h / 2 * K2
        k3, K3 = f(w3), df(w3) @ P3
        K4 = df(w + h * k3) @ (eye + h * K3)
        return eye + h / 6 * (K1 + 2 * K2 + 2 * K3 + K4)
    raise ValueError(f"no rotation map for integrator {integrator!r}")


def rotation_map_rate(integrator: str, rate: float, h: float) -> float:
    """The angle per step over h (rad/s) of the eigenvalue a body-frame precession of `rate` (linearised about a
    steady spin about a symmetry axis: ``omega_perp' = rate e3 x omega_perp``) has under `integrator`:
    ``atan(rate h) / h`` for the Euler family and discrete (``1 + i rate h``, and ``1 / (1 - i rate h)`` for
    implicit), and ``arg R(i rate h) / h`` for RK4."""
    z = rate * h
    if integrator in (*EULER_FAMILY, "discrete"):
        return float(np.arctan(z) / h)
    if integrator == "RK4":
        iz = 1j * z
        return float(np.angle(1 + iz + iz**2 / 2 + iz**3 / 6 + iz**4 / 24) / h)
    raise ValueError(f"no rotation map for integrator {integrator!r}")
