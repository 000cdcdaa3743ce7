"""``rigidbench/CueShot-v0``: strike the cue ball to roll at a target speed with the least skid (docs/theory.md B1-B2).

Built on the `CueStrike` scenario: its model (ball on cloth, cue pulse on a line at ``height``), its initial state
(the ball settled on the cloth), its closed forms (`rigidbench.analytic.percussion.cue_strike`) and its
measurement of the final speed and the initial slip.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from rigidbench.analytic import percussion
from rigidbench.envs.cue_strike import CueStrike
from rigidbench.envs.planar import free_body_motion
from rigidbench.envs.task import ShotTask

# Largest penalty of each reward term (relative to the target speed): a shot that diverges scores this on both.
ERROR_CAP = 10.0
# The ball counts as rolling once the contact's slip stays below this fraction of the target speed (the soft
# cloth contact holds a rolling ball's slip to ~1e-6 m/s; a no-skid blow leaves ~3e-7 m/s).
SLIP_TOLERANCE = 1e-3


class CueShotEnv(ShotTask):
    """``rigidbench/CueShot-v0``: one cue strike per episode, to reach a target rolling speed without skidding.

    Description
        A solid ball (radius R, mass M) rests on cloth with Coulomb friction ``mu``. The agent chooses where and
        how hard to strike it: the height h of the cue's line above the centre and the speed v0 the blow gives
        (impulse M v0, a 1 ms pulse). The ball then skids and rolls (docs/theory.md B1-B2): slip
        u0 = v0 (1 - h/(gamma R)), rolling speed v_f = v0 (1 + h/R) / (1 + gamma) (gamma = 2/5). The task: roll
        at the target speed v* with the least skid.

        Theory action (the optimum): reward <= 0, and 0 only if u0 = 0 and v_f = v*: B1 gives u0 = 0 only at the
        no-skid height h = gamma R = 2R/5, and then v_f = v0, so the unique optimum is (h, v0) = (2R/5, v*).

    Observation Space
        Box(1,), float64: the target rolling speed v* (m/s).

    Action Space
        Box(-1, 1, (2,)), float32, normalised:

        ==== ============================================================ ======================
        idx  quantity                                                     physical range
        ==== ============================================================ ======================
        0    height h of the cue's line above the centre, h = 0.8 a0 R     [-0.8 R, 0.8 R]
        1    speed v0 given by the blow, v0 = lo + (a1 + 1)/2 (hi - lo)   [0.25, 2] m/s
        ==== ============================================================ ======================

    Rewards
        ``reward = reward_speed + reward_skid``: ``reward_speed = -|v_f - v*| / v*`` with v_f the ball's speed at
        the end of the run (1.5 predicted rolling times, at least 50 ms); ``reward_skid = -t_s / t_ref`` with
        t_s the skid time, from the blow until the contact's slip last exceeds 1e-3 v*, and t_ref = v* / ((1 +
        1/gamma) mu g) = 2 v* / (7 mu g), the time friction takes to remove a slip of v* (B2), so that under B2
        the term is -|u0| / v*. Each term is capped at -10. ``info["regret"]``: the closed-form
        reward of the theory action (0) minus this reward (`ShotTask`).

    Starting State
        The ball at rest on the cloth (settled at its contact's resting penetration); v* ~ U(0.5, 2) m/s
        (``reset(options={"target": {"speed": ...}})`` fixes it).

    Episode End
        Terminated after the one step (the whole shot is simulated in it).

    Arguments
        ``params`` (CueStrike's: radius, mass, mu, g; default mu = 0.5), ``timestep`` (default 5e-5 s),
        ``regret``, ``profile``, ``integrator``, ``render_mode``, ``width``, ``height``.

    Task Settings
        ``profile="task"`` (default) is the reference's 50 us step: no cheaper integrator or step keeps the
        reward within 1e-4 of it (100 us moves it by 1.3e-3 or more). The theory action's regret: 4.9e-8.
        ``info["task_settings"]`` at reset.

    Version History
        v0: initial version.
    """

    env_id = "rigidbench/CueShot-v0"
    scenario_cls = CueStrike
    # The no-skid case: its checks are those of a blow at any height (the skid ones need a sliding phase, which
    # the agent's strike near 2R/5 may not leave: cue-strike's skid domain), and its theory action is the task's.
    task_case = "no-skid"
    target_names = ("speed",)
    reward_terms = ("speed", "skid")
    # Action ranges: |h| <= 0.8 R (the cue must hit the ball well inside its rim); v0 in [0.25, 2] m/s, inside
    # cue-strike's speed range at mu = 0.5 (its slip |u0| <= 9 sqrt(g R), where MuJoCo's soft cone hops the ball
    # < 1e-3 R, admits 2.12 m/s on the default ball) and enough for every target (the no-skid shot has v0 = v*).
    max_height: ClassVar[float] = 0.8
    speed_range: ClassVar[tuple[float, float]] = (0.25, 2.0)
    target_range: ClassVar[tuple[float, float]] = (0.5, 2.0)

    # mu = 0.5 (a grippier cloth than the scenario's 0.2) and a 50 us step keep a skidding shot under ~0.2 s of
    # compute: measured against 10 us, the final speed moves by <= 1e-5 relative and the no-skid shot's slip stays
    # 3.4e-7 m/s. The reference profile's step.
    reference_timestep = 5e-5
    # Task settings (issue 36): the reference's own. Swept (benchmarks/task_speed.py --sweep), every cheaper setting
    # moves the reward by more than the bound of 1e-4 (1e-2 of a reward read to 1e-2 of the target speed): 100 us
    # by 3.5e-3 (Euler, implicitfast) and 1.3e-3 (RK4), and 400 us and longer are refused (the cloth contact would
    # last under 4 steps). The theory action's regret there: 4.9e-8.
    task_record: ClassVar[dict[str, Any]] = {
        "reward_error": 0.0,
        "error_bound": 1e-4,
        "theory_regret": 4.9e-8,
        "swept": "Euler, RK4, implicitfast at 2-40x the reference step: none below the bound",
    }

    def __init__(self, *, params: Mapping[str, Any] | None = None, **kwargs: Any) -> None:
        super().__init__(params={"mu": 0.5, **dict(params or {})}, **kwargs)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float64)

    def _target_ranges(self) -> dict[str, tuple[float, float]]:
        return {"speed": self.target_range}

    def _gamma(self) -> float:
        p = self.params
        return float(self.model.body("ball").inertia[1] / (p["mass"] * p["radius"] ** 2))

    def _physical(self, action: np.ndarray) -> tuple[float, float]:
        lo, hi = self.speed_range
        return float(action[0]) * self.max_height * self.params["radius"], lo + (float(action[1]) + 1) / 2 * (hi - lo)

    def theory_action(self) -> np.ndarray:
        """(2R/5, v*) normalised: B1's no-skid height, where v_f = v0 (B2)."""
        radius, gamma = self.params["radius"], self._gamma()
        height = percussion.no_skid_height(radius, gamma)
        speed = self.target["speed"] * (1 + gamma) / (1 + height / radius)  # v_f = v0 (1 + h/R) / (1 + gamma)
        lo, hi = self.speed_range
        return np.array([height / (self.max_height * radius), 2 * (speed - lo) / (hi - lo) - 1])

    def _theory_reward(self) -> float:
        p, target = self.params, self.target["speed"]
        height, speed = self._physical(self.theory_action())
        shot = percussion.cue_strike(p["radius"], p["mu"], p["g"], speed, height, self._gamma())
        return -abs(shot.final_speed - target) / target - shot.time_to_roll / self._skid_scale()

    def _skid_scale(self) -> float:
        """t_ref = v* / ((1 + 1/gamma) mu g) (s): how long friction takes to remove a slip of v* (B2)."""
        p = self.params
        return self.target["speed"] / ((1 + 1 / self._gamma()) * p["mu"] * p["g"])

    def _shot(self, action: np.ndarray) -> tuple[dict[str, float], dict[str, Any]]:
        height, speed = self._physical(action)
        measured = self._run_scenario({"height": height, "speed": speed}, self._measure_shot)
        if measured is None or not all(np.isfinite(v) for v in measured.values()):
            return {}, {"diverged": True}
        target = self.target["speed"]
        terms = {
            "speed": -min(abs(measured["final-speed"] - target) / target, ERROR_CAP),
            "skid": -min(measured["skid-time"] / self._skid_scale(), ERROR_CAP),
        }
        outcome = {
            "height": height,
            "strike_speed": speed,
            "final_speed": measured["final-speed"],
            "skid_time": measured["skid-time"],
            "predicted_final_speed": float(self.prediction["final-speed"]),
            "predicted_skid_time": float(self.prediction["_theory"].time_to_roll),
        }
        return terms, outcome

    def _measure_shot(self, model, traj, prediction) -> dict[str, float]:
        """Final speed (the scenario's measure: the CoM speed at the end of the run) and the skid time: when the
        contact's slip (`CueStrike.slip`) last exceeds `SLIP_TOLERANCE` v*, counted from the start of the blow
        (the scenario's convention, docs/theory.md B2), 0 if it never does."""
        motion = free_body_motion(model, traj, "ball")
        slip = np.abs(CueStrike.slip(model, motion))
        t = motion.time
        sliding = np.flatnonzero(slip > SLIP_TOLERANCE * self.target["speed"])
        if len(sliding) == 0:
            skid = 0.0
        elif sliding[-1] == len(t) - 1:
            skid = float(t[-1])  # still sliding at the end of the run (not at the run lengths used here)
        else:
            i = int(sliding[-1])  # the slip falls through the tolerance between samples i and i + 1
            level = SLIP_TOLERANCE * self.target["speed"]
            skid = float(t[i] + (t[i + 1] - t[i]) * (slip[i] - level) / (slip[i] - slip[i + 1]))
        return {"final-speed": float(motion.v_W[-1, 0]), "skid-time": skid}

    def _diverged_terms(self) -> dict[str, float]:
        return {name: -ERROR_CAP for name in self.reward_terms}
