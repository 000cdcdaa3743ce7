"""The physics layer shared by the percussion scenarios: free bodies moving in a plane, and blows.

Turns MuJoCo's free-joint state rows into named planar quantities (house rule 6): the body turns only about
world z, so its heading is the angle of body y from world y and omega_z is both the body- and world-frame
component. `PlanarMotion` works on whole trajectories (vectorised over time) or single states; an env step reads
its one state in Python floats instead (`heading`, `dot` on the rows of `frames.matrix_rows`: the same arithmetic,
without arrays). `BlowEnv` is the env plumbing for scenarios whose episode starts with a blow: the scenario's pulse
(`Scenario.control`) is delivered during ``reset`` (the `ScenarioEnv.begin_episode` hook), so an episode starts just
after the blow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import frames, pulse
from rigidbench.contract import MAX_ACCELERATION, Derived, Trajectory, round_step
from rigidbench.envs.base import ScenarioEnv


@dataclass(frozen=True)
class PlanarMotion:
    """One free body's motion, from its free-joint qpos [x, y, z, qw, qx, qy, qz] and qvel [v_W, omega_B].

    Attributes
    ----------
    time : ndarray, shape (n,)
    qpos : ndarray, shape (n, 7)
    qvel : ndarray, shape (n, 6)
    """

    time: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray

    @cached_property
    def R_WB(self) -> np.ndarray:
        return frames.quat_to_matrix(self.qpos[..., 3:7])

    @property
    def com_W(self) -> np.ndarray:
        """Position of the body origin (its CM in these models), world frame (m), shape (n, 3)."""
        return self.qpos[..., 0:3]

    @property
    def v_W(self) -> np.ndarray:
        """Velocity of the body origin, world frame (m/s), shape (n, 3)."""
        return self.qvel[..., 0:3]

    @cached_property
    def omega_W(self) -> np.ndarray:
        """Angular velocity, world frame (rad/s), shape (n, 3)."""
        return frames.body_to_world(self.R_WB, self.qvel[..., 3:6])

    @cached_property
    def heading(self) -> np.ndarray:
        """Angle (rad) of body y from world y, counter-clockwise about world z (unwrapped over time)."""
        axis = self.R_WB[..., :, 1]
        heading = np.arctan2(-axis[..., 0], axis[..., 1])
        # One sample (an env step) has nothing to unwrap, and np.unwrap costs more than the rest of a step.
        return heading if len(heading) == 1 else np.unwrap(heading, axis=0)

    def point_W(self, p_B: np.ndarray) -> np.ndarray:
        """World position (m) of the body point with body-frame coordinates `p_B`, shape (n, 3)."""
        return self.com_W + frames.body_to_world(self.R_WB, np.broadcast_to(p_B, self.com_W.shape))

    def point_velocity_W(self, p_B: np.ndarray) -> np.ndarray:
        """World velocity (m/s) of the body point `p_B` (body frame), shape (n, 3)."""
        r_W = frames.body_to_world(self.R_WB, np.broadcast_to(p_B, self.com_W.shape))
        return self.v_W + np.cross(self.omega_W, r_W)

    def point_acceleration_W(self, p_B: np.ndarray) -> np.ndarray:
        """World acceleration (m/s^2) of the body point `p_B` of a body moving freely (no force, no torque):
        the centripetal omega x (omega x r); exact between blows."""
        r_W = frames.body_to_world(self.R_WB, np.broadcast_to(p_B, self.com_W.shape))
        return np.cross(self.omega_W, np.cross(self.omega_W, r_W))


def free_body_motion(model: mujoco.MjModel, traj: Trajectory, body: str) -> PlanarMotion:
    """The planar motion of the free `body` of `model` over a trajectory."""
    jnt = model.body(body).jntadr[0]
    qa, va = model.jnt_qposadr[jnt], model.jnt_dofadr[jnt]
    return PlanarMotion(time=traj.time, qpos=traj.qpos[:, qa : qa + 7], qvel=traj.qvel[:, va : va + 6])


def body_state(model: mujoco.MjModel, data: mujoco.MjData, body: str) -> PlanarMotion:
    """The planar state of the free `body` now (arrays of length 1)."""
    jnt = model.body(body).jntadr[0]
    qa, va = model.jnt_qposadr[jnt], model.jnt_dofadr[jnt]
    return PlanarMotion(
        time=np.array([data.time]), qpos=data.qpos[None, qa : qa + 7].copy(), qvel=data.qvel[None, va : va + 6].copy()
    )


class BlowEnv(ScenarioEnv):
    """Env plumbing for one body struck at the start of the episode.

    ``reset`` delivers the scenario's blow (its `Scenario.control` pulse, in `begin_episode`) before returning, so the
    first observation is the state just after the blow; the action is then a small extra planar force and torque on
    `body` (world frame, through ``xfrc_applied``): (f_x N, f_y N, tau_z N m), clipped to +-`max_force`.
    Zero action is the textbook problem. Observation (float64, shape (6,)):

    ==== =============================================== ======= ============================
    idx  quantity                                        unit    MuJoCo source
    ==== =============================================== ======= ============================
    0-1  position of the body's CM (x, y), world         m       free joint qpos[0:2]
    2    heading: angle of body y from world y, about z  rad     free joint quaternion
    3-4  CM velocity (v_x, v_y), world                   m/s     free joint qvel[0:2]
    5    angular velocity omega_z                        rad/s   free joint qvel[5]
    ==== =============================================== ======= ============================
    """

    body: ClassVar[str]
    max_force: ClassVar[float] = 0.1

    def begin_episode(self) -> None:
        if self.model.nu:  # a model with an actuator is struck by a pulse (rigidbench.pulse)
            for row in self.scenario.control(self.model, self.model.opt.timestep, pulse.steps(self.model)):
                self.data.ctrl[:] = row
                mujoco.mj_step(self.model, self.data)
            self.data.ctrl[:] = 0.0

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(6,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_force, self.max_force, shape=(3,), dtype=np.float64)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        # Read or written every step (issue 8): the body's free-joint addresses and id, cached here (a look-up by
        # name costs ~0.4 us), and views into `self.data` (`bind_views`).
        body = self.model.body(self.body)
        joint = body.jntadr[0]
        qpos, dof = int(self.model.jnt_qposadr[joint]), int(self.model.jnt_dofadr[joint])
        self._free_qpos, self._free_qvel = slice(qpos, qpos + 7), slice(dof, dof + 6)
        self._body_id = body.id
        self._length = self._actual.get("length")  # a stick's full length L (m), the scale of `_pose_deviation`
        self.start_views()

    def bind_views(self) -> None:
        """The free joint's qpos and qvel and the body's xfrc_applied row (`ScenarioEnv.bind_views`)."""
        data = self.data
        self._qpos, self._qvel = data.qpos[self._free_qpos], data.qvel[self._free_qvel]
        self._xfrc = data.xfrc_applied[self._body_id]

    def _free_joint(self) -> tuple[list[float], list[float]]:
        """The body's free-joint qpos [x, y, z, qw, qx, qy, qz] and qvel [v_W, omega_B] now, as Python floats."""
        return self._qpos.tolist(), self._qvel.tolist()

    def observe(self) -> np.ndarray:
        # PlanarMotion's heading and omega_W for one state, in Python floats: ~7x cheaper than its arrays. Plain
        # unpacking (no starred names, no slices): ~0.3 us a step less.
        (x, y, _, q_w, q_x, q_y, q_z), (v_x, v_y, _, w_x, w_y, w_z) = self._free_joint()
        R = frames.matrix_rows(q_w, q_x, q_y, q_z)
        return np.array([x, y, heading(R), v_x, v_y, dot(R[2], (w_x, w_y, w_z))])

    def apply_action(self, action: np.ndarray) -> None:
        self._xfrc[:] = self._wrench(action.tolist())

    def observe_batch(self, worlds) -> np.ndarray:
        # `observe` on arrays over the copies: the same operations in the same order (heading's atan2 per copy)
        (x, y, _, q_w, q_x, q_y, q_z), (v_x, v_y, _, w_x, w_y, w_z) = self._free_joints(worlds)
        R = frames.matrix_rows(q_w, q_x, q_y, q_z, sqrt=np.sqrt)
        return np.stack([x, y, headings(R), v_x, v_y, dot(R[2], (w_x, w_y, w_z))], axis=1)

    def _free_joints(self, worlds) -> tuple[np.ndarray, np.ndarray]:
        """The body's free-joint qpos and qvel components, each an array over the copies (`_free_joint`)."""
        return worlds.qpos[:, self._free_qpos].T, worlds.qvel[:, self._free_qvel].T

    def apply_actions(self, actions: np.ndarray, worlds) -> None:
        xfrc = worlds.xfrc_applied[:, self._body_id]
        for j, column in enumerate(self._wrench(list(actions.T))):  # columns of copies, or 0.0
            xfrc[:, j] = column

    def _wrench(self, action: list[float]) -> tuple[float, ...]:
        """The body's ``xfrc_applied`` row (force, then torque; world frame) for an action (already clipped)."""
        f_x, f_y, tau_z = action
        return f_x, f_y, 0.0, 0.0, 0.0, tau_z

    def _stick_pose_theory(self, t: np.ndarray) -> np.ndarray:
        """(x, y, heading) of a stick struck by the scenario's blow, free afterwards (P1): CM at V t', heading
        omega t', with t' = t - tau/2 from the pulse's centroid; shape (len(t), 3)."""
        theory = self.prediction["_theory"]
        tp = np.asarray(t) - 0.5 * self.prediction["_tau"]
        return np.stack([theory.com_velocity * tp, np.zeros_like(tp), theory.angular_velocity * tp], axis=1)

    def _pose_deviation(self, measured: list[float], predicted: list[float]) -> float:
        """(|dx| + |dy|) / L + |d heading| / pi (heading difference wrapped to [-pi, pi)); 0 where the theory
        is NaN (not scored). `measured` and `predicted` are (x, y, heading) in Python floats."""
        if has_nan(predicted):
            return 0.0
        (x, y, h), (x_p, y_p, h_p) = measured, predicted
        return (abs(x - x_p) + abs(y - y_p)) / self._length + abs(wrap_angle(h - h_p)) / math.pi

    def _pose_deviations(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        """`_pose_deviation` of every copy, from (nworld, 3) arrays."""
        (x, y, h), (x_p, y_p, h_p) = measured.T, predicted.T
        deviation = (np.abs(x - x_p) + np.abs(y - y_p)) / self._length + np.abs(wrap_angle(h - h_p)) / math.pi
        return np.where(np.isnan(predicted).any(axis=1), 0.0, deviation)


def heading(R_WB) -> float:
    """Angle (rad) of body y from world y, counter-clockwise about world z, from the rows of R_WB (one state)."""
    return math.atan2(-R_WB[0][1], R_WB[1][1])


def headings(R_WB) -> np.ndarray:
    """`heading` of each copy, from rows of arrays over the copies (`math.atan2` per copy: numpy's SIMD arctan2 may
    round the last bit otherwise)."""
    return np.array(list(map(math.atan2, (-R_WB[0][1]).tolist(), R_WB[1][1].tolist())))


def dot(a, b) -> float:
    """a . b of two 3-vectors of Python floats (a row of R_WB and a body-frame vector: one world component)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def wrap_angle(angle):
    """`angle` (rad; a float or an array) wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def has_nan(values) -> bool:
    """Whether a theory row (Python floats) holds a NaN: a step the theory does not score."""
    for v in values:
        if v != v:
            return True
    return False


def require_strike_on_stick(offset: float, length: float) -> None:
    """Refuse a blow `offset` (m, from the centre) beyond the end of a stick of full `length` (m).

    Raises
    ------
    ValueError
        Naming the parameter, its value and the valid range.
    """
    if offset > length / 2:
        raise ValueError(
            f"parameter 'offset' = {offset:g} m is outside the valid range (0, {length / 2:g}] m (half the stick's "
            f"length = {length:g} m): the blow must hit the stick"
        )


# ---- settings that follow the parameters (issue 13): the blow's pulse, the step, MuJoCo's acceleration limit ----

# omega tau of the fastest default case of the free-stick scenarios (struck at the end: |omega| = 24 rad/s, tau =
# 0.1 ms). A reference pulse keeps this omega tau whatever the parameters (rounded down to one digit: 1.2e-3 ..
# 2.4e-3), so the pulse's errors, O((omega tau)^2) <= 1.4e-7 relative, and the run's step count stay those of the
# default cases.
OMEGA_TAU = 2.4e-3
# Steps per pulse: the reference timestep is tau / 5 (the model files' 20 us for 0.1 ms), so free rotation after
# the blow steps omega dt <= 4.8e-4 (RK4's phase error ~ omega T (omega dt)^4 ~ 1e-12).
STEPS_PER_PULSE = 5


def reference_pulse(omega: float, what: str, omega_tau: float = OMEGA_TAU) -> dict[str, Any]:
    """The reference pulse duration and timestep for a blow that leaves the body turning at `omega` (rad/s):
    ``tau = omega_tau / |omega|`` rounded down to one digit, ``dt = tau / STEPS_PER_PULSE``. `what` says how omega
    follows from the parameters (for the rules)."""
    tau = round_step(omega_tau / abs(omega))
    return {
        "pulse_duration": Derived(
            tau,
            f"tau = {omega_tau:g} / |omega| rounded down to one digit (omega tau = {abs(omega) * tau:.3g}: the finite "
            f"pulse's errors O((omega tau)^2) stay those of the default cases); |omega| = {what} = {abs(omega):.6g} "
            "rad/s",
        ),
        "timestep": Derived(
            tau / STEPS_PER_PULSE,
            f"dt = tau / {STEPS_PER_PULSE} (whole steps per pulse; free rotation then omega dt = "
            f"{abs(omega) * tau / STEPS_PER_PULSE:.3g}: RK4 phase error ~1e-12 over the run)",
        ),
    }


def max_impulse(omega_per_impulse: float, speed_per_impulse: float, omega_tau: float = OMEGA_TAU) -> float:
    """Largest impulse (N s) whose reference pulse keeps MuJoCo's accelerations below `MAX_ACCELERATION`: the
    pulse lasts at least omega_tau / 2 / |omega| (one-digit rounding), so it accelerates by up to |omega|^2 /
    (omega_tau / 2) (rad/s^2) and |omega| V / (omega_tau / 2) (m/s^2); omega and V are proportional to the impulse,
    at `omega_per_impulse` (rad/s per N s) and `speed_per_impulse` (m/s per N s, the fastest point of the body)."""
    half = omega_tau / 2
    by_turn = np.sqrt(MAX_ACCELERATION * half) / omega_per_impulse
    by_speed = np.sqrt(MAX_ACCELERATION * half / (omega_per_impulse * speed_per_impulse))
    return float(min(by_turn, by_speed))


def similar_step(timestep: float, scale: float) -> float:
    """A model file's reference `timestep` (s) at `scale` times its default time scale, rounded down to one digit
    (calibrated a hair above, so the default case keeps the file's step exactly)."""
    return round_step(timestep * scale * (1 + 1e-9))


def similar_settings(
    scale: float, why: str, *, stiffness: float, timestep: float, pulse_steps: int, pulse_default: str
) -> dict[str, Derived]:
    """Contact stiffness, timestep and pulse for a case `scale` times slower than its model file's default (`why`
    says which time scale, with its numbers): k (T / T_0)^2, dt / T and tau / T are the default's, so MuJoCo solves the
    default case's contact problem in units of T (issue 13: cue-strike, cushion-rebound, marble-shot)."""
    k = stiffness / scale**2
    dt = similar_step(timestep, scale)
    return {
        "contact_stiffness": Derived(
            k,
            f"k = {stiffness:g} (T_0 / T)^2 = {k:.6g} 1/s^2 ({why}): the contact's time constant keeps its share of T "
            f"({1 / math.sqrt(k) / dt:.3g} steps), so MuJoCo's soft contact solves the default case's problem in "
            "units of T",
        ),
        "timestep": Derived(dt, f"dt = {timestep:g} s x T / T_0 rounded down to one digit ({why})"),
        "pulse_duration": Derived(
            pulse_steps * dt, f"tau = {pulse_steps} dt ({pulse_default} at the default): the blow keeps its share of T"
        ),
    }
