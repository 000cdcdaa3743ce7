"""The bent axle: a rigid rotor turning at constant rate about a fixed axle its principal axes are tilted from.

docs/theory.md R8 (seed 001, Harter, Fig. 6.5.1; the general form is [DONE] there). For a body turning at constant
``omega = omega z`` about a fixed axle through the point O, its angular momentum about O is ``L = I_O omega`` and
the torque the axle must exert on it about O is

    N = dL/dt = omega x L = omega^2 (-I_yz, I_xz, 0),   |N| = omega^2 sqrt(I_xz^2 + I_yz^2),

with ``I_xz``, ``I_yz`` the off-diagonal entries of the inertia tensor about O (matrix entries, ``I_xz = -sum m x
z``), in axes that turn with the body (the "axle frame": z along the axle). N is fixed in those axes, so in space
it is perpendicular to the axle and turns with the body at omega. A centre of mass off the axle makes the rotor
statically unbalanced as well: the axle then also exerts the rotating net force ``F = m omega x (omega x c) = -m
omega^2 (c_x, c_y, 0)``, of size ``m omega^2 rho`` (R8's note). Neither depends on the sign of omega.

Conventions: frames are named in the variables (``_B``: the rotor's own axes, z along the axle; ``_W``: space,
the same z). Inertia tensors are about the point their name says (``inertia_O``: about O on the axle;
``inertia_cm``: about the centre of mass). Torques are about O. numpy only: no simulator imports.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

Z_AXIS = np.array([0.0, 0.0, 1.0])


def tilted_principal_frame(tilt: float) -> np.ndarray:
    """Rotation (3, 3) from principal axes (columns e1, e2, e3) to axle axes: e3 tilted by `tilt` (rad) from the
    axle (z) towards -y, a turn about x = e1.

    Parameters
    ----------
    tilt : float
        Angle (rad) between the principal axis e3 and the axle.
    """
    c, s = np.cos(tilt), np.sin(tilt)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def inertia_about_point(
    mass: float, principal: np.ndarray, rotation: np.ndarray, com: np.ndarray, point: np.ndarray | None = None
) -> np.ndarray:
    """Inertia tensor (3, 3; kg m^2) about `point`, in the axes `rotation` maps principal axes to.

    ``I_P = R diag(principal) R^T + m (|d|^2 1 - d d^T)``, ``d = com - point`` (the parallel-axis theorem, any
    mechanics text, e.g. Goldstein 3rd ed. section 5.3).

    Parameters
    ----------
    mass : float
        kg.
    principal : array (3,)
        Principal moments about the centre of mass, kg m^2.
    rotation : array (3, 3)
        Principal axes (columns) in the frame of the result.
    com : array (3,)
        Centre of mass in that frame, m.
    point : array (3,), optional
        Reference point, m (default the origin).
    """
    d = np.asarray(com, dtype=float) - (np.zeros(3) if point is None else np.asarray(point, dtype=float))
    r = np.asarray(rotation, dtype=float)
    inertia_cm = r @ np.diag(np.asarray(principal, dtype=float)) @ r.T
    return inertia_cm + mass * (float(d @ d) * np.eye(3) - np.outer(d, d))


def bearing_torque(inertia_O: np.ndarray, omega: float) -> np.ndarray:
    """Torque N_B (3,; N m) the axle exerts on the rotor about O, in the rotor's axes: ``omega x (I_O omega)``.

    docs/theory.md R8 general form: ``N = omega^2 (-I_yz, I_xz, 0)`` for ``omega = omega z``.
    """
    w = omega * Z_AXIS
    return np.cross(w, np.asarray(inertia_O, dtype=float) @ w)


def bearing_force(mass: float, com: np.ndarray, omega: float) -> np.ndarray:
    """Net force F_B (3,; N) the axle exerts on the rotor, in its axes: ``m omega x (omega x c)`` (centripetal).

    docs/theory.md R8 note: of size ``m omega^2 rho``, rho the distance of the centre of mass from the axle.
    """
    w = omega * Z_AXIS
    return mass * np.cross(w, np.cross(w, np.asarray(com, dtype=float)))


def unbalance(inertia_O: np.ndarray) -> float:
    """``sqrt(I_xz^2 + I_yz^2) / max |eig(I_O)|``: the torque's size in units of ``omega^2`` times the largest moment
    about O (0 for a dynamically balanced rotor, at most 1/2)."""
    i = np.asarray(inertia_O, dtype=float)
    return float(np.hypot(i[0, 2], i[1, 2]) / np.abs(np.linalg.eigvalsh(i)).max())


def rotate_about_axle(vectors_B: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Vectors (3,) or (n, 3) in the rotor's axes to space, the rotor turned by `angle` (rad, scalar or (n,))
    about z."""
    v = np.asarray(vectors_B, dtype=float)
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(np.broadcast_arrays(c * x - s * y, s * x + c * y, z + 0 * a), axis=-1)


