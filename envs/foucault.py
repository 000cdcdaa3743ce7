"""Foucault pendulum on a turning platform: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md N2 (the swing plane turns at ``-Omega sin(lambda)`` about the local vertical: clockwise seen
from above in the northern hemisphere, counter-clockwise in the southern, not at all on the equator), with N1
(the rotating-frame acceleration) for what N2 neglects, implemented in `rigidbench.analytic.rotating`. Model:
``models/foucault.xml`` (a spherical pendulum hung from the axis of a platform turning at a constant rate, gravity
fixed in the platform's axes through `rigidbench.forces.FrameField`).

What is measured: the bob's position relative to the platform, projected on the plane perpendicular to the plumb
line (the bob's rest direction in the turning frame, which leans from the geographic vertical by the bob's own
centrifugal acceleration, ~ (Omega/omega0)^2 sin(lambda) cos(lambda) rad); the azimuth of the swing at each
maximum excursion (events located by cubic interpolation); the time the swing plane takes to turn by pi (back to
its starting line), which gives the mean rate over a whole cycle of the centrifugal anisotropy.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import signals
from rigidbench.analytic import oscillations as osc
from rigidbench.analytic import rotating as rot
from rigidbench.contract import Case, Check, Derived, Scenario, Trajectory
from rigidbench.envs import rotating
from rigidbench.envs.base import ScenarioEnv
from rigidbench.envs.pendulums import RodLength
from rigidbench.params import Bound, Numeric, Param, Range

BOB, SWING = "pendulum", "swing"
# Steps per small-amplitude period T0 = 2 pi sqrt(l/g) in the reference settings: omega0 dt = 2 pi / 200 = 0.031.
STEPS_PER_PERIOD = 200
# Platform rate over the pendulum's frequency, Omega/omega0: above 0.01 the plane turns by pi within 100 periods
# (at |lambda| = 30 deg); at most 0.05, where the neglected (Omega/omega0)^2 terms stay below ~2.5e-3.
RATE_RATIO = (0.01, 0.05)
# Equator: the swing's azimuth is fitted over this many periods.
EQUATOR_PERIODS = 20
# The exact companions (precession-rate-exact, swing-path): the reference is `analytic.rotating.rotating_pendulum`
# at this relative tolerance (DOP853); MuJoCo's RK4 errors, predicted to leading order, are doubled.
REFERENCE_RTOL = 1e-12
RK4_MARGIN = 2.0
# The reference's own error, bounded from its comparison with an independent integration (inertial frame,
# spherical angles, LSODA; tests/test_rotating_exact.py) over the domain's corners: its half-turn rate within
# this fraction (measured <= 1.5e-10), its path within this phase (rad) per period times the swing's amplitude
# (measured <= 2.3e-10).
REFERENCE_RATE_ERROR = 1e-9
REFERENCE_PHASE_PER_PERIOD = 1e-9
# The equator's check: the compiled axis's sin(lambda) (read back; ~eps at most) turns the swing plane at Omega x
# it; round-off cannot turn it at all (measured 0: the swing's North components stay exactly 0 by the symmetry of
# every operation on them).

_PRECESSION = (
    "each neglected term sized from the compiled model and the release (`analytic.rotating."
    "precession_neglected_terms`): the plumb line's lean (the bob's centrifugal acceleration) |Omega . up - Omega "
    "sin(lambda)| / Omega sin(lambda) ~ (Omega/omega0)^2 cos^2(lambda), computed exactly; Airy's precession of the "
    "release's ellipse (b = a Omega_z / omega0), (3/8) sin^2(a) (1 + cot^2(lambda)) with the anisotropy's modulation "
    "of b; the centrifugal anisotropy Omega^2 cos^2(lambda) against the Coriolis splitting, kappa^2, kappa = "
    "(Omega/omega0) cos^2(lambda) / (2 |sin lambda|); x 1.25 for their cross terms (the largest error on a grid of the "
    "full nonlinear pendulum is 0.94 of the plain sum); + the platform's rate drift (check platform-rate's round-off "
    "bound); + RK4's splitting error 10 x 5 (omega0 dt)^4 / 120 (4e-7 at 200 steps a period). ~6e-4 at the defaults"
)
_PLATFORM = (
    "the pivot lies on the platform's axis and the ball joint transmits no torque, so the pendulum cannot torque the "
    "platform about its axis: Omega is constant in exact arithmetic, whatever the platform's inertia (1e9 kg m^2 only "
    "keeps the reaction's wobble of the hinge's numbers small), and its measured drift is round-off: tolerance "
    "10 n eps over the run's n steps (1.6e-11 at the defaults, measured 0)"
)
_EXACT_RATE = (
    "the same estimator (the azimuth at each maximum excursion, cubic-interpolated; the half turn) reads MuJoCo's "
    "samples and the exact motion's at the same step times, so its own bias cancels; what is left is RK4's: each of "
    "the swing's two circular modes, at -Omega_z +- omega', runs slow by (lambda dt)^4/120, which slows the plane's "
    "turn (their mean) by 5 (omega0 dt)^4/120 (1 + O((Omega/omega0)^2)) relative (4.1e-8 at 200 steps a period; "
    "measured 0.98-1.02 of it over 40 census draws), x 2; + the reference's own error (DOP853 at rtol 1e-12: 1e-9, "
    "measured <= 1.5e-10 against an independent inertial-frame integration); + round-off 10 n eps. ~8.2e-8 at the "
    "defaults"
)
_PATH = (
    "the bob's position in the platform's axes at every step against the exact motion at the same time: RK4 slows "
    "each circular mode's phase by omega t (omega0 dt)^4/120 by time t, moving the bob by at most its horizontal "
    "amplitude A = l sin(a) times that (measured 0.98-1.0 of A omega0 T (omega0 dt)^4/120, T the run's end, over 40 "
    "census draws), x 2 (set per run); + the reference's own error (DOP853 at rtol 1e-12: 1e-9 rad a period times A, "
    "measured <= 2.3e-10 against an independent inertial-frame integration); + round-off 10 n eps l. ~7.5e-8 m at "
    "the defaults"
)
_EXACT_THEORY = (
    "N1, exact rotating-frame equations: the spherical pendulum (rod l, the bob's isotropic 1e-9 kg m^2 as O2) on a "
    "platform turning at a constant Omega, gravity fixed in its axes, integrated to rtol 1e-12 (analytic.rotating."
    "rotating_pendulum)"
)
CHECKS = (
    Check(
        "precession-rate",
        "rad/s",
        5.7e-4,
        "rel",
        _PRECESSION,
        "N2: the swing plane turns at -Omega sin(lambda) about the vertical (Wilcox section 10.6); half a turn takes "
        "pi / (Omega |sin lambda|)",
    ),
    Check(
        "equator-precession",
        "rad/s",
        1e-17,
        "abs",
        f"on the equator Omega is horizontal and an East-West swing stays in its plane by symmetry (the Coriolis and "
        f"centrifugal forces of a motion in the East-Up plane lie in it): the floor is the rate the compiled axis's "
        f"sin(lambda) (read back, ~eps at most) gives, Omega x max(|sin lambda|, eps) (set per run; 1e-17 at the "
        f"default rate); round-off keeps the North components exactly 0 (measured 0); azimuth fitted over "
        f"{EQUATOR_PERIODS} periods",
        "N2 at lambda = 0: Omega sin(lambda) = 0, no precession",
        identity=True,
    ),
    Check(
        "swing-period",
        "s",
        1e-7,
        "rel",
        "on the equator Omega is horizontal: for an East-West swing the Coriolis force (perpendicular to the velocity "
        "in the swing's plane) and the centrifugal force (Omega^2 r, r perpendicular to Omega) are both along the rod, "
        "so the swing is an exact planar pendulum. Tolerance: RK4's frequency error 10 (omega0 dt)^4/120 (8e-8 at 200 "
        "steps a period); the turning points are cubic-interpolated (O(dt^4)) and averaged over the run",
        "O1 with O2 (the bob's 1e-9 kg m^2): T = 4 sqrt(l_eq/g) K(sin(a/2)), unchanged by the rotation on the equator",
    ),
    Check(
        "precession-rate-exact",
        "rad/s",
        8.2e-8,
        "rel",
        _EXACT_RATE,
        f"{_EXACT_THEORY}: the time its swing plane takes to turn by pi, read as precession-rate reads it",
    ),
    Check(
        "swing-path",
        "m",
        7.5e-8,
        "abs",
        _PATH,
        f"{_EXACT_THEORY}: the bob's path relative to the platform",
    ),
    Check(
        "platform-rate",
        "1",
        1.6e-11,
        "abs",
        _PLATFORM,
        "N1 with Omega' = 0: the platform turns at a constant rate",
        identity=True,
    ),
)
_TURNING = ("precession-rate", "precession-rate-exact", "swing-path", "platform-rate")


def _rate_range(p: Mapping[str, Any]) -> Range:
    w0 = math.sqrt(float(p["g"]) / float(p["length"]))
    return Range(RATE_RATIO[0] * w0, RATE_RATIO[1] * w0)


_REGIME = (
    "the neglected terms' sizes (precession-rate's reason) are bounds tested against the full nonlinear pendulum "
    "for 30 deg <= |lambda| <= 90 deg; nearer the equator the centrifugal anisotropy Omega^2 cos^2(lambda) outgrows "
    "the Coriolis splitting Omega sin(lambda) and the plane no longer turns uniformly"
)


class Foucault(Scenario):
    """A spherical pendulum on a platform turning at latitude lambda (docs/theory.md N1, N2)."""

    slug = "foucault"
    title = "Foucault pendulum on a turning platform (swing plane turns at -Omega sin(latitude))"
    env_id = "rigidbench/Foucault-v0"
    params = (
        Param(
            "length",
            "m",
            "distance l from the pivot (on the platform's axis) to the point bob",
            Range(0.1, 100.0),
            RodLength(),
        ),
        rotating.GRAVITY,
        rotating.LATITUDE,
        Param(
            "rate",
            "rad/s",
            "the platform's rate Omega (the Earth's, scaled up so that the plane turns within a short run)",
            Range(1e-4, 10.0),
            Numeric("rate"),
            within=Bound(
                "[0.01, 0.05] sqrt(g/length) (N2's domain here: its neglected terms are sized up to Omega/omega0 = "
                "0.05; below 0.01 half a turn takes over 100 periods)",
                _rate_range,
                needs=("length", "g"),
            ),
        ),
        Param(
            "amplitude",
            "rad",
            "release angle from the plumb line, at rest relative to the platform",
            Range(0.005, 0.05),
            Numeric("amplitude"),
        ),
        Param(
            "azimuth",
            "rad",
            "release direction about the plumb line, from East towards North",
            Range(-math.pi, math.pi),
            Numeric("azimuth"),
        ),
    )
    cases = (
        Case(
            "mid-latitude",
            "Paris (Foucault's Pantheon, 1851), lambda = 48.85 deg: clockwise at Omega sin(lambda) = 0.75 Omega",
            {"latitude": math.radians(48.85)},
            _TURNING,
            ranges={"latitude": Range(math.pi / 6, 4 * math.pi / 9, magnitude=True)},
            regime=_REGIME,
        ),
        Case(
            "pole",
            "the North pole: the plane stays fixed in space while the platform turns under it, at -Omega",
            {"latitude": math.pi / 2},
            _TURNING,
            ranges={"latitude": Range(4 * math.pi / 9, math.pi / 2)},
            regime="80 deg <= lambda <= 90 deg (the pole's neighbourhood; mid-latitude covers 30-80 deg)",
        ),
        Case(
            "southern",
            "Sydney, lambda = -33.87 deg: counter-clockwise at 0.56 Omega",
            {"latitude": math.radians(-33.87)},
            _TURNING,
            ranges={"latitude": Range(-4 * math.pi / 9, -math.pi / 6)},
            regime=_REGIME,
        ),
        Case(
            "equator",
            "the equator, an East-West swing: Omega is horizontal and the plane does not turn",
            {"latitude": 0.0, "azimuth": 0.0},
            ("equator-precession", "swing-period", "swing-path", "platform-rate"),
            ranges={"latitude": Range(0.0, 0.0), "azimuth": Range(0.0, 0.0)},
            regime="lambda = 0 exactly, released East-West: the plane of swing is then invariant by symmetry",
        ),
    )
    checks = CHECKS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        period = 2 * math.pi * math.sqrt(float(params["length"]) / float(params["g"]))
        return {
            "timestep": Derived(
                period / STEPS_PER_PERIOD,
                f"dt = T0 / {STEPS_PER_PERIOD}, T0 = 2 pi sqrt(l/g) = {period:.6g} s (omega0 dt = "
                f"{2 * math.pi / STEPS_PER_PERIOD:.3g}: RK4 frequency error (omega0 dt)^4/120 = "
                f"{(2 * math.pi / STEPS_PER_PERIOD) ** 4 / 120:.1e})",
            )
        }

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        mujoco.mj_resetData(model, data)
        spin, swing = model.joint(rotating.SPIN), model.joint(SWING)
        lam, rate = float(params["latitude"]), float(params["rate"])
        down = rot.plumb_line([0.0, 0.0, -float(params["g"])], rot.rate_vector(rate, lam), float(params["length"]))
        east, north = rot.horizontal_axes(down)
        a, az = float(params["amplitude"]), float(params["azimuth"])
        u = math.cos(a) * down + math.sin(a) * (math.cos(az) * east + math.sin(az) * north)
        # The ball joint's orientation turning the pendulum's -z (its rod) onto u: about -z x u by arccos(-z . u).
        rod = np.array([0.0, 0.0, -1.0])
        axis = np.cross(rod, u)
        angle = math.atan2(np.linalg.norm(axis), float(rod @ u))
        quat = np.zeros(4)
        mujoco.mju_axisAngle2Quat(quat, axis / np.linalg.norm(axis), angle)
        data.qpos[swing.qposadr[0] : swing.qposadr[0] + 4] = quat
        data.qvel[spin.dofadr[0]] = rate  # at rest relative to the platform, which turns at Omega

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        pl = rotating.platform(model, data)
        body = model.body(BOB)
        length, mass = float(-body.ipos[2]), float(body.mass[0])
        inertia_pivot = mass * length**2 + float(body.inertia[0])
        omega0 = math.sqrt(mass * pl.g * length / inertia_pivot)  # O2: the bob's own 1e-9 kg m^2 included
        down = rot.plumb_line(pl.field, pl.rate_vec, length)
        east, north = rot.horizontal_axes(down)
        r0, v0 = (x[0] for x in self._bob(model, data.qpos[None], data.qvel[None], length))
        amplitude = math.acos(min(1.0, float(r0 @ down) / length))
        azimuth = math.atan2(float(r0 @ north), float(r0 @ east))
        period = 2 * math.pi / omega0
        expected = rot.foucault_precession_rate(pl.rate, pl.latitude)
        equator = abs(math.sin(pl.latitude)) < 1e-12
        dt = float(model.opt.timestep)
        duration = EQUATOR_PERIODS * period if equator else math.pi / abs(expected) + 2 * period
        # Platform-rate: round-off only (check platform-rate's reason).
        drift = 10 * round(duration / dt) * np.finfo(float).eps
        rk4 = 10 * 5 * (omega0 * dt) ** 4 / 120
        tolerance = {"platform-rate": drift}
        # The exact companions: the exact motion sampled at MuJoCo's step times k dt (check swing-path's reason).
        steps = round(duration / dt)
        times = np.arange(steps + 1) * dt
        ratio = float(body.inertia[0]) / (mass * length**2)
        r, v = (
            x.T
            for x in rot.rotating_pendulum(
                length, pl.field, pl.rate_vec, r0, v0, times[-1], rtol=REFERENCE_RTOL, inertia_ratio=ratio
            )(times)
        )
        horizontal = length * math.sin(amplitude)
        phase = omega0 * times[-1] * (omega0 * dt) ** 4 / 120
        tolerance["swing-path"] = (
            RK4_MARGIN * horizontal * phase
            + REFERENCE_PHASE_PER_PERIOD * times[-1] / period * horizontal
            + 10 * steps * np.finfo(float).eps * length
        )
        exact_rate = 0.0
        terms = {}
        if not equator:
            terms = rot.precession_neglected_terms(pl.rate_vec, down, omega0, amplitude, pl.latitude)
            tolerance["precession-rate"] = rot.precession_tolerance(terms) + drift + rk4
            tips, tip_azimuths, _, _ = swing(times, r, v, (east, north), period)
            exact_rate = swing_rates(tips, tip_azimuths, expected)[1]
            tolerance["precession-rate-exact"] = (
                RK4_MARGIN * 5 * (omega0 * dt) ** 4 / 120 + REFERENCE_RATE_ERROR + drift
            )
        else:
            tolerance["equator-precession"] = abs(pl.rate) * max(abs(float(pl.axis[2])), float(np.finfo(float).eps))
            tolerance["swing-period"] = 10 * (omega0 * dt) ** 4 / 120  # RK4 frequency error x 10
        return {
            "_length": length,
            "_omega0": omega0,
            "_period": period,
            "_down": down,
            "_axes": (east, north),
            "_amplitude": amplitude,
            "_azimuth": azimuth,
            "_rate": pl.rate,
            "_latitude": pl.latitude,
            "_vertical_rate": float(-pl.rate_vec @ down),
            "_terms": terms,
            "_r0": r0,
            "_field": pl.field,
            "_rate_vec": pl.rate_vec,
            "_duration": duration,
            "_tolerance": tolerance,
            "_inertia_ratio": ratio,
            "_exact_path": r,
            "precession-rate": expected,
            "precession-rate-exact": exact_rate,
            "swing-path": 0.0,
            "equator-precession": 0.0,
            "swing-period": osc.pendulum_period(inertia_pivot / (mass * length), pl.g, amplitude),
            "platform-rate": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return float(prediction["_duration"])

    @staticmethod
    def _bob(model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray]:
        """The bob's position (m) and velocity (m/s) relative to the platform, in its axes, shape (n, 3) each."""
        swing = model.joint(SWING)
        q = qpos[:, swing.qposadr[0] : swing.qposadr[0] + 4]
        w = qvel[:, swing.dofadr[0] : swing.dofadr[0] + 3]  # the pendulum's rate relative to the platform, its axes
        rod = np.array([0.0, 0.0, -length])
        return rotating.rotate(q, np.broadcast_to(rod, w.shape)), rotating.rotate(q, np.cross(w, rod))

    def swing(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]):
        """The swing seen from above the plumb line: times (s) and azimuths (rad, unwrapped modulo pi, from East
        towards North) at each maximum excursion, the release included, and the horizontal path (X, Y) (m)."""
        r, v = self._bob(model, traj.qpos, traj.qvel, prediction["_length"])
        return swing(traj.time, r, v, prediction["_axes"], prediction["_period"])

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        r, v = self._bob(model, traj.qpos, traj.qvel, prediction["_length"])
        times, azimuth, _, _ = swing(traj.time, r, v, prediction["_axes"], prediction["_period"])
        slope, rate = swing_rates(times, azimuth, prediction["precession-rate"])
        spin = rotating.spin_rate(model, traj.qvel)
        exact = prediction["_exact_path"]
        if exact.shape != r.shape:  # a run of another length than predicted (an env's episode): solved afresh
            grid = np.arange(len(r)) * float(model.opt.timestep)
            exact = rot.rotating_pendulum(
                prediction["_length"],
                prediction["_field"],
                prediction["_rate_vec"],
                prediction["_r0"],
                v[0],
                grid[-1],
                rtol=REFERENCE_RTOL,
                inertia_ratio=prediction["_inertia_ratio"],
            )(grid)[0].T
        tips = times[1:]  # the turning points after the release: two a period
        return {
            "swing-period": 2 * signals.mean_spacing(tips),
            "precession-rate": rate,
            "precession-rate-exact": rate,
            "swing-path": float(np.max(np.linalg.norm(r - exact, axis=1))),
            "equator-precession": slope,
            "platform-rate": float(np.max(np.abs(spin / spin[0] - 1))),
        }


