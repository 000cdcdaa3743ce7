"""Heavy symmetric top on a fixed frictionless pivot (Lagrange top): the MuJoCo side, and its gymnasium env.

Theory: THEORY.md T1-T7 (Wilcox Part II section 11.10, eqs 11.52-11.62; prob. 11.13, 11.18), implemented in
`rigidbench.analytic.tops`. Model: ``models/heavy_top.xml`` (a ball joint at the world origin; body z is the
symmetry axis; the CM at ``arm`` on it).

Conventions: theta from the upward vertical, so U = M g h cos(theta); z-x-z Euler angles with phi = psi = 0
at t = 0, so the initial body rates are (theta_dot, phi_dot sin(theta), omega3).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import frames, signals
from rigidbench.analytic import tops
from rigidbench.envs.rotor import RotorEnv, RotorMotion, require_rigid_body_inertia
from rigidbench.params import BodyComOffset, BodyInertia, BodyMass, Gravity, Numeric, Param, Range, positive
from rigidbench.scenario import Case, Check, Scenario
from rigidbench.simulate import Trajectory

# Reference: RK4 at dt = 1e-4 s; the nutation (~60 rad/s at the default spin) is the fastest scale that
# theta and phi see, so omega dt ~ 6e-3 and RK4's global error ~ omega T (omega dt)^4 ~ 1e-7 at worst over a
# few seconds; event times and extreme values are cubic-interpolated, error O(dt^4).
_RK4 = "RK4 at dt = 1e-4 s: global error ~ omega_nut T (omega_nut dt)^4 <~ 1e-7 over the run; events cubic-interpolated"
_DRIFT = "RK4 is not symplectic: drift ~ T omega (omega dt)^4 ~ 1e-10 at reference; 1e-8 is 2 decades above"
_LINEAR = "linearised in theta (T6): relative error O(theta^2), <= 1e-4 here (theta <= 1e-2 rad)"

CHECKS = (
    Check("theta-min", "rad", 1e-6, "rel", _RK4, "T2: theta_min = arccos(u2), roots of the cubic f(u)"),
    Check("theta-max", "rad", 1e-6, "rel", _RK4, "T2: theta_max = arccos(u1), roots of the cubic f(u)"),
    Check(
        "nutation-period",
        "s",
        1e-6,
        "rel",
        _RK4 + " (mean spacing of the theta maxima)",
        "T3: T_nut = 4 K(k) / sqrt(beta (u3 - u1))",
    ),
    Check(
        "mean-precession",
        "rad/s",
        1e-6,
        "rel",
        _RK4 + " (phi advance between the first and last theta maxima)",
        "T3: Delta phi / T_nut, phi_dot = (b - a u)/(1 - u^2) over one nutation period",
    ),
    Check(
        "precession-at-theta-min",
        "rad/s",
        1e-6,
        "rel",
        _RK4,
        "T2: phi_dot = (b - a u2)/(1 - u2^2) at the top turning point",
    ),
    Check(
        "precession-at-theta-max",
        "rad/s",
        1e-6,
        "rel",
        _RK4 + " (sign change = looping)",
        "T2: phi_dot = (b - a u1)/(1 - u1^2) at the bottom turning point",
    ),
    Check(
        "tilt-deviation",
        "rad",
        1e-7,
        "abs",
        "steady precession has theta_dot = 0 exactly; integration error excites a nutation of amplitude "
        "~ global error ~1e-9 rad; 1e-7 leaves 2 decades",
        "T4: steady precession at a root of I1 cos(theta0) phi_dot^2 - I3 omega3 phi_dot + M g h = 0",
    ),
    Check(
        "precession-rate",
        "rad/s",
        1e-6,
        "rel",
        _RK4 + " (slope of the unwrapped phi)",
        "T4: phi_dot = [I3 omega3 -+ sqrt(I3^2 omega3^2 - 4 I1 M g h cos(theta0))] / (2 I1 cos(theta0))",
    ),
    Check(
        "max-tilt-linear",
        "rad",
        1e-3,
        "rel",
        _LINEAR.replace("<= 1e-4", "~ theta0^2 = 1e-4"),
        "T6: theta_max = theta0 I3 omega3 / sqrt(I3^2 omega3^2 - 4 I1 M g h) (sleeping top, Wilcox prob. 11.13)",
    ),
    Check(
        "tilt-growth-rate",
        "1/s",
        1e-3,
        "rel",
        "slope of ln(theta) fitted over theta in [20, 100] theta0 (theta0 = 1e-4 rad): the decaying mode "
        "biases it by ~2 e^(-2 gamma t) <= 1e-3 at the window's start, ~2e-4 on average; nonlinear terms "
        "O(theta^2) <= 1e-4",
        "T6: gamma = sqrt(4 I1 M g h - I3^2 omega3^2) / (2 I1); linearised theta = theta0 "
        "sqrt(cosh^2(gamma t) + (a/2 gamma)^2 sinh^2(gamma t))",
    ),
    Check("energy-drift", "1", 1e-8, "abs", _DRIFT, "T1: E conserved (frictionless pivot)"),
    Check("p-phi-drift", "1", 1e-8, "abs", _DRIFT + " (relative to |L|)", "T1: p_phi = L_z conserved, eq. 11.61"),
    Check("p-psi-drift", "1", 1e-8, "abs", _DRIFT, "T1: p_psi = I3 omega3 conserved, eq. 11.62"),
)
_CONSERVED = ("energy-drift", "p-phi-drift", "p-psi-drift")
_NUTATION = ("theta-min", "theta-max", "nutation-period", "mean-precession", *_CONSERVED)
_STEADY = ("tilt-deviation", "precession-rate", *_CONSERVED)


def _pivot_inertia(p: Mapping[str, Any]) -> float:
    return p["I1"] + p["mass"] * p["arm"] ** 2  # parallel axes, THEORY.md R4


def _mgh(p: Mapping[str, Any]) -> float:
    return p["mass"] * p["g"] * p["arm"]


def _steady(p: Mapping[str, Any], root: int) -> float:
    return tops.steady_precession_rates(_pivot_inertia(p), p["I3"], _mgh(p), p["spin"], p["tilt"])[root]


def _threshold(p: Mapping[str, Any]) -> float:
    return tops.sleeping_threshold(_pivot_inertia(p), p["I3"], _mgh(p))


class HeavyTop(Scenario):
    """A symmetric top on a fixed pivot under gravity: nutation between the roots of a cubic, steady
    precession, the sleeping top and its threshold (THEORY.md T1-T7)."""

    slug = "heavy-top"
    title = "Heavy symmetric top on a fixed pivot (Lagrange top)"
    env_id = "rigidbench/HeavyTop-v0"
    params = (
        Param("mass", "kg", "mass of the top", positive(1e3), BodyMass("top")),
        Param(
            "arm",
            "m",
            "distance h from the pivot to the CM along the symmetry axis",
            positive(10.0),
            BodyComOffset("top", 2),
        ),
        Param(
            "I1",
            "kg m^2",
            "transverse principal moment about the CM (the theory adds M arm^2 for the pivot)",
            positive(1e3),
            BodyInertia("top", (0, 1)),
        ),
        Param("I3", "kg m^2", "principal moment about the symmetry axis", positive(1e3), BodyInertia("top", (2,))),
        Param(
            "tilt",
            "rad",
            "initial angle theta0 of the symmetry axis from the upward vertical",
            Range(0, np.pi, low_open=True, high_open=True),
            Numeric("tilt"),
        ),
        Param(
            "spin",
            "rad/s",
            "omega3, angular velocity about the symmetry axis (conserved)",
            Range(-1e4, 1e4),
            Numeric("spin"),
        ),
        Param(
            "precession",
            "rad/s",
            "initial phi_dot, rate of the axis about the vertical",
            Range(-1e4, 1e4),
            Numeric("precession"),
        ),
        Param("nutation_rate", "rad/s", "initial theta_dot", Range(-1e4, 1e4), Numeric("nutation_rate")),
        Param("g", "m/s^2", "gravitational acceleration (along -z)", positive(1e3), Gravity()),
    )
    cases = (
        Case(
            "nutation",
            "released with theta_dot = phi_dot = 0: cusped nutation between the cubic's roots",
            {"tilt": 0.5, "precession": 0.0, "nutation_rate": 0.0},
            _NUTATION,
        ),
        Case(
            "looping",
            "released with phi_dot = minus the gyroscopic rate: phi_dot changes sign (loops)",
            {"tilt": 0.5, "nutation_rate": 0.0, "precession": lambda p: -_steady(p, 0)},
            (*_NUTATION, "precession-at-theta-min", "precession-at-theta-max"),
        ),
        Case(
            "slow-precession",
            "phi_dot at the slow root of T4: theta stays at tilt",
            {"tilt": 0.5, "nutation_rate": 0.0, "precession": lambda p: _steady(p, 0)},
            _STEADY,
        ),
        Case(
            "fast-precession",
            "phi_dot at the fast root of T4: theta stays at tilt",
            {"tilt": 0.5, "nutation_rate": 0.0, "precession": lambda p: _steady(p, 1)},
            _STEADY,
        ),
        Case(
            "sleeping",
            "nearly upright (0.01 rad) at 1.5x the T6 threshold spin: the tilt stays bounded",
            {"tilt": 0.01, "precession": 0.0, "nutation_rate": 0.0, "spin": lambda p: 1.5 * _threshold(p)},
            (*_NUTATION, "max-tilt-linear"),
        ),
        # No nutation-period check here: a top released at rest at theta0 from the upright returns to theta0,
        # and its period ~ (2/gamma) ln(1/theta0) hangs on how close it comes back, which the conserved energy
        # fixes only to dtheta0/theta0 ~ dE / (M g h theta0^2): at theta0 = 1e-4 an energy error of 1e-13 (RK4
        # at reference) moves the period by ~1e-7. The nutation cases check the period where it is well posed.
        Case(
            "falling",
            "nearly upright (1e-4 rad) at 0.5x the T6 threshold spin: the tilt grows exponentially",
            {"tilt": 1e-4, "precession": 0.0, "nutation_rate": 0.0, "spin": lambda p: 0.5 * _threshold(p)},
            ("theta-max", "tilt-growth-rate", *_CONSERVED),
        ),
    )
    checks = CHECKS

    def validate(self, params: Mapping[str, Any]) -> None:
        require_rigid_body_inertia(params["I1"], params["I1"], params["I3"], "I1 = I2, I3 (about the CM)")

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        theta = params["tilt"]
        data.qpos[:4] = frames.quat_from_euler_zxz(0.0, theta, 0.0)
        data.qvel[:3] = [params["nutation_rate"], params["precession"] * np.sin(theta), params["spin"]]

    def motion(self, model: mujoco.MjModel, time: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> RotorMotion:
        """The top's motion about the pivot (inertia taken about the pivot, THEORY.md R4)."""
        body = model.body("top")
        i_cm = body.inertia
        h = body.ipos[2]
        inertia = np.array([i_cm[0] + body.mass[0] * h * h, i_cm[1] + body.mass[0] * h * h, i_cm[2]])
        return RotorMotion(time=time, quat_WB=qpos[..., :4], omega_B=qvel[..., :3], inertia_B=inertia)

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        m = self.motion(model, np.array([data.time]), data.qpos[None], data.qvel[None])
        mgh = self._mgh(model)
        i1, _, i3 = m.inertia_B
        R = m.R_WB[0]
        w1, w2, spin = m.omega_B[0]
        # From the state, without cancellation (THEORY.md section 0, eq. 11.38 inverted):
        # sin(theta) = |(R31, R32)|, sin(theta) theta_dot = w1 R32 - w2 R31, sin^2(theta) phi_dot = w1 R31 + w2 R32.
        s = float(np.hypot(R[2, 0], R[2, 1]))
        tilt = float(np.arctan2(s, R[2, 2]))
        tilt_rate = float((w1 * R[2, 1] - w2 * R[2, 0]) / s)
        phi_dot0 = float((w1 * R[2, 0] + w2 * R[2, 1]) / (s * s))
        top = tops.heavy_top(i1, i3, mgh, tilt=tilt, tilt_rate=tilt_rate, precession=phi_dot0, spin=float(spin))
        steady = tilt_rate == 0 and (top.w_roots[0] - top.w_roots[1]) < 1e-12
        out = {
            "_theory": top,
            "_steady": steady,
            "_tilt0": tilt,
            "theta-min": top.theta_min,
            "theta-max": top.theta_max,
            "nutation-period": top.nutation_period,
            "mean-precession": top.mean_precession_rate,
            "precession-at-theta-min": float(top.precession_rate_at_w(top.w_roots[1])),
            "precession-at-theta-max": float(top.precession_rate_at_w(top.w_roots[0])),
            "tilt-deviation": 0.0,
            "precession-rate": phi_dot0,  # a steady top keeps its initial phi_dot; T4 says which values
            "energy-drift": 0.0,
            "p-phi-drift": 0.0,
            "p-psi-drift": 0.0,
        }
        if (i3 * spin) ** 2 > 4 * i1 * mgh:
            out["max-tilt-linear"] = tops.sleeping_max_tilt(i1, i3, mgh, spin, tilt)
        else:
            out["tilt-growth-rate"] = tops.falling_growth_rate(i1, i3, mgh, spin)
        if steady:
            slow, fast = tops.steady_precession_rates(i1, i3, mgh, spin, tilt)
            out["precession-rate"] = slow if abs(phi_dot0 - slow) <= abs(phi_dot0 - fast) else fast
        return out

    def duration(self, prediction: Mapping[str, Any]) -> float:
        if prediction["_steady"]:
            return 2 * 2 * np.pi / abs(prediction["precession-rate"])  # two turns about the vertical
        return 3.3 * prediction["nutation-period"]  # three full nutations (four maxima of theta)

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        m = self.motion(model, traj.time, traj.qpos, traj.qvel)
        t = m.time
        e3 = m.e3_W
        theta = np.arctan2(np.hypot(e3[:, 0], e3[:, 1]), e3[:, 2])
        u_dot = np.cross(m.omega_W, e3)[:, 2]
        u = e3[:, 2]
        phi = np.unwrap(np.arctan2(e3[:, 0], -e3[:, 1]))
        phi_dot = (m.omega_W[:, 2] - m.omega_B[:, 2] * u) / (1 - u * u)
        # theta is largest where u is smallest: minima of u are the zero crossings of u_dot going up.
        t_max, theta_max = signals.extrema(t, theta, -u_dot, "max")
        t_min, theta_min = signals.extrema(t, theta, -u_dot, "min")
        out = {
            "theta-max": _worst(theta_max, prediction["theta-max"]),
            "theta-min": _worst(
                np.concatenate([theta_min, [theta[0]] if traj.qvel[0, 0] == 0 else []]), prediction["theta-min"]
            ),
            "nutation-period": signals.mean_spacing(t_max),
            "mean-precession": float(np.diff(signals.interpolate(t, phi, t_max[[0, -1]]))[0] / (t_max[-1] - t_max[0]))
            if len(t_max) >= 2
            else float("nan"),
            "precession-at-theta-min": _worst(
                signals.interpolate(t, phi_dot, t_min), prediction["precession-at-theta-min"]
            ),
            "precession-at-theta-max": _worst(
                signals.interpolate(t, phi_dot, t_max), prediction["precession-at-theta-max"]
            ),
            "tilt-deviation": float(np.abs(theta - prediction["_tilt0"]).max()),
            "precession-rate": signals.phase_rate(t, phi),
            "energy-drift": signals.max_relative_drift(m.kinetic_energy + self._mgh(model) * u),
            "p-phi-drift": float(np.abs(m.L_W[:, 2] - m.L_W[0, 2]).max() / np.linalg.norm(m.L_W[0])),
            "p-psi-drift": signals.max_relative_drift(m.L_B[:, 2]),
        }
        if "tilt-growth-rate" in prediction:
            out["tilt-growth-rate"] = self._growth(t, theta, prediction["_tilt0"])
        else:
            out["max-tilt-linear"] = float(theta_max.max()) if len(theta_max) else float("nan")
        return out

    @staticmethod
    def _mgh(model: mujoco.MjModel) -> float:
        body = model.body("top")
        return float(body.mass[0] * -model.opt.gravity[2] * body.ipos[2])

    @staticmethod
    def _growth(t: np.ndarray, theta: np.ndarray, theta0: float) -> float:
        """Least-squares slope of ln(theta) over theta in [20, 100] theta0, on the first rise."""
        beyond = theta > 100 * theta0
        if not beyond.any():
            return float("nan")
        rise = slice(0, int(np.argmax(beyond)))  # up to the first time theta leaves the window
        window = theta[rise] >= 20 * theta0
        if np.count_nonzero(window) < 3:
            return float("nan")
        return float(np.polyfit(t[rise][window], np.log(theta[rise][window]), 1)[0])


