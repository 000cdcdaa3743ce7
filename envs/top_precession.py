"""``rigidbench/TopPrecession-v0``: torque a heavy top from rest tilt into steady precession (docs/theory.md T4).

Built on the `HeavyTop` scenario (model, parameters, initial state of its ``nutation`` case) and its rotor
env plumbing (observation, torque action); the target state is T4's slow steady precession.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import mujoco
import numpy as np

from rigidbench.analytic import tops
from rigidbench.envs.heavy_top import HeavyTop
from rigidbench.envs.rotor import RotorEnv
from rigidbench.envs.task import ClosedLoopTask

# Largest per-step penalty of each reward term (relative error): the rate error blows up near theta = 0 or pi
# (phi_dot = (omega_z - omega3 u) / (1 - u^2)), and a capped term keeps one bad step from swamping an episode.
ERROR_CAP = 10.0
# Tilts sampled per episode (rad): away from the upright, where phi is undefined, and from the horizontal.
TILT_RANGE = (0.3, 1.2)


class TopPrecessionEnv(ClosedLoopTask, RotorEnv):
    """``rigidbench/TopPrecession-v0``: bring a spinning heavy top, released at rest tilt, into steady precession.

    Description
        The heavy symmetric top of ``rigidbench/HeavyTop-v0`` (ball-joint pivot, gravity) starts at tilt theta0
        from the upward vertical, spinning at omega3 about its axis with theta_dot = phi_dot = 0. Left alone it
        nutates (cusped, docs/theory.md T2-T3). The task: apply a bounded torque so that it precesses steadily at
        theta0 at the slow T4 rate, the root of ``I1 cos(theta0) phi_dot^2 - I3 omega3 phi_dot + M g h = 0``
        (I1 about the pivot). Steady precession is a free motion: once reached, it needs no torque.

        Theory action (a baseline, not a proven optimum): steady precession at theta needs the transverse
        angular momentum ``L_perp* = I1 phi_dot* sin(theta) n``, with n the unit vector perpendicular to the
        axis e3 in the vertical plane through it (n = (z - cos(theta) e3) / sin(theta)); the top starts with
        L_perp = 0. The baseline applies ``tau = k_L (L_perp* + I1 k_theta (theta - theta0) (e3 x n) - L_perp)``,
        scaled down to the torque bound: a feed-forward angular-momentum change of I1 phi_dot* sin(theta0)
        about n delivered at the bound (~6 ms at the defaults, against a ~110 ms nutation period), feedback
        that damps the nutation (rate k_L), and a slow tilt correction (e3 moves at ``(L_perp x e3) / I1``,
        rate k_theta). The torque is perpendicular to e3, so the spin I3 omega3 is untouched.

    Observation Space
        Box(9,), float64:

        ==== ================================================ ======= ===========================
        idx  quantity                                         unit    source
        ==== ================================================ ======= ===========================
        0-3  body-to-world quaternion (w, x, y, z)            1       ball joint qpos
        4-6  angular velocity omega_B in body axes            rad/s   ball joint qvel
        7    target precession rate phi_dot* (T4 slow root)   rad/s   sampled target
        8    target tilt theta0 (the initial tilt)            rad     sampled target
        ==== ================================================ ======= ===========================

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = max_torque = 0.05`` N m times it is a torque on
        the top in world axes, through ``xfrc_applied``;
        out-of-range actions are clipped.

    Rewards
        Per step (1 ms), ``reward = reward_rate + reward_tilt`` with
        ``reward_rate = -min(|phi_dot - phi_dot*| / |phi_dot*|, 10)`` and
        ``reward_tilt = -min(|theta - theta0| / theta0, 10)``, phi_dot = (omega_z - omega3 cos theta) /
        sin^2 theta from the state. ``info["regret"]``: the baseline's reward at this step (simulated from the
        same initial state at reset, `ClosedLoopTask`) minus the agent's. A diverged step scores -20 for each
        remaining step.

    Starting State
        theta0 ~ U(0.3, 1.2) rad (``reset(options={"target": {"tilt": ...}})`` fixes it), phi = psi = 0, body
        rates (0, 0, spin); spin, mass, arm, I1, I3 and g from the scenario's parameters.

    Episode End
        Truncated after ``duration`` (default 1 s, ~0.7 precession turns at the defaults); terminated on
        divergence.

    Arguments
        ``duration`` (s), ``params`` (HeavyTop's: mass, arm, I1, I3, spin, g), ``regret``, ``profile``,
        ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 1 ms), ``render_mode``, ``width``,
        ``height``.

    Task Settings
        ``profile="task"`` (default) is the reference's (not swept yet, issue 36); the baseline's regret is 0 by
        construction (`ClosedLoopTask`). ``info["task_settings"]`` at reset.

    Version History
        v0: initial version.
    """

    env_id = "rigidbench/TopPrecession-v0"
    scenario_cls = HeavyTop
    task_case = "nutation"
    target_names = ("tilt", "precession")
    reward_terms = ("rate", "tilt")
    max_torque: ClassVar[float] = 0.05
    # Baseline gains (1/s): the momentum loop must be slower than the 1 ms control period (5 ms time constant)
    # and faster than the nutation (~56 rad/s at the defaults) it damps; the tilt loop slower again.
    gain_momentum: ClassVar[float] = 200.0
    gain_tilt: ClassVar[float] = 20.0
    # Task settings (issue 36): the reference's, not swept yet; the baseline's regret is 0 by construction.
    task_record: ClassVar[dict[str, Any]] = {"theory_regret": 0.0, "swept": "not yet: the reference's settings"}

    def __init__(self, *, duration: float = 1.0, **kwargs) -> None:
        if not (math.isfinite(duration) and 0 < duration <= 60):
            raise ValueError(f"duration = {duration!r} s is outside the valid range (0, 60] s")
        self._task_duration = float(duration)
        super().__init__(**kwargs)

    def define_observation_space(self):
        space = super().define_observation_space()
        high = np.concatenate((space.high, [np.inf, np.pi]))
        low = np.concatenate((space.low, [-np.inf, 0.0]))
        return type(space)(low, high, dtype=np.float64)

    def observe(self) -> np.ndarray:
        # RotorEnv's views of the quaternion and body rates (issue 8: slicing afresh costs ~0.2 us each), then the
        # target; one array, filled in place.
        quat, omega_B = self._obs_views
        target = self.target
        obs = np.empty(9)
        obs[:4] = quat
        obs[4:7] = omega_B
        obs[7] = target["precession"]
        obs[8] = target["tilt"]
        return obs

    def load(self, case: str, params) -> None:
        super().load(case, params)
        motion = self.scenario.motion(self.model, np.zeros(1), self.data.qpos[None], self.data.qvel[None])
        self._inertia = motion.inertia_B  # about the pivot (docs/theory.md R4)
        self._mgh = self.scenario._mgh(self.model)
        self._R = np.empty((3, 3))
        self._R9 = self._R.reshape(9)  # a view: what mju_quat2Mat fills

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__(state)
        if "_R" in state:  # a copy holds `_R` and `_R9` as arrays of their own: make `_R9` its view again
            self._R9 = self._R.reshape(9)

    def _target_ranges(self) -> dict[str, tuple[float, float]]:
        return {"tilt": TILT_RANGE}

    def _complete_target(self, target: dict[str, float]) -> dict[str, float]:
        i1, _, i3 = self._inertia
        spin = float(self.params["spin"])
        try:
            slow, _fast = tops.steady_precession_rates(i1, i3, self._mgh, spin, target["tilt"])
        except ValueError as exc:
            tilt = target["tilt"]
            raise ValueError(f"no steady precession at tilt {tilt:g} rad with these parameters: {exc}") from None
        return {"tilt": target["tilt"], "precession": float(slow)}

    def _start_episode(self) -> None:
        start = {**self.params, "tilt": self.target["tilt"], "precession": 0.0, "nutation_rate": 0.0}
        self.scenario.initial_state(self.model, self.data, start)
        mujoco.mj_forward(self.model, self.data)

    def _state(self) -> dict[str, Any]:
        """Axis e3, angular momentum about the pivot (world), tilt theta and precession rate phi_dot."""
        R = self._R
        mujoco.mju_quat2Mat(R.reshape(9), self.data.qpos[self._quat])  # same as frames.quat_to_matrix, in C
        omega_B = self.data.qvel[-3:]
        e3 = R[:, 2]
        u = float(e3[2])
        omega_W = R @ omega_B
        sin2 = max(1.0 - u * u, 1e-300)
        return {
            "e3_W": e3,
            "L_W": R @ (self._inertia * omega_B),
            "theta": math.atan2(math.hypot(e3[0], e3[1]), u),
            "phi_dot": float((omega_W[2] - omega_B[2] * u) / sin2),
        }

    def _tilt_and_rate(self) -> tuple[float, float]:
        """`_state`'s theta and phi_dot alone, as Python floats (every step scores them: issue 8): the same
        operations on the same values, so the same bits, without L_W and e3 that only the baseline needs."""
        quat, omega_B = self._obs_views
        R = self._R
        mujoco.mju_quat2Mat(self._R9, quat)
        e3_x, e3_y, e3_z = self._R9.tolist()[2::3]  # column 2 of R: the axis e3
        omega_W_z = (R @ omega_B).tolist()[2]  # numpy's matmul, not three products: BLAS may round otherwise
        sin2 = max(1.0 - e3_z * e3_z, 1e-300)
        return math.atan2(math.hypot(e3_x, e3_y), e3_z), (omega_W_z - omega_B.tolist()[2] * e3_z) / sin2

    def _terms(self, action: np.ndarray) -> dict[str, float]:
        theta, phi_dot = self._tilt_and_rate()
        target = self.target
        rate = abs(phi_dot - target["precession"]) / abs(target["precession"])
        tilt = abs(theta - target["tilt"]) / target["tilt"]
        return {"rate": -min(rate, ERROR_CAP), "tilt": -min(tilt, ERROR_CAP)}

    def _diverged_terms(self) -> dict[str, float]:
        remaining = self._nsteps - self._k + 1
        return {name: -ERROR_CAP * remaining for name in self.reward_terms}

    def theory_action(self) -> np.ndarray:
        """The baseline's action for the current state: its torque (N m, world axes; see the class docstring) over
        `max_torque`, in [-1, 1] (float64, `normalised_action`)."""
        s = self._state()
        e3, L, theta = s["e3_W"], s["L_W"], s["theta"]
        sin_t = max(math.sin(theta), 1e-9)
        n = (np.array([0.0, 0.0, 1.0]) - math.cos(theta) * e3) / sin_t
        i1 = self._inertia[0]
        L_perp = L - (L @ e3) * e3
        L_target = i1 * self.target["precession"] * sin_t * n
        h = np.array([e3[1] * n[2] - e3[2] * n[1], e3[2] * n[0] - e3[0] * n[2], e3[0] * n[1] - e3[1] * n[0]])
        L_target += i1 * self.gain_tilt * (theta - self.target["tilt"]) * h  # h = e3 x n, horizontal
        torque = self.gain_momentum * (L_target - L_perp)
        torque /= max(1.0, float(np.abs(torque).max()) / self.max_torque)  # keeps its direction
        return np.clip(self.normalised_action(torque), -1.0, 1.0)  # rounding of the divisions
