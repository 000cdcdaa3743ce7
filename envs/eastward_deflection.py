"""Eastward deflection of a body dropped on a turning platform: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md N3 (a body dropped from rest through h lands ``(1/3) Omega g t0^3 cos(lambda)`` East of the
point below its release, t0 = sqrt(2h/g)), and N1 integrated exactly for a field fixed in the turning frame
(`rigidbench.analytic.rotating.drop_path`: every order in Omega), implemented in `rigidbench.analytic.rotating`.
Model: ``models/eastward_deflection.xml`` (a free ball released on the axis of a platform turning at a constant
rate, gravity fixed in the platform's axes through `rigidbench.forces.FrameField`).

What is measured: the ball's position relative to the platform, in its East-North-Up axes, at every step; where
it has fallen h (the crossing of Up = -h, located by cubic interpolation), its eastward displacement.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import signals
from rigidbench.analytic import rotating as rot
from rigidbench.contract import Case, Check, Derived, Scenario, Trajectory
from rigidbench.envs import rotating
from rigidbench.envs.base import ScenarioEnv
from rigidbench.params import Bound, Numeric, Param, Range, Value

BALL = "ball"
# Steps per fall time t0 = sqrt(2h/g) in the reference settings (the crossing's cubic interpolation error is
# O((dt/t0)^4) ~ 2e-11 relative; RK4's truncation error is far smaller, the motion being nearly polynomial).
STEPS_PER_FALL = 500
# Largest x0 = Omega t0 accepted: the neglected terms' bound (3/8) x0^2 + x0^4 holds up to x0 = 0.5 (tested), and
# at 0.3 it is 4.2 %.
MAX_TURN = 0.3
# The pole's check: the compiled axis leans from the vertical by at most ~eps (cos(pi/2) rounds to 6e-17), which
# would deflect the fall East by (1/3) Omega g t0^3 x that lean; + the positions' round-off 10 n eps h.
# Round-off of the position (m): each of the n steps rounds positions up to h from the origin, by ~eps h; the
# floor 10 n eps h (measured ~0.1 n eps h at the defaults).
ROUNDOFF_FACTOR = 10


@dataclass(frozen=True)
class DropHeight:
    """Drop height h (m): the custom numeric ``height``, and the drawn ground (h below the release) and tower."""

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        h = float(value)
        spec.numeric("height").data = [h]
        spec.geom("ground").pos = [0.0, 0.0, -h - 0.05]
        spec.geom("tower").pos = [-0.6, 0.0, -h / 2]
        spec.geom("tower").size = [0.2, 0.2, h / 2]

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.numeric("height").data[0])


_EAST = (
    "the terms N3 neglects, from the exact motion's series in x0 = Omega t0 (`analytic.rotating."
    "eastward_neglected_terms`): East gains -x^2/10, the fall to -h takes longer by x0^2 cos^2(lambda)/8, together "
    "at most (3/8) x0^2 relative, + x0^4 for the rest (6e-4 at the defaults, x0 = 0.04); + round-off 10 n eps h / d_E; "
    "RK4's truncation (~g t^2 (Omega dt)^4) and the crossing's cubic interpolation ((dt/t0)^4 ~ 2e-11) are far below"
)
_PATH = (
    "the exact motion (every order in Omega) against the simulated one at every step: RK4's truncation error is ~g "
    "t0^2 (Omega dt)^4 ~ 1e-20 m (the field turns slowly, the motion is otherwise polynomial), so what is left is "
    "round-off: each step rounds positions up to h by ~eps h; tolerance 10 n eps h over the run's n steps "
    "(2.2e-11 m at the defaults)"
)
_POLE = (
    "at the pole Omega is vertical: no Coriolis force on a vertical fall and no centrifugal force on the axis, so the "
    "ball falls straight; the floor is the deflection the compiled axis's lean from the vertical (read back; at most "
    "~eps: cos(pi/2) rounds to 6e-17) gives, (1/3) Omega g t0^3 x max(lean, eps), + round-off 10 n eps h (set per "
    "run)"
)
_EXACT = (
    "the eastward offset where the ball has fallen h, read as eastward-deflection reads it, against the exact motion's "
    "at its own crossing (`analytic.rotating.landing`, root-found to 4 eps); RK4's truncation is ~g t0^2 (Omega "
    "dt)^4 (check drop-path's reason), so the tolerance is round-off, 10 n eps h / d_E, + the crossing's and the "
    "East's cubic interpolation: exact for the cubic in t that N3 is, the Omega^2 t^4 and Omega^3 t^5 terms leave "
    "< x0^2 (dt/t0)^4 relative (set per run; 6e-11 at the defaults)"
)
CHECKS = (
    Check(
        "eastward-deflection",
        "m",
        6.2e-4,
        "rel",
        _EAST,
        "N3: d_E = (1/3) Omega g t0^3 cos(lambda) = (1/3) Omega cos(lambda) sqrt(8 h^3 / g) (Wilcox section 10.5)",
    ),
    Check(
        "eastward-deflection-exact",
        "m",
        6e-11,
        "rel",
        _EXACT,
        "N1, exact rotating-frame equations integrated in closed form (analytic.rotating.drop_path): the eastward "
        "offset where the body has fallen h, every order in Omega",
    ),
    Check(
        "pole-deflection",
        "m",
        5.6e-10,
        "abs",
        _POLE,
        "N3 at lambda = +-90 deg: cos(lambda) = 0, no deflection",
        identity=True,
    ),
    Check(
        "drop-path",
        "m",
        2.2e-11,
        "abs",
        _PATH,
        "N1 integrated in closed form for a field fixed in the turning frame: r(t) = R(t)^T [r0 + (Omega x r0) t + "
        "integral (t - s) R(s) g ds]",
    ),
)


def _rate_range(p: Mapping[str, Any]) -> Range:
    t0 = rot.fall_time(float(p["g"]), float(p["height"]))
    return Range(1e-4 / t0, MAX_TURN / t0)


class EastwardDeflection(Scenario):
    """A ball dropped from rest on a platform turning at latitude lambda (docs/theory.md N1, N3)."""

    slug = "eastward-deflection"
    title = "Eastward deflection of a body dropped on a turning platform ((1/3) Omega g t^3 cos(latitude))"
    env_id = "rigidbench/EastwardDeflection-v0"
    params = (
        Param(
            "height",
            "m",
            "drop height h: the ball starts at rest on the platform's axis, h above the ground",
            Range(0.1, 1e4),
            DropHeight(),
        ),
        rotating.GRAVITY,
        rotating.LATITUDE,
        Param(
            "rate",
            "rad/s",
            "the platform's rate Omega (the Earth's, scaled up so that the deflection is large)",
            Range(1e-8, 10.0),
            Numeric("rate"),
            within=Bound(
                "[1e-4, 0.3] / t0, t0 = sqrt(2 height / g) (N3's domain here: its neglected terms' bound (3/8) "
                "(Omega t0)^2 + (Omega t0)^4 is tested up to Omega t0 = 0.5)",
                _rate_range,
                needs=("height", "g"),
            ),
        ),
    )
    cases = (
        Case(
            "mid-latitude",
            "lambda = 45 deg: East by (1/3) Omega g t0^3 / sqrt(2), and South by a second-order term",
            {"latitude": math.pi / 4},
            ("eastward-deflection", "eastward-deflection-exact", "drop-path"),
            ranges={"latitude": Range(math.pi / 18, 4 * math.pi / 9, magnitude=True)},
            regime="10 deg <= |lambda| <= 80 deg (nearer the poles the deflection is a small difference; see 'pole')",
        ),
        Case(
            "equator",
            "the equator: the largest deflection, (1/3) Omega g t0^3, and no North-South drift",
            {"latitude": 0.0},
            ("eastward-deflection", "eastward-deflection-exact", "drop-path"),
            ranges={"latitude": Range(0.0, math.pi / 18, magnitude=True)},
            regime="|lambda| <= 10 deg",
        ),
        Case(
            "pole",
            "the North pole: Omega is vertical and the ball falls straight down (no deflection)",
            {"latitude": math.pi / 2},
            ("pole-deflection", "drop-path"),
            ranges={"latitude": Range(math.pi / 2, math.pi / 2, magnitude=True)},
            regime="lambda = +-90 deg exactly: the zero deflection is then an identity",
        ),
    )
    checks = CHECKS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        t0 = rot.fall_time(float(params["g"]), float(params["height"]))
        return {
            "timestep": Derived(
                t0 / STEPS_PER_FALL,
                f"dt = t0 / {STEPS_PER_FALL}, t0 = sqrt(2 h / g) = {t0:.6g} s (the crossing's cubic interpolation "
                f"error (dt/t0)^4 = {STEPS_PER_FALL**-4.0:.1e})",
            )
        }

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        mujoco.mj_resetData(model, data)
        spin, ball = model.joint(rotating.SPIN), model.joint(BALL)
        rate = float(params["rate"])
        data.qvel[spin.dofadr[0]] = rate
        # At rest relative to the platform, on its axis: no velocity; the ball turns with the platform (its spin
        # does not enter: the field acts at its centre of mass). Free joint: linear velocity in world axes, angular
        # velocity in the ball's axes (aligned with the world's at t = 0).
        data.qvel[ball.dofadr[0] + 3 : ball.dofadr[0] + 6] = rate * np.array(model.jnt_axis[spin.id])

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        pl = rotating.platform(model, data)
        h = float(model.numeric("height").data[0])
        r0 = self._position(model, data.qpos[None])[0]
        t0 = rot.fall_time(pl.g, h)
        t_h, r_h = rot.landing(pl.field, pl.rate_vec, h, r0)
        dt = float(model.opt.timestep)
        duration = 1.02 * t_h + 4 * dt
        n = round(duration / dt)
        roundoff = ROUNDOFF_FACTOR * n * np.finfo(float).eps * h
        d_e = rot.eastward_deflection(pl.rate, pl.g, h, pl.latitude)
        lean = max(math.atan2(math.hypot(pl.axis[0], pl.axis[1]), abs(pl.axis[2])), float(np.finfo(float).eps))
        tolerance = {"drop-path": roundoff, "pole-deflection": abs(pl.rate) * pl.g * t0**3 / 3 * lean + roundoff}
        if d_e != 0 and abs(math.cos(pl.latitude)) > 1e-12:
            tolerance["eastward-deflection"] = rot.eastward_neglected_terms(pl.rate, pl.g, h) + roundoff / abs(d_e)
            tolerance["eastward-deflection-exact"] = roundoff / abs(r_h[0]) + (pl.rate * t0) ** 2 * (dt / t0) ** 4
        return {
            "_height": h,
            "_field": pl.field,
            "_rate_vec": pl.rate_vec,
            "_axis": pl.axis,
            "_r0": r0,
            "_t0": t0,
            "_landing": (t_h, r_h),
            "_duration": duration,
            "_tolerance": tolerance,
            "eastward-deflection": d_e,
            "eastward-deflection-exact": float(r_h[0]),
            "pole-deflection": d_e,
            "drop-path": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return float(prediction["_duration"])

    @staticmethod
    def _position(model: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
        """The ball's centre (m) relative to the platform, in its East-North-Up axes, shape (n, 3)."""
        adr = model.joint(BALL).qposadr[0]
        return rotating.world_to_platform(model, qpos, qpos[:, adr : adr + 3])

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        r = self._position(model, traj.qpos)
        exact = rot.drop_path(traj.time, prediction["_field"], prediction["_rate_vec"], prediction["_r0"])
        fallen = r[:, 2] - prediction["_r0"][2] + prediction["_height"]
        cross = signals.crossings(traj.time, fallen, -1)
        east = float(signals.interpolate(traj.time, r[:, 0], cross[:1])[0]) if cross.size else math.nan
        return {
            "eastward-deflection": east,
            "eastward-deflection-exact": east,
            "pole-deflection": east,
            "drop-path": float(np.max(np.linalg.norm(r - exact, axis=1))),
        }