def point_mass_torque(mass: float, radius: float, omega: float) -> np.ndarray:
    """docs/theory.md R8 (001, Fig. 6.5.1): a point mass at ``r (1/sqrt 2, 1/sqrt 2, 0)`` on an axle along x turning at
    omega: ``N = -1/2 m r^2 omega^2 z`` (in that figure's axes: axle x, arm in the xy-plane)."""
    return np.array([0.0, 0.0, -0.5 * mass * radius**2 * omega**2])


@dataclass(frozen=True)
class BentAxle:
    """A rotor on a fixed axle (z) through O turning at constant rate: the bearing torque and force (R8).

    Attributes
    ----------
    mass : float
        kg.
    inertia_O : ndarray (3, 3)
        Inertia tensor about O in the rotor's axes (kg m^2).
    com : ndarray (3,)
        Centre of mass in the rotor's axes (m).
    omega : float
        Axle rate (rad/s), about +z.
    angle0 : float
        Rotor angle at t = 0 (rad).
    """

    mass: float
    inertia_O: np.ndarray
    com: np.ndarray
    omega: float
    angle0: float = 0.0

    @property
    def torque_B(self) -> np.ndarray:
        """Bearing torque about O in the rotor's axes (N m): constant."""
        return bearing_torque(self.inertia_O, self.omega)

    @property
    def torque(self) -> float:
        """``|N| = omega^2 sqrt(I_xz^2 + I_yz^2)`` (N m)."""
        i = self.inertia_O
        return float(self.omega**2 * np.hypot(i[0, 2], i[1, 2]))

    @property
    def force_B(self) -> np.ndarray:
        """Net bearing force in the rotor's axes (N): constant."""
        return bearing_force(self.mass, self.com, self.omega)

    @property
    def force(self) -> float:
        """``|F| = m omega^2 rho`` (N)."""
        return float(self.mass * self.omega**2 * np.hypot(self.com[0], self.com[1]))

    @property
    def torque_scale(self) -> float:
        """``omega^2 max |eig(I_O)|`` (N m): the size the torque's round-off is relative to."""
        return float(self.omega**2 * np.abs(np.linalg.eigvalsh(self.inertia_O)).max())

    @property
    def force_scale(self) -> float:
        """``omega^2 sqrt(m max |eig(I_O)|)`` (N): the centripetal force of the rotor's mass at its radius of
        gyration about O, the size a balanced rotor's residual force is measured against."""
        return float(self.omega**2 * np.sqrt(self.mass * np.abs(np.linalg.eigvalsh(self.inertia_O)).max()))

    def angle(self, t: np.ndarray) -> np.ndarray:
        """Rotor angle (rad) at times `t` (s): ``angle0 + omega t``."""
        return self.angle0 + self.omega * np.asarray(t, dtype=float)

    def torque_W(self, t: np.ndarray) -> np.ndarray:
        """Bearing torque in space (n, 3; N m) at times `t`: N_B turned with the rotor."""
        return rotate_about_axle(self.torque_B, self.angle(t))

    def force_W(self, t: np.ndarray) -> np.ndarray:
        """Bearing force in space (n, 3; N) at times `t`."""
        return rotate_about_axle(self.force_B, self.angle(t))
