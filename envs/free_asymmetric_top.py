"""Torque-free asymmetric top (I1 < I2 < I3): the MuJoCo side of the scenario, and its gymnasium environment.

Theory: THEORY.md A1-A5 (Jacobi elliptic solution of Euler's equations; Harter & Kim, Am. J. Phys. 44, 1080
(1976), eqs 10-18, reproduced in seed 001), implemented in `rigidbench.analytic.tops.asymmetric_top`.
Model: ``models/free_asymmetric_top.xml``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import signals
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

_RK4 = "RK4 at dt = 1e-4 s: global error ~ |omega| T (|omega| dt)^4 ~ 1e-11 over ~30 s; 1e-8 leaves 3 decades"
_FLIP = (
    "as omega-body; the crossing times are cubic-interpolated (error O(dt^4)); near the separatrix a phase "
    "error grows like exp(lambda t), still << 1e-8 here"
)

CHECKS = (
    Check(
        "omega-body",
        "1",
        1e-8,
        "abs",
        _RK4 + " (max |omega(t) - omega_theory(t)| / |omega| over the run)",
        "A2: Jacobi elliptic solution (cn, sn, dn), THEORY.md; Harter & Kim eqs 10-16",
    ),
    Check(
        "period",
        "s",
        1e-8,
        "rel",
        _RK4 + " (mean spacing of upward zero crossings of omega2)",
        "A2: omega2 = A2 sn(s t + tau0, k) has period 4 K(k) / s",
    ),
    Check(
        "flip-time",
        "s",
        1e-8,
        "rel",
        _FLIP,
        "A3: reversal time 2 K(k) / s, Harter & Kim eq. 17b (as read in THEORY.md A3)",
    ),
    Check(
        "energy-drift",
        "1",
        1e-9,
        "abs",
        "RK4 is not symplectic: drift ~ T |omega| (|omega| dt)^4 ~ 1e-11 at reference; 1e-9 is 2 decades above",
        "A1: torque-free, E conserved",
    ),
    Check(
        "momentum-drift",
        "1",
        1e-9,
        "abs",
        "as energy-drift, for max |L_W(t) - L_W(0)| / |L|",
        "A1: torque-free, L_W conserved",
    ),
)
_COMMON = ("omega-body", "period", "energy-drift", "momentum-drift")


class FreeAsymmetricTop(Scenario):
    """A free rigid body with three different principal moments: stable spins about the largest and smallest
    axes, and the intermediate-axis flip (tennis-racket effect), against the exact elliptic solution."""

    slug = "free-asymmetric-top"
    title = "Torque-free asymmetric top (stable axes and the intermediate-axis flip)"
    env_id = "rigidbench/FreeAsymmetricTop-v0"
    params = (
        Param(
            "I1", "kg m^2", "smallest principal moment about the CM (body x)", positive(1e3), BodyInertia("top", (0,))
        ),
        Param(
            "I2",
            "kg m^2",
            "intermediate principal moment about the CM (body y)",
            positive(1e3),
            BodyInertia("top", (1,)),
        ),
        Param(
            "I3", "kg m^2", "largest principal moment about the CM (body z)", positive(1e3), BodyInertia("top", (2,))
        ),
        OMEGA_PARAM,
    )
    cases = (
        Case(
            "major-axis",
            "spin slightly off the largest axis (3): stable, the polhode circles axis 3",
            {"omega": (0.05, 0.1, 3.0)},
            _COMMON,
        ),
        Case(
            "minor-axis",
            "spin slightly off the smallest axis (1): stable, the polhode circles axis 1",
            {"omega": (3.0, 0.1, 0.05)},
            _COMMON,
        ),
        Case(
            "intermediate-axis",
            "omega = W (0, cos eps, sin eps), W = 3 rad/s, eps = 0.02 rad: the body flips over every 2 K / s",
            {"omega": (0.0, 3.0 * np.cos(0.02), 3.0 * np.sin(0.02))},
            (*_COMMON, "flip-time"),
        ),
    )
    checks = CHECKS

    def validate(self, params: Mapping[str, Any]) -> None:
        i1, i2, i3 = params["I1"], params["I2"], params["I3"]
        if not i1 < i2 < i3:
            raise ValueError(
                f"parameters I1 = {i1:g}, I2 = {i2:g}, I3 = {i3:g} kg m^2 must satisfy I1 < I2 < I3 "
                "(use free-symmetric-top for two equal moments)"
            )
        require_rigid_body_inertia(i1, i2, i3)
        w = np.asarray(params["omega"])
        inertia = np.array([i1, i2, i3])
        two_e, l2 = np.sum(inertia * w**2), np.sum((inertia * w) ** 2)
        if not np.any(w):
            raise ValueError("parameter 'omega' = 0,0,0 rad/s: the body must turn")
        if abs(l2 - two_e * i2) <= 1e-9 * l2:
            raise ValueError(
                f"parameter 'omega' = {','.join(f'{x:g}' for x in w)} rad/s lies on the separatrix L^2 = 2 E I2 "
                "(infinite period): tilt it off the intermediate axis"
            )

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        set_free_body_rotation(data, params["omega"])

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        motion = free_body_motion(model, np.array([data.time]), data.qpos[None], data.qvel[None])
        top = tops.asymmetric_top(tuple(motion.inertia_B), motion.omega_B[0])
        return {
            "_theory": top,
            "omega-body": 0.0,
            "period": top.period,
            "flip-time": top.reversal_time,
            "energy-drift": 0.0,
            "momentum-drift": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return 2.6 * prediction["_theory"].period  # at least two full periods of omega2, i.e. five flips

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        top = prediction["_theory"]
        m = free_body_motion(model, traj.time, traj.qpos, traj.qvel)
        w2 = m.omega_B[:, 1]
        up = signals.crossings(m.time, w2, direction=1)
        every = signals.crossings(m.time, w2)
        return {
            "omega-body": float(np.abs(m.omega_B - top.omega_body(m.time)).max() / np.linalg.norm(m.omega_B[0])),
            "period": signals.mean_spacing(up),
            "flip-time": signals.mean_spacing(every),
            "energy-drift": signals.max_relative_drift(m.kinetic_energy),
            "momentum-drift": signals.max_relative_drift(m.L_W),
        }


class FreeAsymmetricTopEnv(FreeRotorEnv):
    """``rigidbench/FreeAsymmetricTop-v0``: the torque-free asymmetric top, scored against theory every step.

    Description
        A free rigid body with I1 < I2 < I3 (about its CM) and no gravity. With zero action it is Euler's
        torque-free top, solved exactly by Jacobi elliptic functions (THEORY.md A2); the ``intermediate-axis``
        case shows the flip (A3).

    Observation Space
        See `RotorEnv`: body-to-world quaternion (4) and body-frame angular velocity (3, rad/s).

    Action Space
        Box(-1, 1, (3,)), float64: torque on the body in world axes (N m), through ``xfrc_applied``; clipped.

    Rewards
        ``reward = -|omega_B - omega_theory(t)| / |omega_theory(t)|`` (see ``info["reward_deviation"]``).

    Starting State
        The case's (or given) ``omega`` in body axes, body unrotated. Deterministic.

    Episode End
        Truncated after 2.6 periods of omega2 (the validation run's duration); terminated on divergence.

    Arguments
        ``case`` (``major-axis``, ``minor-axis``, ``intermediate-axis``), ``params`` (``I1``, ``I2``, ``I3``,
        ``omega``), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = FreeAsymmetricTop