def _worst(values: np.ndarray, expected: float) -> float:
    """The measured value farthest from the prediction (NaN if there is none)."""
    values = np.asarray(values, dtype=float)
    return float(values[np.argmax(np.abs(values - expected))]) if values.size else float("nan")


class HeavyTopEnv(RotorEnv):
    """``rigidbench/HeavyTop-v0``: the heavy symmetric top on a pivot, scored against theory every step.

    Description
        A symmetric top on a frictionless ball-joint pivot at the origin, under gravity. With zero action it
        is the Lagrange top (THEORY.md T1-T7): theta(t) follows u = cos(theta) = u1 + (u2 - u1) sn^2(nu t, k).

    Observation Space
        See `RotorEnv`: body-to-world quaternion of the ball joint (4) and body-frame angular velocity (3,
        rad/s). theta = arccos of the quaternion's rotated body z-axis, z component.

    Action Space
        Box(-0.05, 0.05, (3,)), float64: torque on the top in world axes (N m), through ``xfrc_applied``;
        out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|theta - theta_theory(t)| / pi``: the negative deviation of the tilt from the closed form,
        normalised by pi; ``info["measured"]["theta"]`` and ``info["predicted"]["theta"]`` hold both (rad).

    Starting State
        Tilt ``tilt`` from the upward vertical, rates (nutation_rate, precession sin(tilt), spin) in body axes.

    Episode End
        Truncated after 3.3 nutation periods (two precession turns if steady); terminated on divergence.

    Arguments
        ``case`` (nutation, looping, slow-precession, fast-precession, sleeping, falling), ``params`` (mass, arm,
        I1, I3, tilt, spin, precession, nutation_rate, g), ``profile``, ``integrator``, ``timestep``,
        ``frame_skip`` (default 10, i.e. 1 ms), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = HeavyTop
    max_torque = 0.05

    observables = ("theta",)

    def _theory(self, t: np.ndarray) -> np.ndarray:
        top = self.prediction["_theory"]
        return top.theta_at_w(top.w(t))[:, None]

    def _measure(self, obs: np.ndarray) -> tuple[float]:
        # body z-axis in the world: e3 = (2(xz + wy), 2(yz - wx), 1 - 2(x^2 + y^2)) for a unit quaternion,
        # so sin(theta) = |(e3x, e3y)| = 2 sqrt((x^2 + y^2)(w^2 + z^2)).
        w, x, y, z = obs[:4].tolist()
        r2 = x * x + y * y
        return (math.atan2(2.0 * math.sqrt(r2 * (w * w + z * z)), 1.0 - 2.0 * r2),)

    def _deviation(self, measured: tuple[float], predicted: np.ndarray) -> float:
        return abs(measured[0] - float(predicted[0])) / math.pi
