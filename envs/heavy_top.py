"""Heavy symmetric top on a fixed frictionless pivot (Lagrange top): the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md T1-T7 (Wilcox Part II section 11.10, eqs 11.52-11.62; prob. 11.13, 11.18), implemented in
`rigidbench.analytic.heavy_top`. Model: ``models/heavy_top.xml`` (a ball joint at the world origin; body z is the
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
from rigidbench.analytic import heavy_top as theory
from rigidbench.analytic.heavy_top import (  # noqa: F401 (their old import path)
    RK4_TARGET,
    SPIN_TURN,
    UNWRAP_TURN,
    Scales,
    momentum_scale,
    scales,
)
from rigidbench.contract import Case, Check, Derived, Scenario, Trajectory
from rigidbench.envs.heavy_top_domain import (  # noqa: F401 (public names keep their old import path)
    _AT_REST,
    _FAST_SPIN,
    _OFF_VERTICAL,
    _OFF_VERTICAL_WHY,
    _STEADY_SPIN,
    _ZERO,
    DOMAINS,
    FALL_NUTATIONS,
    FALLING_TILT,
    FAST_TILT,
    LINEAR_ERROR,
    MAX_STEPS,
    MIN_ADVANCE,
    OMEGA_C_MAX,
    RATE_RANGE,
    RHO_MAX,
    RUN_NUTATIONS,
    SIGMA_MIN,
    SLEEPING_TILT,
    THETA_FLOOR,
    Plan,
    _pivot_inertia,
    _plan_or_none,
    _spin_bound,
    _steady,
    _threshold,
    closed_form,
    plan,
    reference_run,
)
from rigidbench.envs.rotor import RotorEnv, RotorMotion, require_rigid_body_inertia
from rigidbench.params import BodyComOffset, BodyInertia, BodyMass, Bound, Gravity, Numeric, Param, Range

_RK4 = (
    "RK4 with the step of reference_settings: drift of L and E <= r Omega T (Omega h)^4 / 120 <= 4e-9, errors of "
    "theta and phi of the same order; Omega h <= 0.0188, events cubic-interpolated to ~(Omega h)^4 / 384 <~ 3e-10"
)
_EXTREMA = (
    " (the axis at each extremum of theta, at the zero crossings of u_dot, its components cubic-interpolated: an "
    "absolute error ~(Omega h)^4 / 384 rad, also where the axis passes near the vertical and theta(t) has a corner)"
)
_DRIFT = (
    "RK4 is not symplectic: drift <= r Omega T (Omega h)^4 / 120 <= 4e-9 at the reference step (the rule above; "
    "measured <= 0.09 of the bound), round-off <~ 1e-13 over <= 1e6 steps; 1e-8 leaves a factor 2.5 over the bound"
)
_LINEAR = (
    "linearised in theta (T6): relative error 0.147 theta0^2 at 1.5x the threshold spin, <= 1e-4 in the case's "
    "regime (theta0 <= 0.026 rad; the domain 'linear-max-tilt' computes it exactly from the cubic T2)"
)


CHECKS = (
    Check(
        "theta-min",
        "rad",
        1e-6,
        "rel",
        _RK4 + _EXTREMA + "; relative to max(theta_min, 1e-3 rad): near the vertical theta_min is the axis' distance "
        "from it, known to the axis' absolute accuracy (Omega h)^4 / 384 <= 3.3e-10 rad, a third of 1e-6 x 1e-3 rad",
        "T2: theta_min = arccos(u2), roots of the cubic f(u)",
    ),
    Check("theta-max", "rad", 1e-6, "rel", _RK4 + _EXTREMA, "T2: theta_max = arccos(u1), roots of the cubic f(u)"),
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
        _RK4 + " (phi advance between the first and last theta maxima: the azimuth of the axis at each maximum, "
        "cubic-interpolated, its whole turns in between counted from the prediction, which only an error over "
        "pi rad per nutation could miscount)",
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
        _LINEAR,
        "T6: theta_max = theta0 I3 omega3 / sqrt(I3^2 omega3^2 - 4 I1 M g h) (sleeping top, Wilcox prob. 11.13)",
    ),
    Check(
        "tilt-growth-rate",
        "1/s",
        1e-3,
        "rel",
        "slope of ln(theta) fitted over theta in [20, 100] theta0 (theta0 <= 1e-4 rad): the decaying mode "
        "biases it by ~2 e^(-2 gamma t) <= 1e-3 at the window's start, 2.2e-4 measured at |spin| = 0.5x the "
        "threshold (less below; domain 'falling'); nonlinear terms O(theta^2) <= (100 theta0)^2 <= 1e-4",
        "T6: gamma = sqrt(4 I1 M g h - I3^2 omega3^2) / (2 I1); linearised theta = theta0 "
        "sqrt(cosh^2(gamma t) + (a/2 gamma)^2 sinh^2(gamma t))",
    ),
    Check(
        "energy-drift",
        "1",
        1e-8,
        "abs",
        _DRIFT + " (max |E(t) - E(0)| relative to E_scale = E_kin(0) + M g h, defined for any E(0))",
        "T1: E conserved (frictionless pivot)",
    ),
    Check(
        "p-phi-drift",
        "1",
        1e-8,
        "abs",
        _DRIFT + " (relative to L_scale = sqrt(|L(0)|^2 + 2 I1 M g h), defined for a top released at rest)",
        "T1: p_phi = L_z conserved, eq. 11.61",
    ),
    Check(
        "p-psi-drift",
        "1",
        1e-8,
        "abs",
        _DRIFT + " (relative to L_scale, as p-phi-drift)",
        "T1: p_psi = I3 omega3 conserved, eq. 11.62",
        identity=True,
    ),
)
_CONSERVED = ("energy-drift", "p-phi-drift", "p-psi-drift")
_NUTATION = ("theta-min", "theta-max", "nutation-period", "mean-precession", *_CONSERVED)
_STEADY = ("tilt-deviation", "precession-rate", *_CONSERVED)


class HeavyTop(Scenario):
    """A symmetric top on a fixed pivot under gravity: nutation between the roots of a cubic, steady
    precession, the sleeping top and its threshold (docs/theory.md T1-T7)."""

    slug = "heavy-top"
    title = "Heavy symmetric top on a fixed pivot (Lagrange top)"
    env_id = "rigidbench/HeavyTop-v0"
    params = (
        Param(
            "mass",
            "kg",
            "mass of the top (three decades below the default 0.1 kg, four above)",
            Range(1e-4, 1e3),
            BodyMass("top"),
        ),
        Param(
            "I1",
            "kg m^2",
            "transverse principal moment about the CM (the theory adds M arm^2 for the pivot)",
            Range(1e-7, 1e3),
            BodyInertia("top", (0, 1)),
        ),
        Param(
            "arm",
            "m",
            "distance h from the pivot to the CM along the symmetry axis; at most sqrt(199 I1 / mass), so that "
            f"I3 can reach (I1 + mass arm^2) / {RHO_MAX:g} (a top, not a spinning pendulum)",
            Range(1e-4, 10.0),
            BodyComOffset("top", 2),
            within=Bound(
                f"[1e-4, sqrt({2 * RHO_MAX - 1:g} I1 / mass)]",
                lambda p: Range(1e-4, math.sqrt((2 * RHO_MAX - 1) * p["I1"] / p["mass"])),
                ("I1", "mass"),
            ),
        ),
        Param(
            "I3",
            "kg m^2",
            "principal moment about the symmetry axis; between (I1 + mass arm^2) / 100 (see arm) and 2 I1",
            Range(1e-11, 2e3),
            BodyInertia("top", (2,)),
            within=Bound(
                f"[(I1 + mass arm^2) / {RHO_MAX:g}, 2 I1] (the triangle inequality I3 <= I1 + I2 of every rigid "
                "body; the pivot inertia at most 100 I3)",
                lambda p: Range(_pivot_inertia(p) / RHO_MAX, 2 * p["I1"]),
                ("I1", "mass", "arm"),
            ),
        ),
        Param(
            "tilt",
            "rad",
            "initial angle theta0 of the symmetry axis from the upward vertical",
            Range(1e-6, np.pi - 1e-6),
            Numeric("tilt"),
        ),
        Param(
            "g",
            "m/s^2",
            f"gravitational acceleration (along -z); at most what puts the T6 threshold omega_c at {OMEGA_C_MAX:g} "
            "rad/s, so that the top's rates (up to ~1e6 rad/s, see spin) fit their ranges",
            Range(1e-2, 1e3),
            Gravity(),
            within=Bound(
                f"[1e-2, g_max], g_max = {OMEGA_C_MAX:g}^2 I3^2 / (4 (I1 + M arm^2) M arm) (omega_c <= "
                f"{OMEGA_C_MAX:g})",
                lambda p: Range(1e-2, OMEGA_C_MAX**2 * p["I3"] ** 2 / (4 * _pivot_inertia(p) * p["mass"] * p["arm"])),
                ("mass", "arm", "I1", "I3"),
            ),
        ),
        Param(
            "spin",
            "rad/s",
            "omega3, angular velocity about the symmetry axis (conserved); at most S = omega_c / sqrt(2 x 3e-5) in "
            "magnitude, omega_c = 2 sqrt(I1 M g h) / I3 the T6 threshold (beta / a^2 >= 3e-5: a faster top's "
            "nutation and precession sink below round-off)",
            RATE_RANGE,
            Numeric("spin"),
            within=Bound(
                "[-S, S], S = omega_c / sqrt(6e-5) (omega_c = 2 sqrt((I1 + M arm^2) M g arm) / I3)",
                lambda p: Range(-_spin_bound(p), _spin_bound(p)),
                ("mass", "arm", "I1", "I3", "g"),
            ),
        ),
        Param(
            "precession",
            "rad/s",
            "initial phi_dot, rate of the axis about the vertical; at most 30 S in magnitude (see spin: the fast "
            "T4 root of fast-precession is below 28.3 S)",
            RATE_RANGE,
            Numeric("precession"),
            within=Bound(
                "[-30 S, 30 S]",
                lambda p: Range(-30 * _spin_bound(p), 30 * _spin_bound(p)),
                ("mass", "arm", "I1", "I3", "g"),
            ),
        ),
        Param(
            "nutation_rate",
            "rad/s",
            "initial theta_dot; at most S in magnitude (see spin)",
            RATE_RANGE,
            Numeric("nutation_rate"),
            within=Bound(
                "[-S, S]",
                lambda p: Range(-_spin_bound(p), _spin_bound(p)),
                ("mass", "arm", "I1", "I3", "g"),
            ),
        ),
    )
    cases = (
        Case(
            "nutation",
            "released with theta_dot = phi_dot = 0 (cusped nutation between the cubic's roots); any initial rates "
            "are covered by T2-T3",
            {"tilt": 0.5, "precession": 0.0, "nutation_rate": 0.0},
            _NUTATION,
            ranges={"tilt": _OFF_VERTICAL},
            regime=_OFF_VERTICAL_WHY,
        ),
        Case(
            "looping",
            "released with phi_dot = minus the gyroscopic rate: phi_dot changes sign (loops)",
            {"tilt": 0.5, "nutation_rate": 0.0, "precession": lambda p: -_steady(p, 0)},
            (*_NUTATION, "precession-at-theta-min", "precession-at-theta-max"),
            ranges={"tilt": _OFF_VERTICAL, "spin": _STEADY_SPIN, "nutation_rate": _ZERO},
            regime="released at rest in theta with phi_dot0 = minus the slow T4 root, which exists for I3^2 omega3^2 "
            ">= 4 I1 M g h cos(theta0) (as slow-precession): the loop between theta0 and theta_max, whose turning "
            "points' phi_dot are checked (a theta_dot0 can carry the axis past the vertical, where phi_dot is "
            f"ill-conditioned; the nutation case takes any); {_OFF_VERTICAL_WHY}",
        ),
        Case(
            "slow-precession",
            "phi_dot at the slow root of T4: theta stays at tilt",
            {"tilt": 0.5, "nutation_rate": 0.0, "precession": lambda p: _steady(p, 0)},
            _STEADY,
            ranges={"nutation_rate": _ZERO, "tilt": _OFF_VERTICAL, "spin": _STEADY_SPIN},
            regime="steady precession starts with theta_dot = 0, and exists above the horizontal only for "
            "I3^2 omega3^2 >= 4 I1 M g h cos(theta0) (T4); a negative spin mirrors the motion (phi_dot -> "
            f"-phi_dot) and is covered by the nutation case; {_OFF_VERTICAL_WHY}",
        ),
        Case(
            "fast-precession",
            "phi_dot at the fast root of T4: theta stays at tilt",
            {"tilt": 0.5, "nutation_rate": 0.0, "precession": lambda p: _steady(p, 1)},
            _STEADY,
            ranges={"nutation_rate": _ZERO, "tilt": Range(_OFF_VERTICAL.low, FAST_TILT), "spin": _FAST_SPIN},
            regime=f"as slow-precession, above the horizontal (theta0 <= {FAST_TILT:g} rad): the fast root "
            "(I3 omega3 + sqrt(D)) / (2 I1 cos(theta0)) grows without bound toward it; spin <= 5e5 I1 cos(theta0) / "
            "I3 keeps the root within 5e5 rad/s",
        ),
        Case(
            "sleeping",
            "nearly upright (0.01 rad) at 1.5x the T6 threshold spin: the tilt stays bounded",
            {"tilt": 0.01, "precession": 0.0, "nutation_rate": 0.0, "spin": lambda p: 1.5 * _threshold(p)},
            (*_NUTATION, "max-tilt-linear"),
            ranges={"tilt": Range(1e-6, SLEEPING_TILT), "precession": _ZERO, "nutation_rate": _ZERO},
            regime=f"{_AT_REST}; theta0 <= {SLEEPING_TILT:g} rad keeps the linearisation's error 0.147 theta0^2 "
            "(at 1.5x the threshold) below 1e-4, a tenth of the max-tilt-linear tolerance",
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
            ranges={"tilt": Range(1e-6, FALLING_TILT), "precession": _ZERO, "nutation_rate": _ZERO},
            regime=f"{_AT_REST}; theta0 <= {FALLING_TILT:g} rad keeps the nonlinear terms (100 theta0)^2 over "
            "the fitted window [20, 100] theta0 below 1e-4",
        ),
    )
    checks = CHECKS
    domains = DOMAINS

    def validate(self, params: Mapping[str, Any]) -> None:
        require_rigid_body_inertia(params["I1"], params["I1"], params["I3"], "I1 = I2, I3 (about the CM)")

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        pl = _plan_or_none(params)
        return {} if pl is None else {"timestep": pl.step}

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        theta = params["tilt"]
        data.qpos[:4] = frames.quat_from_euler_zxz(0.0, theta, 0.0)
        data.qvel[:3] = [params["nutation_rate"], params["precession"] * np.sin(theta), params["spin"]]

    def motion(self, model: mujoco.MjModel, time: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> RotorMotion:
        """The top's motion about the pivot (inertia taken about the pivot, docs/theory.md R4)."""
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
        # From the state, without cancellation (docs/theory.md section 0, eq. 11.38 inverted):
        # sin(theta) = |(R31, R32)|, sin(theta) theta_dot = w1 R32 - w2 R31, sin^2(theta) phi_dot = w1 R31 + w2 R32.
        s = float(np.hypot(R[2, 0], R[2, 1]))
        tilt = float(np.arctan2(s, R[2, 2]))
        tilt_rate = float((w1 * R[2, 1] - w2 * R[2, 0]) / s)
        phi_dot0 = float((w1 * R[2, 0] + w2 * R[2, 1]) / (s * s))
        top = theory.heavy_top(i1, i3, mgh, tilt=tilt, tilt_rate=tilt_rate, precession=phi_dot0, spin=float(spin))
        steady = tilt_rate == 0 and (top.w_roots[0] - top.w_roots[1]) < 1e-12
        transverse0 = float(np.hypot(w1, w2))
        out = {
            "_theory": top,
            "_steady": steady,
            "_run_nutations": reference_run(
                top, i1, i3, mgh, tilt=tilt, tilt_rate=tilt_rate, precession=phi_dot0, spin=float(spin)
            ).duration
            / top.nutation_period,
            "_tilt0": tilt,
            "_energy_scale": 0.5 * float(np.sum(m.inertia_B * m.omega_B[0] ** 2)) + mgh,
            "_momentum_scale": momentum_scale(i1, i3, mgh, transverse0, float(spin)),
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
            "_tolerance": {"theta-min": self.check("theta-min").tolerance * max(1.0, THETA_FLOOR / top.theta_min)},
        }
        if (i3 * spin) ** 2 > 4 * i1 * mgh:
            out["max-tilt-linear"] = theory.sleeping_max_tilt(i1, i3, mgh, spin, tilt)
        else:
            out["tilt-growth-rate"] = theory.falling_growth_rate(i1, i3, mgh, spin)
        if steady:
            slow, fast = theory.steady_precession_rates(i1, i3, mgh, spin, tilt)
            out["precession-rate"] = slow if abs(phi_dot0 - slow) <= abs(phi_dot0 - fast) else fast
        out["_roundoff_scale"] = _roundoff_scales(out, self.duration(out))
        return out

    def duration(self, prediction: Mapping[str, Any]) -> float:
        # Three full nutations (four maxima of theta); for a steady top, three periods of the small nutation about
        # it (T5; the closed form's period at a double root), over which the precession rate is a slope; a falling
        # top whose three would be too long, its first fall (`reference_run`).
        return prediction["_run_nutations"] * prediction["nutation-period"]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        m = self.motion(model, traj.time, traj.qpos, traj.qvel)
        t = m.time
        e3 = m.e3_W
        theta = np.arctan2(np.hypot(e3[:, 0], e3[:, 1]), e3[:, 2])
        u_dot = np.cross(m.omega_W, e3)[:, 2]
        u = e3[:, 2]
        phi = np.unwrap(np.arctan2(e3[:, 0], -e3[:, 1]))
        # sin^2(theta) phi_dot = omega1 R31 + omega2 R32 (docs/theory.md section 0 inverted), free of the cancellation
        # of
        # (omega_z - omega3 u) / (1 - u^2) near the vertical
        R = m.R_WB
        sin2_phi_dot = m.omega_B[:, 0] * R[:, 2, 0] + m.omega_B[:, 1] * R[:, 2, 1]  # smooth, unlike phi_dot
        # theta is largest where u is smallest: minima of u are the zero crossings of u_dot going up. theta at each
        # from the axis' components interpolated there (smooth where theta(t) has a corner, at a pass near a pole).
        t_max = signals.crossings(t, -u_dot, -1)
        t_min = signals.crossings(t, -u_dot, 1)
        axis_max, axis_min = _axis_at(t, e3, t_max), _axis_at(t, e3, t_min)
        theta_max = _polar(axis_max)
        theta_min = _polar(axis_min)
        L_scale = prediction["_momentum_scale"]
        energy = m.kinetic_energy + self._mgh(model) * u
        out = {
            "theta-max": _worst(theta_max, prediction["theta-max"]),
            "theta-min": _worst(
                np.concatenate([theta_min, [theta[0]] if traj.qvel[0, 0] == 0 else []]), prediction["theta-min"]
            ),
            "nutation-period": signals.mean_spacing(t_max),
            "mean-precession": _mean_precession(
                (t_max, axis_max)
                if np.sin(prediction["theta-max"]) >= np.sin(prediction["theta-min"])
                else (t_min, axis_min),
                prediction["mean-precession"],
            ),
            "precession-at-theta-min": _worst(
                _phi_dot_at(t, sin2_phi_dot, t_min, axis_min), prediction["precession-at-theta-min"]
            ),
            "precession-at-theta-max": _worst(
                _phi_dot_at(t, sin2_phi_dot, t_max, axis_max), prediction["precession-at-theta-max"]
            ),
            "tilt-deviation": float(np.abs(theta - prediction["_tilt0"]).max()),
            "precession-rate": signals.phase_rate(t, phi),
            "energy-drift": float(np.abs(energy - energy[0]).max() / prediction["_energy_scale"]),
            "p-phi-drift": float(np.abs(m.L_W[:, 2] - m.L_W[0, 2]).max() / L_scale),
            "p-psi-drift": float(np.abs(m.L_B[:, 2] - m.L_B[0, 2]).max() / L_scale),
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


def _roundoff_scales(prediction: Mapping[str, Any], duration: float) -> dict[str, float]:
    """The float32 round-off scales of the checks (`Scenario.roundoff_scale`), from the closed form
    (`rigidbench.analytic.heavy_top.roundoff_scales`)."""
    return theory.roundoff_scales(
        prediction["_theory"],
        duration=duration,
        nutations=prediction["_run_nutations"],
        precession_rate=prediction["precession-rate"],
        tilt=prediction["_tilt0"],
        falling="tilt-growth-rate" in prediction,
    )


def _axis_at(t: np.ndarray, e3_W: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The axis e3 (world) at times `at`, each component cubic-interpolated, shape (len(at), 3)."""
    if len(at) == 0:
        return np.zeros((0, 3))
    return np.stack([signals.interpolate(t, e3_W[:, i], at) for i in range(3)], axis=-1)


def _phi_dot_at(t: np.ndarray, sin2_phi_dot: np.ndarray, at: np.ndarray, axis_W: np.ndarray) -> np.ndarray:
    """phi_dot (rad/s) at times `at`: sin^2(theta) phi_dot (smooth) interpolated, over sin^2(theta) of the axes
    there."""
    if len(at) == 0:
        return np.zeros(0)
    return signals.interpolate(t, sin2_phi_dot, at) / (axis_W[:, 0] ** 2 + axis_W[:, 1] ** 2)


def _polar(axis_W: np.ndarray) -> np.ndarray:
    """theta (rad) of axes (n, 3), from the upward vertical, free of cancellation near either pole."""
    return np.arctan2(np.hypot(axis_W[:, 0], axis_W[:, 1]), axis_W[:, 2])


def _mean_precession(extremes: tuple[np.ndarray, np.ndarray], predicted: float) -> float:
    """Mean phi_dot (rad/s) between the first and last of a family of extremes of theta (times, axes there): the
    azimuth of the axis at each, and the whole turns between consecutive ones counted from the `predicted` rate
    (the azimuth whirls where the axis passes near a pole, and sampled phi cannot be unwrapped there). The family
    farther from its pole is used (its azimuth the better defined)."""
    t_ext, axis = extremes
    if len(t_ext) < 2:
        return float("nan")
    az = np.arctan2(axis[:, 0], -axis[:, 1])
    step = np.diff(az)
    expected = predicted * np.diff(t_ext)
    step += 2 * np.pi * np.round((expected - step) / (2 * np.pi))
    return float(step.sum() / (t_ext[-1] - t_ext[0]))


def _worst(values: np.ndarray, expected: float) -> float:
    """The measured value farthest from the prediction (NaN if there is none)."""
    values = np.asarray(values, dtype=float)
    return float(values[np.argmax(np.abs(values - expected))]) if values.size else float("nan")


class HeavyTopEnv(RotorEnv):
    """``rigidbench/HeavyTop-v0``: the heavy symmetric top on a pivot, scored against theory every step.

    Description
        A symmetric top on a frictionless ball-joint pivot at the origin, under gravity. With zero action it
        is the Lagrange top (docs/theory.md T1-T7): theta(t) follows u = cos(theta) = u1 + (u2 - u1) sn^2(nu t, k).

    Observation Space
        See `RotorEnv`: body-to-world quaternion of the ball joint (4) and body-frame angular velocity (3,
        rad/s). theta = arccos of the quaternion's rotated body z-axis, z component.

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = 0.05`` N m times it is a torque on the top in
        world axes, through ``xfrc_applied``;
        out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|theta - theta_theory(t)| / pi``: the negative deviation of the tilt from the closed form,
        normalised by pi; ``info["measured"]["theta"]`` and ``info["predicted"]["theta"]`` hold both (rad).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        Tilt ``tilt`` from the upward vertical, rates (nutation_rate, precession sin(tilt), spin) in body axes.

    Episode End
        Truncated after 3.3 nutation periods (of the small nutation about it, T5, if steady; the first fall, 0.6
        periods, for a falling top whose three would exceed 1e6 steps); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (nutation, looping, slow-precession, fast-precession, sleeping, falling), ``params`` (mass, arm,
        I1, I3, tilt, spin, precession, nutation_rate, g), ``profile``, ``integrator``, ``timestep``,
        ``frame_skip`` (default 10: 1 ms at the default cases; the reference timestep follows the parameters, see
        `HeavyTop.reference_settings`), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = HeavyTop
    max_torque = 0.05

    observables = ("theta",)

    def theory(self, t: np.ndarray) -> np.ndarray:
        top = self.prediction["_theory"]
        return top.theta_at_w(top.w(t))[:, None]

    def measured(self, obs: np.ndarray) -> tuple[float]:
        # body z-axis in the world: e3 = (2(xz + wy), 2(yz - wx), 1 - 2(x^2 + y^2)) for a unit quaternion,
        # so sin(theta) = |(e3x, e3y)| = 2 sqrt((x^2 + y^2)(w^2 + z^2)).
        w, x, y, z = obs[:4].tolist()
        r2 = x * x + y * y
        return (math.atan2(2.0 * math.sqrt(r2 * (w * w + z * z)), 1.0 - 2.0 * r2),)

    def deviation(self, measured: tuple[float], predicted: np.ndarray) -> float:
        return abs(measured[0] - float(predicted[0])) / math.pi

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        w, x, y, z = obs[:, :4].T
        r2 = x * x + y * y
        # math.atan2 per copy, as `measured` takes it (numpy's SIMD arctan2 may round the last bit otherwise)
        sin_theta, cos_theta = 2.0 * np.sqrt(r2 * (w * w + z * z)), 1.0 - 2.0 * r2
        return np.array(list(map(math.atan2, sin_theta.tolist(), cos_theta.tolist())))[:, None]

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        return np.abs(measured[:, 0] - predicted[:, 0]) / math.pi