class EastwardDeflectionEnv(ScenarioEnv):
    """``rigidbench/EastwardDeflection-v0``: a body dropped on a turning platform, scored against theory every step.

    Description
        A ball is released at rest relative to a platform (the Earth) that turns at ``rate`` about the axis (0, cos
        lambda, sin lambda) of its East-North-Up frame, from a point on that axis, ``height`` above the ground;
        gravity is fixed in the platform's axes. It lands East of the point below, by (1/3) Omega g t0^3
        cos(lambda) (docs/theory.md N3). With zero action the env follows the exact motion (N1 in closed form,
        `analytic.rotating.drop_path`).

    Observation Space
        Box(-inf, inf, (15,)), float64:

        ====  =================================================  ======  ==========================
        idx   quantity                                           unit    MuJoCo source
        ====  =================================================  ======  ==========================
        0     platform angle about its axis                      rad     qpos of hinge ``spin``
        1-3   ball centre, world frame                           m       qpos of free joint ``ball``
        4-7   ball orientation (w, x, y, z)                      1       qpos of free joint ``ball``
        8     platform rate                                      rad/s   qvel of hinge ``spin``
        9-11  ball velocity, world frame                         m/s     qvel of free joint ``ball``
        12-14 ball angular velocity, ball frame                  rad/s   qvel of free joint ``ball``
        ====  =================================================  ======  ==========================

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = max_force = 0.1`` N times it is a force on the
        ball in world axes, through ``xfrc_applied``; out-of-range actions are clipped. Zero action = the textbook
        problem.

    Rewards
        ``reward = -|r - r_theory(t)| / h``: the distance between the ball's position relative to the platform
        (its East-North-Up axes) and the exact motion, in units of the drop height; ``info["measured"]`` and
        ``info["predicted"]`` hold ``x_east``, ``y_north``, ``z_up`` (m).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        The ball at rest relative to the platform at its origin (on the axis); the platform at angle 0 turning
        at ``rate``.

    Episode End
        Truncated just after the ball has fallen ``height`` (1.02 times the exact fall time); terminated on
        divergence. The diverged step pays -10 for itself and for each step left, the worst the rest could
        score: blowing up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (mid-latitude, equator, pole), ``params`` (height, g, latitude, rate), ``profile``,
        ``integrator``, ``timestep``, ``frame_skip`` (default 10: t0/50), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = EastwardDeflection
    max_force: ClassVar[float] = 0.1
    observables: ClassVar[tuple[str, ...]] = ("x_east", "y_north", "z_up")

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(15,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_force, self.max_force, shape=(3,), dtype=np.float64)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        self._body = int(self.model.body(BALL).id)
        self._axis = np.asarray(self.prediction["_axis"], dtype=float)
        self.start_views()

    def bind_views(self) -> None:
        self._force = self._data.xfrc_applied[self._body, :3]

    def observe(self) -> np.ndarray:
        return np.concatenate([self._data.qpos, self._data.qvel])

    def apply_action(self, action: np.ndarray) -> None:
        self._force[:] = action

    def theory(self, t: np.ndarray) -> np.ndarray:
        p = self.prediction
        return rot.drop_path(np.asarray(t, dtype=float), p["_field"], p["_rate_vec"], p["_r0"])

    def measured(self, obs: np.ndarray) -> list[float]:
        theta, x = -float(obs[0]), obs[1:4]
        c, s, n = math.cos(theta), math.sin(theta), self._axis
        r = x * c + np.cross(n, x) * s + n * float(n @ x) * (1 - c)
        return [float(r[0]), float(r[1]), float(r[2])]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        d = [m - p for m, p in zip(measured, predicted, strict=True)]
        return math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / self.prediction["_height"]
