"""``rigidbench/PendulumEnergyTransfer-v0``: drive pendulum 1 so that the energy ends in pendulum 2 (docs/theory.md
O3-O4).

Built on the `CoupledPendulums` scenario (model, parameters, the ``beats`` case's initial state, the normal-mode
frequencies it predicts) and the pendulum env plumbing (observation, torque on pendulum 1).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from rigidbench import lazy
from rigidbench.envs import pendulums
from rigidbench.envs.coupled_pendulums import CoupledPendulums
from rigidbench.envs.pendulums import PendulumEnv
from rigidbench.envs.task import ClosedLoopTask

optimize = lazy.module("scipy.optimize")

# Episode lengths sampled, as fractions of the free beat's transfer time T_x = pi / (omega_a - omega_s) (O4).
DURATION_RANGE = (0.5, 1.0)
# Grid of directions phi searched for the bang-bang optimum (then refined): 0.5 degree.
PHASES = 720


def bang_bang_schedule(
    inertia_pivot: float,
    omega_s: float,
    omega_a: float,
    angles0: np.ndarray,
    rates0: np.ndarray,
    max_torque: float,
    hold: float,
    nsteps: int,
) -> tuple[np.ndarray, float]:
    """The torques on pendulum 1, one per hold interval, that maximise pendulum 2's energy at ``nsteps * hold``
    in the linearised model (docs/theory.md O3), and that energy (J).

    Linear model: normal coordinates q_s = (th1 + th2)/2, q_a = (th1 - th2)/2 obey I q_s'' = -I omega_s^2 q_s
    + u/2 and I q_a'' = -I omega_a^2 q_a + u/2 (O3), so th2 = q_s - q_a responds to a unit impulse on pendulum 1
    after s seconds with (sin(omega_s s)/omega_s - sin(omega_a s)/omega_a) / (2 I): the beat of O4. With
    z = omega_s th2 + i th2', pendulum 2's energy is I |z|^2 / 2, and z(T) = z_free + sum_k u_k g_k with g_k the
    response integrated over hold interval k (exact for a torque held constant over each interval). For a
    direction phi, Re(e^{-i phi} z(T)) is largest at u_k = max_torque sign(Re(e^{-i phi} g_k)); |z(T)| is the
    largest of those over phi (a convex objective is maximised at a vertex of the box: bang-bang, Pontryagin).
    So the schedule is the exact optimum of the linear, zero-order-hold problem.

    Parameters
    ----------
    inertia_pivot : float
        I_O of each pendulum (kg m^2).
    omega_s, omega_a : float
        In-phase and anti-phase frequencies (rad/s).
    angles0, rates0 : ndarray, shape (2,)
        Initial angles (rad) and rates (rad/s).
    max_torque : float
        Bound on |u| (N m).
    hold : float
        Control interval (s).
    nsteps : int
        Number of intervals; the energy is read at T = nsteps * hold.
    """
    T = nsteps * hold
    c = 1.0 / (2.0 * inertia_pivot)

    def integral(s: np.ndarray) -> np.ndarray:  # antiderivative of the impulse response z(s)
        real = c * (-np.cos(omega_s * s) / omega_s + omega_s * np.cos(omega_a * s) / omega_a**2)
        imag = c * (np.sin(omega_s * s) / omega_s - np.sin(omega_a * s) / omega_a)
        return real + 1j * imag

    start = hold * np.arange(nsteps)
    g = integral(T - start) - integral(T - start - hold)  # interval k covers s in [T - t_k - hold, T - t_k]
    qs0, qa0 = (angles0[0] + angles0[1]) / 2, (angles0[0] - angles0[1]) / 2
    vs0, va0 = (rates0[0] + rates0[1]) / 2, (rates0[0] - rates0[1]) / 2
    qs = qs0 * math.cos(omega_s * T) + vs0 / omega_s * math.sin(omega_s * T)
    qa = qa0 * math.cos(omega_a * T) + va0 / omega_a * math.sin(omega_a * T)
    vs = -qs0 * omega_s * math.sin(omega_s * T) + vs0 * math.cos(omega_s * T)
    va = -qa0 * omega_a * math.sin(omega_a * T) + va0 * math.cos(omega_a * T)
    z_free = omega_s * (qs - qa) + 1j * (vs - va)

    def value(phi: float | np.ndarray) -> np.ndarray:
        phi = np.atleast_1d(phi)[:, None]
        proj = np.cos(phi) * g.real + np.sin(phi) * g.imag
        return np.cos(phi[:, 0]) * z_free.real + np.sin(phi[:, 0]) * z_free.imag + max_torque * np.abs(proj).sum(1)

    phis = np.linspace(0.0, 2 * np.pi, PHASES, endpoint=False)
    best = phis[int(np.argmax(value(phis)))]
    step = 2 * np.pi / PHASES
    res = optimize.minimize_scalar(lambda p: -value(p)[0], bounds=(best - step, best + step), method="bounded")
    phi = float(res.x) if -res.fun >= value(best)[0] else float(best)
    proj = np.cos(phi) * g.real + np.sin(phi) * g.imag
    torques = np.where(proj >= 0, max_torque, -max_torque)
    z = z_free + torques @ g
    return torques, 0.5 * inertia_pivot * abs(z) ** 2


class PendulumEnergyTransferEnv(ClosedLoopTask, PendulumEnv):
    """``rigidbench/PendulumEnergyTransfer-v0``: a bounded torque on pendulum 1, for a time T, to leave as much
    energy as possible in pendulum 2.

    Description
        The coupled pendulums of ``rigidbench/CoupledPendulums-v0`` (``beats`` case: pendulum 1 released at
        1 mrad, pendulum 2 at rest). The agent applies a torque |u| <= 0.01 N m to pendulum 1 for T seconds,
        sampled per episode; what counts is pendulum 2's own energy at T, ``E2 = 1/2 I_O th2'^2 + m g l (1 -
        cos th2)`` (the spring's energy not included).

        Theory action (a baseline; the optimum of the linearised model): `bang_bang_schedule`, full torque with
        the sign of pendulum 2's beat response (O3-O4) to a blow on pendulum 1 at each instant, phased to
        arrive at T: it drives pendulum 1 at the normal-mode carrier, reversing with the beat. It is the exact
        optimum of the linear model with the torque held over each 19.6 ms step; MuJoCo's pendulums are
        nonlinear (sin th, the spring's geometry), at amplitudes <~ 0.03 rad here, relative O(th^2) ~ 1e-3.

    Observation Space
        Box(5,), float64: angles th1, th2 (rad), rates th1', th2' (rad/s) (`PendulumEnv`), and the time left
        until T (s).

    Action Space
        Box(-1, 1, (1,)), float32, normalised: ``action_scale = max_torque = 0.01`` N m times it is a torque on
        pendulum 1 about its hinge, through ``qfrc_applied``.

    Rewards
        ``reward = reward_energy``: 0 at every step but the last, then ``E2(T) / E2*`` with E2* the linear
        theory's optimum (so the baseline scores ~1). ``info["regret"]``: the baseline's reward at this step,
        simulated from the same initial state at reset (`ClosedLoopTask`), minus the agent's. A diverged
        episode scores 0 (the least E2 can be).

    Starting State
        The ``beats`` case: th1 = 1 mrad, th2 = 0, at rest. T ~ U(0.5, 1) T_x, T_x = pi / (omega_a - omega_s)
        the free transfer time (39.7 s at the defaults); ``reset(options={"target": {"duration": ...}})``
        fixes it.

    Episode End
        Terminated at T (a whole number of steps): T is the task's own end, where its whole reward is paid and
        the observation's time left reaches 0, so nothing follows it to bootstrap from (gymnasium's
        ``terminated``; ``truncated`` stays False). Also terminated on divergence (reward 0).

    Arguments
        ``params`` (CoupledPendulums': mass, length, k, d, amplitude1, amplitude2, g), ``regret``, ``profile``,
        ``integrator``, ``timestep``, ``frame_skip`` (default 10: ten
        derived steps, 19.6 ms at the defaults), ``render_mode``, ``width``,
        ``height``.

    Task Settings
        ``profile="task"`` (default) is the reference's (not swept yet, issue 36); the baseline's regret is 0 by
        construction (`ClosedLoopTask`). ``info["task_settings"]`` at reset.

    Version History
        v0: initial version.
    """

    env_id = "rigidbench/PendulumEnergyTransfer-v0"
    scenario_cls = CoupledPendulums
    task_case = "beats"
    target_names = ("duration",)
    reward_terms = ("energy",)
    horizon_ends_task = True  # the reward is E2 at T, and the observation counts down to it
    # Small enough that pendulum 2 stays below ~0.03 rad (linear to ~1e-3) over a transfer time.
    max_torque: ClassVar[float] = 0.01
    # Task settings (issue 36): the reference's, not swept yet; the baseline's regret is 0 by construction.
    task_record: ClassVar[dict[str, Any]] = {"theory_regret": 0.0, "swept": "not yet: the reference's settings"}

    def __init__(self, **kwargs: Any) -> None:
        self._task_duration = 1.0  # replaced by the sampled T at every reset
        super().__init__(**kwargs)

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(2 * self.model.nq + 1,), dtype=np.float64)

    def observe(self) -> np.ndarray:
        left = self._nsteps * self._env_dt - (self.data.time - self._time0)
        return np.concatenate((self.data.qpos, self.data.qvel, (left,)))

    def _target_ranges(self) -> dict[str, tuple[float, float]]:
        t_x = float(self.prediction["transfer-time"])
        return {"duration": (DURATION_RANGE[0] * t_x, DURATION_RANGE[1] * t_x)}

    def _start_episode(self) -> None:
        self._task_duration = self.target["duration"]
        self._nsteps = max(1, round(self._task_duration / self._env_dt))
        self.episode_duration = self._nsteps * self._env_dt
        self._pendulum2 = pendulums.pendulums(self.model)[1]
        # The schedule (and E2*, the reward's scale) is solved when first needed (the baseline's first action, or the
        # last step's reward), not at reset (issue 36: ~18 ms of a 720-phase search), from the state at reset.
        self._bang_bang = None
        self._start_state = (self.data.qpos.copy(), self.data.qvel.copy())

    @property
    def _schedule(self) -> np.ndarray:
        return self._solved()[0]

    @property
    def _optimum(self) -> float:
        return self._solved()[1]

    def _solved(self) -> tuple[np.ndarray, float]:
        """`bang_bang_schedule` for the episode (from its initial state), solved once per episode configuration."""
        if self._bang_bang is None:
            qpos, qvel = self._start_state
            key = (self._nsteps, self._env_dt, qpos.tobytes(), qvel.tobytes(), self.model)
            cache = self.__dict__.setdefault("_bang_bang_cache", {})
            if cache.get("key") is not None and cache["key"][:4] == key[:4] and cache["key"][4] is self.model:
                self._bang_bang = cache["value"]
            else:
                pend = pendulums.pendulums(self.model)
                self._bang_bang = bang_bang_schedule(
                    pend[0].inertia_pivot,
                    float(self.prediction["omega-in-phase"]),
                    float(self.prediction["omega-anti-phase"]),
                    qpos,
                    qvel,
                    self.max_torque,
                    self._env_dt,
                    self._nsteps,
                )
                cache["key"], cache["value"] = key, self._bang_bang
        return self._bang_bang

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_torque, self.max_torque, shape=(1,), dtype=np.float64)

    def energy2(self) -> float:
        """Pendulum 2's own energy (J): 1/2 I_O th2'^2 + m g l (1 - cos th2), 1 - cos written 2 sin^2(th/2)."""
        p, g = self._pendulum2, pendulums.gravity(self.model)
        th, rate = float(self.data.qpos[1]), float(self.data.qvel[1])
        return 0.5 * p.inertia_pivot * rate * rate + 2 * p.mass * g * p.length * math.sin(0.5 * th) ** 2

    def theory_action(self) -> np.ndarray:
        """The bang-bang baseline's action for the current step (open loop, from the schedule set at reset): its
        torque over `max_torque`, +-1 (0 past the schedule)."""
        k = self._k
        return self.normalised_action([self._schedule[k] if k < len(self._schedule) else 0.0])

    def _terms(self, action: np.ndarray) -> dict[str, float]:
        return {"energy": self.energy2() / self._optimum if self._k >= self._nsteps else 0.0}

    def _diverged_terms(self) -> dict[str, float]:
        return {"energy": 0.0}
