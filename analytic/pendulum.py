"""The simple pendulum at any amplitude: its exact period and angle (docs/theory.md O1).

Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2). Its own module, so that
the simple pendulum's scenario (`rigidbench.envs.pendulum`) reads only this; `rigidbench.analytic.oscillations`
re-exports every name.

Conventions: angles in radians from the downward vertical; the pendulum swings in one vertical plane, released
from rest at ``amplitude``. A physical pendulum takes its equivalent length ``I_O / (M h)`` (docs/theory.md O2).

References
----------
[W] Wilcox, *Modern Introductory Mechanics Part II*, ch. 12 (seed 000).
[T] docs/theory.md, entries O1-O2.
"""

from __future__ import annotations

import numpy as np

from rigidbench import lazy

special = lazy.module("scipy.special")


# ---------------------------------------------------------------------------------------------------------
# O1 Exact large-amplitude pendulum period
# ---------------------------------------------------------------------------------------------------------


def small_amplitude_period(length: float, g: float) -> float:
    """T0 = 2 pi sqrt(l/g) (s), the small-amplitude limit of O1."""
    return 2 * np.pi * np.sqrt(length / g)


def pendulum_period(length: float, g: float, amplitude: float) -> float:
    """Exact period (s) of a simple pendulum released from rest at `amplitude` (rad), 0 <= amplitude < pi.

    ``T = 4 sqrt(l/g) K(k)``, ``k = sin(amplitude/2)`` ([T] O1; [W] chapter 12 intro, the elliptic integral of
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