def swing(time: np.ndarray, r: np.ndarray, v: np.ndarray, axes: tuple[np.ndarray, np.ndarray], period: float):
    """The swing of a bob at positions `r` and velocities `v` (m, m/s, shape (n, 3), platform axes) sampled at
    `time`, seen from above the plumb line (`axes` = its East and North): times (s) and azimuths (rad, unwrapped
    modulo pi, from East towards North) at each maximum excursion (cubic-interpolated), the release included, and
    the horizontal path (X, Y) (m). The same estimator reads MuJoCo's samples and the exact motion's."""
    east, north = axes
    x, y, vx, vy = r @ east, r @ north, v @ east, v @ north
    times, _ = signals.extrema(time, x * x + y * y, 2 * (x * vx + y * vy), "max")
    times = times[times > 0.25 * period]
    xs = np.concatenate([[x[0]], signals.interpolate(time, x, times)]) if times.size else x[:1]
    ys = np.concatenate([[y[0]], signals.interpolate(time, y, times)]) if times.size else y[:1]
    times = np.concatenate([[time[0]], times])
    azimuth = np.unwrap(2 * np.arctan2(ys, xs)) / 2  # a line's direction is defined modulo pi
    return times, azimuth, x, y


def swing_rates(times: np.ndarray, azimuth: np.ndarray, expected: float) -> tuple[float, float]:
    """The swing plane's rates (rad/s) from its azimuths at the turning points (`swing`): the least-squares slope,
    and the half turn's pi / t_pi, t_pi the first time the plane is back on its starting line, turned by pi either
    way (the slope where it never is, or where `expected` is 0)."""
    slope = float(np.polyfit(times - times.mean(), azimuth, 1)[0]) if len(times) >= 2 else math.nan
    rate = slope
    if expected != 0 and len(times) >= 4:
        sense = 1.0 if slope > 0 else -1.0
        back = signals.crossings(times, azimuth - (azimuth[0] + sense * math.pi))
        if back.size:
            rate = sense * math.pi / float(back[0])
    return slope, rate


