"""The physics layer shared by the rotating-platform scenarios (``foucault``, ``eastward-deflection``).

Model conventions (``models/foucault.xml``, ``models/eastward_deflection.xml``): the body ``platform`` turns on
the hinge ``spin`` about the axis (0, cos lambda, sin lambda) of its own frame, which is the local East-North-Up
frame at latitude lambda (docs/theory.md section 0) and coincides with the world frame at t = 0. MuJoCo's gravity is
off; gravity is the uniform field (0, 0, -g) fixed in the platform's axes, declared as rigidbench.forces'
``rigidbench:frame-field`` (text: ``platform`` then the bodies that feel it; numeric: the field). The platform's
rate Omega is the hinge's initial velocity, the custom numeric ``rate``.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from rigidbench import forces
from rigidbench.params import Param, Range, Value

PLATFORM, SPIN = "platform", "spin"


@dataclass(frozen=True)
class Latitude:
    """Latitude lambda (rad, signed) of the platform: its hinge axis is (0, cos lambda, sin lambda) in its own
    (East-North-Up) axes. Read back from the compiled (normalised) axis as atan2(z, y)."""

    joint: str = SPIN

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        lam = float(value)
        spec.joint(self.joint).axis = [0.0, np.cos(lam), np.sin(lam)]

    def read(self, model: mujoco.MjModel) -> Value:
        axis = model.joint(self.joint).axis
        return float(np.arctan2(axis[2], axis[1]))


@dataclass(frozen=True)
class PlatformGravity:
    """Magnitude g (m/s^2) of the field (0, 0, -g) fixed in the platform's axes (`rigidbench.forces.FrameField`)."""

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        spec.numeric(forces.FRAME_FIELD).data = [0.0, 0.0, -float(value)]

    def read(self, model: mujoco.MjModel) -> Value:
        return float(-model.numeric(forces.FRAME_FIELD).data[2])


# The parameters every rotating-platform scenario has (the rate's range differs: each scenario bounds it by its
# own theory's domain).
GRAVITY = Param(
    "g",
    "m/s^2",
    "gravity, fixed in the platform's axes along its -z (local down)",
    Range(0.1, 100.0),
    PlatformGravity(),
)
LATITUDE = Param(
    "latitude",
    "rad",
    "latitude lambda: the platform turns about (0, cos lambda, sin lambda) in its East-North-Up axes",
    Range(-np.pi / 2, np.pi / 2),
    Latitude(),
)


@dataclass(frozen=True)
class Platform:
    """What the predictions read back from a compiled model and its initial state."""

    latitude: float  # rad, from the compiled hinge axis
    axis: np.ndarray  # unit, platform axes
    rate: float  # rad/s, the hinge's initial velocity
    field: np.ndarray  # m/s^2, platform axes
    inertia: float  # kg m^2, the platform's moment about its hinge axis

    @property
    def rate_vec(self) -> np.ndarray:
        return self.rate * self.axis

    @property
    def g(self) -> float:
        return float(np.linalg.norm(self.field))


def platform(model: mujoco.MjModel, data: mujoco.MjData) -> Platform:
    """The platform as compiled and started: axis, latitude, rate, the field, its moment about the axis."""
    joint = model.joint(SPIN)
    axis = np.array(joint.axis, dtype=float)
    body = model.body(PLATFORM)
    law = forces.frame_field(model)
    if law is None:
        raise ValueError(
            "a rotating-platform model must declare rigidbench:frame-field (gravity fixed in the platform)"
        )
    return Platform(
        latitude=float(np.arctan2(axis[2], axis[1])),
        axis=axis,
        rate=float(data.qvel[joint.dofadr[0]]),
        field=law.field_frame.copy(),
        inertia=float(axis @ np.diag(body.inertia) @ axis),
    )


def rotate(quat: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Vectors `v` (..., 3) rotated by unit quaternions `quat` (..., 4), (w, x, y, z): R(q) v."""
    w, u = quat[..., :1], quat[..., 1:]
    t = 2 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def spin_angle(model: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
    """The platform's hinge angle (rad) in each row of `qpos`."""
    return qpos[:, model.joint(SPIN).qposadr[0]]


def spin_rate(model: mujoco.MjModel, qvel: np.ndarray) -> np.ndarray:
    """The platform's rate (rad/s) in each row of `qvel`."""
    return qvel[:, model.joint(SPIN).dofadr[0]]


def world_to_platform(model: mujoco.MjModel, qpos: np.ndarray, v_world: np.ndarray) -> np.ndarray:
    """World-frame vectors (n, 3) expressed in the platform's axes at each row of `qpos`: R(-theta) about the
    compiled hinge axis (the platform's frame is the world's at theta = 0)."""
    axis = np.array(model.joint(SPIN).axis, dtype=float)
    theta = -spin_angle(model, qpos)[:, None]
    c, s = np.cos(theta), np.sin(theta)
    return v_world * c + np.cross(axis, v_world) * s + axis * (v_world @ axis)[:, None] * (1 - c)
