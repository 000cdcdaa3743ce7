"""Frames and rotations, vectorised over time.

Quaternions are MuJoCo's (w, x, y, z), body-to-world. `R_WB` maps body-frame components to world-frame ones.
Euler angles follow docs/theory.md section 0 (z-x-z, Goldstein = Wilcox section 11.7): R = Rz(phi) Rx(theta) Rz(psi).
"""

from __future__ import annotations

import math

import numpy as np


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices R_WB, shape (..., 3, 3), from unit quaternions (w, x, y, z), shape (..., 4).

    The quaternions are normalised first (MuJoCo normalises them only when it integrates).
    """
    q = np.asarray(quat, dtype=float)
    if q.size == 4:  # one state (an env step): the same arithmetic on floats, not ~40 ufunc calls on 1-element arrays
        return _quat_to_matrix_one(*q.ravel().tolist()).reshape(*q.shape[:-1], 3, 3)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    R = np.empty((*q.shape[:-1], 3, 3))  # filled in place: no stacking copies over long trajectories
    R[..., 0, 0] = 1 - 2 * (y * y + z * z)
    R[..., 0, 1] = 2 * (x * y - w * z)
    R[..., 0, 2] = 2 * (x * z + w * y)
    R[..., 1, 0] = 2 * (x * y + w * z)
    R[..., 1, 1] = 1 - 2 * (x * x + z * z)
    R[..., 1, 2] = 2 * (y * z - w * x)
    R[..., 2, 0] = 2 * (x * z - w * y)
    R[..., 2, 1] = 2 * (y * z + w * x)
    R[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def _quat_to_matrix_one(w: float, x: float, y: float, z: float) -> np.ndarray:
    return np.array(matrix_rows(w, x, y, z))


def matrix_rows(w, x, y, z, sqrt=math.sqrt) -> tuple[tuple[float, float, float], ...]:
    """R_WB of one quaternion (w, x, y, z), normalised first, as three rows of Python floats: `quat_to_matrix`
    for a single state (an env step) without arrays. With ``sqrt=np.sqrt`` the components may be arrays (one
    element per copy of a batched env: rows of arrays, the same bits as each copy's floats).

    The operations of the vectorised path in the same order (numpy sums the 4 squares left to right), so the
    same bits: tests/test_performance.py checks it.
    """
    n = sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return (
        (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )


def body_to_world(R_WB: np.ndarray, v_B: np.ndarray) -> np.ndarray:
    """Rotate body-frame vectors, shape (..., 3), into the world frame."""
    return np.einsum("...ij,...j->...i", R_WB, v_B)


def quat_from_euler_zxz(phi: float, theta: float, psi: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of R = Rz(phi) Rx(theta) Rz(psi)."""

    def about(axis: int, angle: float) -> np.ndarray:
        q = np.zeros(4)
        q[0] = np.cos(angle / 2)
        q[1 + axis] = np.sin(angle / 2)
        return q

    return _qmul(_qmul(about(2, phi), about(0, theta)), about(2, psi))


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )


def azimuth_about(axis_W: np.ndarray, v_W: np.ndarray) -> np.ndarray:
    """Angle (rad) of vectors `v_W`, shape (n, 3), about the fixed unit `axis_W`, from an arbitrary zero."""
    a = axis_W / np.linalg.norm(axis_W)
    helper = np.eye(3)[np.argmin(np.abs(a))]
    u = np.cross(a, helper)
    u /= np.linalg.norm(u)
    w = np.cross(a, u)
    return np.arctan2(v_W @ w, v_W @ u)


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (rad) between rows of `a` and `b` (or a fixed vector), robust near 0 and pi."""
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.sum(a * b, axis=-1)
    return np.arctan2(cross, dot)