class FoucaultEnv(ScenarioEnv):
    """``rigidbench/Foucault-v0``: the Foucault pendulum on a turning platform, scored against theory every step.

    Description
        A point bob on a massless rod hangs from a ball joint on the axis of a platform (the Earth) that turns at
        ``rate`` about the axis (0, cos lambda, sin lambda) of its East-North-Up frame; gravity is fixed in the
        platform's axes. Released at rest relative to the platform, the swing plane turns at ``-rate sin(lambda)``
        (docs/theory.md N2). With zero action the env follows the exact rotating-frame pendulum (N1,
        `analytic.rotating.rotating_pendulum`).

    Observation Space
        Box(-inf, inf, (9,)), float64:

        ====  ==========================================================  ======  ==========================
        idx   quantity                                                    unit    MuJoCo source
        ====  ==========================================================  ======  ==========================
        0     platform angle about its axis                               rad     qpos of hinge ``spin``
        1-4   pendulum orientation relative to the platform (w, x, y, z)  1       qpos of ball ``swing``
        5     platform rate                                               rad/s   qvel of hinge ``spin``
        6-8   pendulum rate relative to the platform, pendulum axes       rad/s   qvel of ball ``swing``
        ====  ==========================================================  ======  ==========================

    Action Space
        Box(-1, 1, (2,)), float32, normalised: ``action_scale = max_torque = 0.01`` N m times it is a torque on
        the ball joint about the pendulum's own x and y axes, through ``qfrc_applied``; out-of-range actions are
        clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|X - X_theory(t)| / (l sin a)``: the distance between the bob's horizontal position (X, Y)
        across the plumb line, in the platform's frame, and the exact N1 motion, in units of the release's
        horizontal excursion; ``info["measured"]`` and ``info["predicted"]`` hold ``x_east``, ``y_north`` (m).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        At rest relative to the platform, ``amplitude`` from the plumb line towards ``azimuth``; the platform at
        angle 0 turning at ``rate``.

    Episode End
        Truncated when the plane has turned by pi (two periods later; 20 periods on the equator); terminated on
        divergence. The diverged step pays -10 for itself and for each step left, the worst the rest could
        score: blowing up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (mid-latitude, pole, southern, equator), ``params`` (length, g, latitude, rate, amplitude,
        azimuth), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10: T0/20), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = Foucault
    max_torque: ClassVar[float] = 0.01
    observables: ClassVar[tuple[str, ...]] = ("x_east", "y_north")
    # The exact motion (a closure over scipy's dense output): solved again by a copy that needs it.
    _recomputed: ClassVar[tuple[str, ...]] = ("_motion", "_motion_for")

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(9,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_torque, self.max_torque, shape=(2,), dtype=np.float64)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        p = self.prediction
        self._dof = int(self.model.joint(SWING).dofadr[0])
        self._scale = p["_length"] * math.sin(p["_amplitude"])
        self.start_views()

    def bind_views(self) -> None:
        self._torque = self._data.qfrc_applied[self._dof : self._dof + 2]

    def observe(self) -> np.ndarray:
        return np.concatenate([self._data.qpos, self._data.qvel])

    def apply_action(self, action: np.ndarray) -> None:
        self._torque[:] = action

    def theory(self, t: np.ndarray) -> np.ndarray:
        p = self.prediction
        if getattr(self, "_motion_for", None) is not p:
            self._motion = rot.rotating_pendulum(
                p["_length"],
                p["_field"],
                p["_rate_vec"],
                p["_r0"],
                np.zeros(3),
                1.05 * p["_duration"] + 1.0,
                inertia_ratio=p["_inertia_ratio"],
            )
            self._motion_for = p
        r, _ = self._motion(np.clip(np.asarray(t, dtype=float), 0.0, None))
        east, north = p["_axes"]
        return np.stack([east @ r, north @ r], axis=1)

    def measured(self, obs: np.ndarray) -> list[float]:
        q = obs[1:5]
        r = rotating.rotate(q, np.array([0.0, 0.0, -self.prediction["_length"]]))
        east, north = self.prediction["_axes"]
        return [float(r @ east), float(r @ north)]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        return math.hypot(measured[0] - predicted[0], measured[1] - predicted[1]) / self._scale
