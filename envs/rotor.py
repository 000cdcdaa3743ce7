"""The physics layer shared by the tops: one rigid body turning about a fixed point (its CM or a pivot).

Turns MuJoCo's raw state rows into named physical quantities with their frames in their names
(house rule 6). Works on a whole trajectory at once (vectorised over time) or on a single state.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import frames
from rigidbench.envs.base import ScenarioEnv
from rigidbench.params import Numeric, Param, Range

OMEGA_PARAM = Param(
    "omega",
    "rad/s",
    "initial angular velocity in body principal axes (omega1, omega2, omega3)",
    Range(-100, 100),
    Numeric("omega"),
    size=3,
)

# Principal moments of the free tops (kg m^2). Their motion depends only on the ratios of the moments (and omega),
# so the scale is free: four decades below the defaults (~1 kg m^2) to three above. MuJoCo solves for the angular
# acceleration in world axes, with an inertia matrix of condition I_max / I_min (up to 1e7 here): the round-off that
# puts in the rates is bounded where it matters by the scenarios' domains (measured at I3 / I1 = 1e-8, omega-body
# 5e-11; at 1e-10, 2e-9; free-symmetric-top keeps I1 / I3 <= 1e3, see its domain 'axial-round-off').
FREE_INERTIA = Range(1e-4, 1e3)

# The smallest turn per step (rad) of a rate a check measures as a slope: MuJoCo adds each step's change of the state
# to it and rounds it to an ulp, so a phase that turns by x rad per step carries a rounding error of up to eps/x of
# its advance (systematic in the worst case: the rounding of a change far below an ulp is biased). 2 eps / 1e-8
# keeps it at half the 1e-8 tolerance of the rate checks. Measured: a body-frame precession turning 5e-13 rad per
# step came out 7e-5 off (the bound: 4e-4).
MIN_TURN_PER_STEP = 2 * float(np.finfo(float).eps) / 1e-8


# Most steps of a free-symmetric-top run (1.5e5 at the prolate default); the rates are slopes of phases and need no
# whole turns.
MAX_FREE_STEPS = 200_000


# MuJoCo rotates a quaternion by |omega| h about omega / |omega|, and skips the rotation where |omega| < mjMINVAL =
# 1e-15 (mju_normalize3 returns 0): a body turning slower does not turn in MuJoCo at all (measured: a free top at
# |omega| = 1e-16 rad/s keeps its orientation, momentum drift 2). Refused below MIN_RATE, which keeps the slowest
# |omega| along a free motion (>= sqrt(I_min / I_max) of the start) well above it.
MIN_RATE = 1e-9


def mujoco_min_rate(p: Mapping[str, Any]) -> str | None:
    """Domain test: |omega| >= MIN_RATE (MuJoCo's mjMINVAL, see there)."""
    speed = float(np.linalg.norm(np.asarray(p["omega"], dtype=float)))
    if not speed >= MIN_RATE:
        return f"omega = {','.join(f'{float(x):.10g}' for x in p['omega'])} rad/s (|omega| = {speed:.3g} rad/s)"
    return None


MIN_RATE_DOMAIN_TEXT = (
    f"|omega| >= {MIN_RATE:g} rad/s: MuJoCo rotates the orientation by |omega| h about omega / |omega| and skips "
    "the rotation where |omega| < mjMINVAL = 1e-15 rad/s, so a slower body does not turn at all (an engine limit)"
)


def require_rigid_body_inertia(i1: float, i2: float, i3: float, names: str = "I1, I2, I3") -> None:
    """Refuse principal moments that no rigid body has: each must be at most the sum of the other two.

    Raises
    ------
    ValueError
        Naming the parameters and their values (MuJoCo would refuse the model too).
    """
    a, b, c = sorted((i1, i2, i3))
    if a + b < c:
        raise ValueError(
            f"parameters {names} = {i1:g}, {i2:g}, {i3:g} kg m^2 violate the triangle inequality "
            "(each principal moment <= the sum of the other two): no rigid body has these moments"
        )


@dataclass(frozen=True)
class RotorMotion:
    """Orientation and angular velocity of one body over time.

    Attributes
    ----------
    time : ndarray, shape (n,)
    quat_WB : ndarray, shape (n, 4)
        Body-to-world quaternion (w, x, y, z).
    omega_B : ndarray, shape (n, 3)
        Angular velocity in the body frame (rad/s): MuJoCo's qvel for free and ball joints.
    inertia_B : ndarray, shape (3,)
        Principal moments (kg m^2) about the point the body turns about (CM for a free body, pivot for a
        pivoted one), in body axes.
    """

    time: np.ndarray
    quat_WB: np.ndarray
    omega_B: np.ndarray
    inertia_B: np.ndarray

    @cached_property
    def R_WB(self) -> np.ndarray:
        return frames.quat_to_matrix(self.quat_WB)

    @cached_property
    def omega_W(self) -> np.ndarray:
        return frames.body_to_world(self.R_WB, self.omega_B)

    @cached_property
    def L_B(self) -> np.ndarray:
        """Angular momentum about the reference point, body frame (kg m^2/s)."""
        return self.inertia_B * self.omega_B

    @cached_property
    def L_W(self) -> np.ndarray:
        """Angular momentum about the reference point, world frame (kg m^2/s)."""
        return frames.body_to_world(self.R_WB, self.L_B)

    @cached_property
    def e3_W(self) -> np.ndarray:
        """Body axis 3 (the symmetry axis of a symmetric top) in the world frame."""
        return self.R_WB[..., :, 2]

    @cached_property
    def kinetic_energy(self) -> np.ndarray:
        """Rotational kinetic energy about the reference point (J)."""
        return 0.5 * np.sum(self.inertia_B * self.omega_B**2, axis=-1)


def free_body_motion(model: mujoco.MjModel, time: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> RotorMotion:
    """Motion of the single free body of `model` about its CM (qpos = [x, q], qvel = [v_W, omega_B])."""
    return RotorMotion(
        time=time, quat_WB=qpos[..., 3:7], omega_B=qvel[..., 3:6], inertia_B=model.body_inertia[1].copy()
    )


def set_free_body_rotation(data: mujoco.MjData, omega_B: np.ndarray) -> None:
    """Place the free body at the origin, unrotated, at rest except for body-frame angular velocity omega_B."""
    data.qpos[:] = [0, 0, 0, 1, 0, 0, 0]
    data.qvel[:] = [0, 0, 0, *omega_B]


class RotorEnv(ScenarioEnv):
    """Env plumbing for one rigid body turning about a point: observation [quaternion, body rates], action a
    world-frame torque on the body (N m), clipped to +-`max_torque`. Subclasses say what is compared with theory.

    Observation (float64, shape (7,))

    ==== ============================================ ============= ==========================
    idx  quantity                                     unit          MuJoCo source
    ==== ============================================ ============= ==========================
    0-3  body-to-world quaternion (w, x, y, z)        1             joint qpos
    4-6  angular velocity omega_B in body axes        rad/s         joint qvel (ball or free)
    ==== ============================================ ============= ==========================
    """

    max_torque: ClassVar[float] = 1.0
    body: ClassVar[str] = "top"

    def define_observation_space(self) -> gym.spaces.Box:
        high = np.full(7, np.inf)
        high[:4] = 1.0
        return gym.spaces.Box(-high, high, dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_torque, self.max_torque, shape=(3,), dtype=np.float64)

    def observe(self) -> np.ndarray:
        # MuJoCo renormalises joint quaternions every step, so qpos holds a unit quaternion already.
        return np.concatenate(self._obs_views)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        adr = int(self.model.jnt_qposadr[0]) + (3 if self.model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE else 0)
        self._quat = slice(adr, adr + 4)
        self._body_id = self.model.body(self.body).id
        self.start_views()

    def bind_views(self) -> None:
        """The quaternion, the body rates and the body's applied torque (`ScenarioEnv.bind_views`)."""
        data = self.data
        self._obs_views = (data.qpos[self._quat], data.qvel[-3:])
        self._torque = data.xfrc_applied[self._body_id, 3:6]

    def apply_action(self, action: np.ndarray) -> None:
        self._torque[:] = action

    def observe_batch(self, worlds) -> np.ndarray:
        return np.concatenate([worlds.qpos[:, self._quat], worlds.qvel[:, -3:]], axis=1)

    def apply_actions(self, actions: np.ndarray, worlds) -> None:
        worlds.xfrc_applied[:, self._body_id, 3:6] = actions


class FreeRotorEnv(RotorEnv):
    """A torque-free top's env: the theory is the body-frame omega(t) of the scenario's closed form.

    Reward: ``-|omega_B - omega_theory(t)| / |omega_theory(t)|``.
    """

    observables = ("omega1", "omega2", "omega3")

    def theory(self, t: np.ndarray) -> np.ndarray:
        return self.prediction["_theory"].omega_body(t)

    def measured(self, obs: np.ndarray) -> list[float]:
        return obs.tolist()[4:7]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        # |m - p| / |p| over three Python floats: cheaper per step than numpy's temporaries (same result to an ulp)
        (m1, m2, m3), (p1, p2, p3) = measured, predicted
        return math.sqrt(((m1 - p1) ** 2 + (m2 - p2) ** 2 + (m3 - p3) ** 2) / (p1 * p1 + p2 * p2 + p3 * p3))

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        return obs[:, 4:7]

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        (m1, m2, m3), (p1, p2, p3) = measured.T, predicted.T  # `deviation`'s operations in its order
        return np.sqrt(((m1 - p1) ** 2 + (m2 - p2) ** 2 + (m3 - p3) ** 2) / (p1 * p1 + p2 * p2 + p3 * p3))
