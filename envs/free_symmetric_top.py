"""Torque-free symmetric top: the MuJoCo side of the scenario, and its gymnasium environment.

Theory: THEORY.md S1-S4 (Wilcox Part II section 11.9, eqs 11.41-11.51), implemented in
`rigidbench.analytic.tops.symmetric_top`. Model: ``models/free_symmetric_top.xml``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import frames, signals
from rigidbench.analytic import tops
from rigidbench.envs.rotor import (
    OMEGA_PARAM,
    FreeRotorEnv,
    free_body_motion,
    require_rigid_body_inertia,
    set_free_body_rotation,
)
from rigidbench.params import BodyInertia, Param, positive
from rigidbench.scenario import Case, Check, Scenario
from rigidbench.simulate import Trajectory

# Reference settings (models/free_symmetric_top.xml): RK4, dt = 1e-4 s, |omega| <= ~5 rad/s, runs of ~15 s.
# RK4's global error ~ |omega| T (|omega| dt)^4 ~ 5e-12 relative; round-off over ~1.5e5 steps adds ~1e-12.
_RK4 = "RK4 at dt = 1e-4 s: global error ~ |omega| T (|omega| dt)^4 ~ 1e-11; 1e-8 leaves 3 decades of margin"

CHECKS = (
    Check(
        "omega-body",
        "1",
        1e-8,
        "abs",
        _RK4 + " (max |omega(t) - omega_theory(t)| / |omega| over the run)",
        "S1: omega1 + i omega2 = A exp(i (Omega_b t + delta)), Wilcox eqs 11.41-11.42",
    ),
    Check(
        "body-rate",
        "rad/s",
        1e-8,
        "rel",
        _RK4 + " (slope of the unwrapped body-frame phase of omega)",
        "S1: Omega_b = (I3 - I1) omega3 / I1, Wilcox eq. 11.42",
    ),
    Check(
        "precession-rate",
        "rad/s",
        1e-8,
        "rel",
        _RK4 + " (slope of the azimuth of e3 about L)",
        "S3: phi_dot = |L| / I1, Wilcox eqs 11.46-11.51 (signs restored)",
    ),
    Check(
        "spin-rate",
        "rad/s",
        1e-8,
        "rel",
        _RK4 + " (slope of psi with space z along L)",
        "S3: psi_dot = -Omega_b = (I1 - I3) omega3 / I1",
    ),
    Check(
        "cone-beta",
        "rad",
        1e-8,
        "abs",
        _RK4 + " (max over the run of |angle(L, e3) - beta|)",
        "S2: tan beta = I1 A / (I3 omega3), Wilcox eq. 11.44",
    ),
    Check(
        "cone-alpha",
        "rad",
        1e-8,
        "abs",
        _RK4 + " (max over the run of |angle(omega, e3) - alpha|)",
        "S2: tan alpha = A / omega3, Wilcox eq. 11.43",
    ),
    Check(
        "space-cone",
        "rad",
        1e-8,
        "abs",
        _RK4 + " (max over the run of |angle(omega, L) - |beta - alpha||)",
        "S4: the body cone rolls on the space cone of half-angle |beta - alpha|",
    ),
    Check(
        "energy-drift",
        "1",
        1e-9,
        "abs",
        "RK4 is not symplectic: drift ~ T |omega| (|omega| dt)^4 ~ 1e-11 at reference; 1e-9 is 2 decades above",
        "R2/R7: torque-free, E conserved",
    ),
    Check(
        "momentum-drift",
        "1",
        1e-9,
        "abs",
        "as energy-drift, for max |L_W(t) - L_W(0)| / |L|",
        "R7: torque-free, L_W conserved",
    ),
)
_ALL = tuple(c.name for c in CHECKS)


class FreeSymmetricTop(Scenario):
    """A free rigid body with I1 = I2 spinning with no torque: omega precesses about the symmetry axis in the
    body frame at Omega_b, and the symmetry axis precesses about L in space at |L|/I1 (THEORY.md S1-S4)."""

    slug = "free-symmetric-top"
    title = "Torque-free symmetric top (prolate and oblate)"
    env_id = "rigidbench/FreeSymmetricTop-v0"
    params = (
        Param(
            "I1",
            "kg m^2",
            "transverse principal moment I1 = I2 about the CM",
            positive(1e3),
            BodyInertia("top", (0, 1)),
        ),
        Param(
            "I3",
            "kg m^2",
            "principal moment about the symmetry axis (body z), about the CM",
            positive(1e3),
            BodyInertia("top", (2,)),
        ),
        OMEGA_PARAM,
    )
    cases = (
        Case(
            "prolate",
            "I3 < I1 (a cigar): omega circles e3 clockwise seen from +e3; beta > alpha",
            {"I1": 2.0, "I3": 0.8, "omega": (0.3, 0.2, 5.0)},
            _ALL,
        ),
        Case(
            "oblate",
            "I3 > I1 (a disc): omega circles e3 counter-clockwise; beta < alpha",
            {"I1": 1.0, "I3": 1.7, "omega": (0.3, 0.2, 5.0)},
            _ALL,
        ),
    )
    checks = CHECKS

    def validate(self, params: Mapping[str, Any]) -> None:
        i1, i3 = params["I1"], params["I3"]
        require_rigid_body_inertia(i1, i1, i3, "I1 = I2, I3")
        if abs(i3 - i1) <= 1e-9 * i1:
            raise ValueError(f"parameters I1 = I3 = {i1:g} kg m^2: a spherical top has no precession to measure")
        w1, w2, w3 = params["omega"]
        if np.hypot(w1, w2) < 1e-6 * max(abs(w3), 1e-300) or w3 == 0:
            raise ValueError(
                f"parameter 'omega' = {w1:g},{w2:g},{w3:g} rad/s: needs a nonzero spin omega3 and a transverse "
                "part (omega1, omega2) of at least 1e-6 |omega3|, or there is no precession to measure"
            )

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        set_free_body_rotation(data, params["omega"])

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        motion = free_body_motion(model, np.array([data.time]), data.qpos[None], data.qvel[None])
        i1, _, i3 = motion.inertia_B
        top = tops.symmetric_top(i1, i3, motion.omega_B[0])
        return {
            "_theory": top,
            "omega-body": 0.0,
            "body-rate": top.body_rate,
            "precession-rate": top.precession_rate,
            "spin-rate": top.spin_rate,
            "cone-beta": 0.0,
            "cone-alpha": 0.0,
            "space-cone": 0.0,
            "energy-drift": 0.0,
            "momentum-drift": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        top = prediction["_theory"]
        slowest = min(abs(top.body_rate), top.precession_rate)
        # Five turns of the slower precession, at most 20 s: the rates are slopes of unwrapped phases and
        # need no whole turns, and a slow precession (omega3 -> 0) must not cost millions of steps.
        return min(5 * 2 * np.pi / slowest, 20.0)

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        top = prediction["_theory"]
        m = free_body_motion(model, traj.time, traj.qpos, traj.qvel)
        t = m.time
        w = m.omega_B
        L0 = m.L_W[0]
        L_hat = L0 / np.linalg.norm(L0)
        # psi with space z along L: rotate the world so L is z, then psi = atan2(R31, R32) (THEORY.md section 0)
        u = np.cross(L_hat, np.eye(3)[np.argmin(np.abs(L_hat))])
        u /= np.linalg.norm(u)
        basis = np.stack([u, np.cross(L_hat, u), L_hat])  # rows: new x, y, z in world coordinates
        R_LB = basis @ m.R_WB
        beta = frames.angle_between(m.L_W, m.e3_W)
        alpha = frames.angle_between(m.omega_W, m.e3_W)
        space = frames.angle_between(m.omega_W, m.L_W)
        scale = float(np.linalg.norm(w[0]))
        return {
            "omega-body": float(np.abs(w - top.omega_body(t)).max() / scale),
            "body-rate": signals.phase_rate(t, np.arctan2(w[:, 1], w[:, 0])),
            "precession-rate": signals.phase_rate(t, frames.azimuth_about(L_hat, m.e3_W)),
            "spin-rate": signals.phase_rate(t, np.arctan2(R_LB[:, 2, 0], R_LB[:, 2, 1])),
            "cone-beta": float(np.abs(beta - top.beta).max()),
            "cone-alpha": float(np.abs(alpha - top.alpha).max()),
            "space-cone": float(np.abs(space - abs(top.beta - top.alpha)).max()),
            "energy-drift": signals.max_relative_drift(m.kinetic_energy),
            "momentum-drift": signals.max_relative_drift(m.L_W),
        }


class FreeSymmetricTopEnv(FreeRotorEnv):
    """``rigidbench/FreeSymmetricTop-v0``: the torque-free symmetric top, scored against theory every step.

    Description
        A free rigid body with I1 = I2 (about its CM) and no gravity. With zero action it is the textbook
        torque-free symmetric top (THEORY.md S1-S4): omega circles the symmetry axis in the body frame at
        Omega_b = (I3 - I1) omega3 / I1 and the axis precesses about L at |L| / I1.

    Observation Space
        See `RotorEnv`: body-to-world quaternion (4) and body-frame angular velocity (3, rad/s).

    Action Space
        Box(-1, 1, (3,)), float64: torque on the body in world axes (N m), applied through ``xfrc_applied``.
        Out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|omega_B - omega_theory(t)| / |omega_theory(t)|``: the negative relative deviation of the
        body rates from the closed form at the current time; ``info["reward_deviation"]`` holds it, and
        ``info["measured"]`` / ``info["predicted"]`` the two vectors.

    Starting State
        The case's (or the given) ``omega`` in body axes, body unrotated at the origin. Deterministic.

    Episode End
        Truncated after five turns of the slower precession, at most 20 s (the validation run's duration);
        terminated only if the simulation diverges (``info["diverged"] = True``).

    Arguments
        See `ScenarioEnv`: ``case`` (``prolate``, ``oblate``), ``params`` (``I1``, ``I3``, ``omega``),
        ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 1 ms), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = FreeSymmetricTop
