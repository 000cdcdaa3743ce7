"""Bent axle: the bearing torque and force on a rotor turning at constant rate, and its gymnasium env.

Theory: docs/theory.md R8 (seed 001, Harter, Fig. 6.5.1; general form [DONE]), implemented in
`rigidbench.analytic.bent_axle`. Model: ``models/bent_axle.xml`` (a rotor on a hinge about world z through the
origin O; the site ``bearing`` at O carries a ``torque`` and a ``force`` sensor).

How the rate is held. The axle's torque ``N = omega x L`` is perpendicular to omega, so keeping omega constant needs
no torque about the axle: the hinge's equation of motion is ``I_zz theta'' = 0`` and the initial rate is kept by the
physics itself, under any integrator (theta = omega t is integrated exactly by Euler and RK4 alike). That is exact,
unlike a velocity actuator (a servo whose gain and the step's implicitness set how far the rate may wander) or a large
armature (which only slows a drift that is not there, and is not part of the rotor). What is left is round-off:
MuJoCo's bias force about the hinge is zero to ~eps omega^2 |I_O| (measured <= 0.6 eps), so the rate drifts by at most
~eps kappa omega T, kappa = |I_O| / I_zz (domain ``axle-inertia``); the ``axle-rate`` check measures it.

How the reaction is read. A hinge is a degree of freedom, not a constraint: it has no rows in ``efc_force`` and
``qfrc_constraint`` stays 0. What the axle exerts on the rotor is the body's interaction wrench ``cfrc_int`` (computed
by ``mj_rnePostConstraint``, in world axes, about the subtree's centre of mass), which the ``torque`` and ``force``
sensors at a site on the rotor shift to the site and express in its frame: the torque about O and the force that the
parent (the world, through the hinge) exerts on the child (the rotor), in the rotor's axes (measured against R8 and
against ``cfrc_int`` in ``tests/test_bent_axle_mujoco.py``). The scenario evaluates them at every recorded state of
the run with the simulated model (`reactions`), so a power run's perturbed model is what is read.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import frames
from rigidbench.analytic import bent_axle as ba
from rigidbench.contract import Case, Check, Derived, Domain, Scenario, Trajectory, round_step
from rigidbench.envs.base import ScenarioEnv
from rigidbench.envs.rotor import require_rigid_body_inertia
from rigidbench.params import BodyInertia, BodyMass, Bound, Numeric, Param, Range, Value
from rigidbench.simulate import STATE, simulate

# Samples per turn of the reference run: the trajectory is exact at any step (theta'' = 0), so the step only sets
# how densely the turning torque is sampled; 200 a turn (0.031 rad a step) draws it smoothly. Rounded down to one
# digit (`round_step`): 1e-3 s at the default omega = 20 rad/s.
STEPS_PER_TURN = 200
# Turns per run: the torque's rotation rate is the slope of its azimuth over this many turns.
TURNS = 5
# Smallest unbalance u = sqrt(I_xz^2 + I_yz^2) / |I_O| a torque check resolves: the sensor's torque carries
# round-off ~eps omega^2 |I_O| (measured <= 0.8 eps over random rotors), i.e. eps / u relative to |N|; at u >= 1e-5
# that is <= 2.2e-11, a 45th of the 1e-9 tolerances.
MIN_UNBALANCE = 1e-5
# Smallest |rho| / r_g (r_g = sqrt(|I_O| / m), the radius of gyration about O) a force check resolves: the force's
# round-off is ~eps m omega^2 r_g (measured <= 1.2 eps), eps r_g / |rho| relative to m omega^2 rho.
MIN_OFFSET = 1e-5
# Largest kappa = |I_O| / I_zz (the largest moment about O over the moment about the axle): the hinge's bias-force
# round-off ~eps omega^2 |I_O| (measured <= 0.6 eps) accelerates it by eps kappa omega^2, so its rate drifts by
# <= eps kappa omega T = eps kappa 2 pi TURNS = 7e-11 relative at kappa = 1e4 (a rod nearly along the axle has
# kappa -> infinity: nothing holds its rate but the arithmetic).
MAX_KAPPA = 1e4
# The floor of the absolute (normalised) checks: a quantity that is zero in theory, computed from terms of size 1
# in its unit (omega^2 |I_O| or omega^2 sqrt(m |I_O|)), comes out at ~eps (measured <= 1.2 eps over random rotors);
# 1e-13 = 450 eps.
ZERO_FLOOR = 1e-13

_STATE = "the state is exact at any step (theta'' = 0: theta = omega t, theta' = omega), so only round-off remains: "
_TORQUE_RO = (
    "the torque sensor's round-off ~eps omega^2 |I_O| (measured <= 0.8 eps), eps / u <= 2.2e-11 relative at the "
    "unbalance u >= 1e-5 (domain 'resolvable-torque')"
)
_FORCE_RO = (
    "the force sensor's round-off ~eps m omega^2 r_g (measured <= 1.2 eps), eps r_g / |rho| <= 2.2e-11 relative at "
    "|rho| >= 1e-5 r_g (domain 'resolvable-force')"
)
_PHASE = "theta's round-off over <= 1e3 steps of qpos += h qvel, ~n eps theta <= 1e-11 rad"
CHECKS = (
    Check(
        "torque-magnitude",
        "N m",
        1e-9,
        "rel",
        _STATE + _TORQUE_RO + "; 1e-9 leaves >= 45x (max over the run of ||N(t)| - |N||)",
        "R8: |N| = omega^2 sqrt(I_xz^2 + I_yz^2), inertia about O in the rotor's axes",
    ),
    Check(
        "torque-direction",
        "rad",
        1e-9,
        "abs",
        _STATE + _TORQUE_RO + " in angle, plus " + _PHASE + "; 1e-9 leaves >= 30x (max over the run of the angle "
        "between the measured N_W(t) and omega^2 (-I_yz, I_xz, 0) turned by omega t: perpendicular to the axle, "
        "rotating with the rotor)",
        "R8: N = omega x L = omega^2 (-I_yz, I_xz, 0) in the rotor's axes, fixed in the rotor",
    ),
    Check(
        "torque-rate",
        "rad/s",
        1e-9,
        "rel",
        _STATE + "the slope of the torque's unwrapped azimuth over 5 turns carries its angle error (<= 2.2e-11 rad) "
        "over 10 pi rad and theta's round-off (<= 1e-11 rad); 1e-9 leaves >= 30x",
        "R8: N turns with the rotor, at omega",
    ),
    Check(
        "axial-torque",
        "1",
        ZERO_FLOOR,
        "abs",
        _STATE + "the torque about the axle, zero in theory, in units of omega^2 |I_O| (|I_O| its largest moment "
        "about O): round-off of terms of that size, measured <= 0.8 eps; 1e-13 = 450 eps",
        "R8: N = omega x L is perpendicular to omega: the constant rate needs no drive torque",
        identity=True,
    ),
    Check(
        "residual-torque",
        "1",
        ZERO_FLOOR,
        "abs",
        _STATE + "|N| of a balanced rotor, zero in theory, in units of omega^2 |I_O|: round-off of terms of that "
        "size, measured <= 0.8 eps; 1e-13 = 450 eps",
        "R8: principal axis along the axle and CoM on it: L parallel to omega, N = 0",
        identity=True,
    ),
    Check(
        "force-magnitude",
        "N",
        1e-9,
        "rel",
        _STATE + _FORCE_RO + "; 1e-9 leaves >= 45x (max over the run of ||F(t)| - m omega^2 rho|)",
        "R8 note: the rotating net force m omega^2 rho of a CoM off the axle",
    ),
    Check(
        "force-direction",
        "rad",
        1e-9,
        "abs",
        _STATE + _FORCE_RO + " in angle, plus " + _PHASE + "; 1e-9 leaves >= 30x (max over the run of the angle "
        "between the measured F_W(t) and -m omega^2 c_perp turned by omega t: towards the axle, rotating with the "
        "rotor)",
        "R8 note: F = m omega x (omega x c), centripetal, fixed in the rotor",
    ),
    Check(
        "residual-force",
        "1",
        ZERO_FLOOR,
        "abs",
        _STATE + "|F| of a rotor whose CoM is on the axle, zero in theory, in units of omega^2 sqrt(m |I_O|): "
        "round-off of terms of that size, measured <= 1.2 eps; 1e-13 = 450 eps",
        "R8 note: a CoM on the axle does not accelerate: no net bearing force",
        identity=True,
    ),
    Check(
        "axle-rate",
        "rad/s",
        1e-9,
        "rel",
        "no torque about the axle is needed (R8), so the hinge's rate is held by theta'' = 0 under any integrator; "
        "MuJoCo's bias force about the hinge is zero to ~eps omega^2 |I_O| (measured <= 0.6 eps), a drift <= eps "
        "kappa omega T = 7e-11 at kappa <= 1e4 (domain 'axle-inertia'); 1e-9 leaves 14x (max over the run of "
        "|theta'(t) - omega|)",
        "R8: omega constant (the premise; held with no drive, as N . omega = 0)",
        identity=True,
    ),
)
_TORQUE = ("torque-magnitude", "torque-direction", "torque-rate", "axial-torque")


@dataclass(frozen=True)
class BodyTilt:
    """Angle (rad) between a body's principal axis e3 and its z axis, turned about its x axis: the body's inertial
    quaternion ``(cos tilt/2, sin tilt/2, 0, 0)``; a visual geom of the rotor is turned with it."""

    body: str
    geom: str

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        quat = [math.cos(float(value) / 2), math.sin(float(value) / 2), 0.0, 0.0]
        spec.body(self.body).iquat = quat
        spec.geom(self.geom).quat = quat

    def read(self, model: mujoco.MjModel) -> Value:
        w, x, y, z = (float(v) for v in model.body(self.body).iquat)
        if y != 0 or z != 0:
            raise ValueError(f"body '{self.body}': its principal frame is not a turn about x (iquat {w, x, y, z})")
        return 2 * math.atan2(x, w)


@dataclass(frozen=True)
class RotorCom:
    """One coordinate (m) of the rotor's centre of mass in its axes; the visual disc is moved with it."""

    body: str
    geom: str
    axis: int

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        for obj, attr in ((spec.body(self.body), "ipos"), (spec.geom(self.geom), "pos")):
            pos = np.array(getattr(obj, attr), dtype=float)
            pos[self.axis] = float(value)
            setattr(obj, attr, pos)

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.body(self.body).ipos[self.axis])


# ---- the theory's numbers from requested parameters (domains) and from the compiled model (predictions) ----------


def _inertia_O(p: Mapping[str, Any]) -> np.ndarray:
    return ba.inertia_about_point(
        p["mass"],
        np.array([p["I1"], p["I2"], p["I3"]], dtype=float),
        ba.tilted_principal_frame(p["tilt"]),
        np.array([p["com_radial"], 0.0, p["com_axial"]]),
    )


def _largest(inertia: np.ndarray) -> float:
    return float(np.abs(np.linalg.eigvalsh(inertia)).max())


def _resolvable_torque(p: Mapping[str, Any]) -> str | None:
    u = ba.unbalance(_inertia_O(p))
    if u < MIN_UNBALANCE:
        return (
            f"I1, I2, I3 = {p['I1']:.10g}, {p['I2']:.10g}, {p['I3']:.10g} kg m^2, tilt = {p['tilt']:.10g} rad, "
            f"mass = {p['mass']:.10g} kg, com_radial = {p['com_radial']:.10g} m, com_axial = {p['com_axial']:.10g} m "
            f"(unbalance u = {u:.3g})"
        )
    return None


def _resolvable_force(p: Mapping[str, Any]) -> str | None:
    r_g = math.sqrt(_largest(_inertia_O(p)) / p["mass"])
    if abs(p["com_radial"]) < MIN_OFFSET * r_g:
        return f"com_radial = {p['com_radial']:.10g} m (radius of gyration about O r_g = {r_g:.3g} m)"
    return None


def _axle_inertia(p: Mapping[str, Any]) -> str | None:
    inertia = _inertia_O(p)
    kappa = _largest(inertia) / inertia[2, 2]
    if kappa > MAX_KAPPA:
        return (
            f"I1, I2, I3 = {p['I1']:.10g}, {p['I2']:.10g}, {p['I3']:.10g} kg m^2, tilt = {p['tilt']:.10g} rad, "
            f"mass = {p['mass']:.10g} kg, com_radial = {p['com_radial']:.10g} m, com_axial = {p['com_axial']:.10g} m "
            f"(kappa = |I_O| / I_zz = {kappa:.3g})"
        )
    return None


# MuJoCo's compiler marks a body's inertial frame as the body's own (``body_sameframe``) when every coordinate of its
# position is below 1e-6 m and every quaternion component within 1e-6 of the body's, and the engine then simulates
# with the body's frame: the offset or the turn is dropped, though ``body_ipos`` and ``body_iquat`` keep it (measured:
# tilt 1.76e-6 rad, quaternion x = 8.8e-7, gives ximat = identity and a bearing torque missing its -omega^2 I_yz part,
# 8.8e-5 rad off in direction; ipos (9e-7, 0, 0) m gives xipos = 0). Refused with a factor 2 of margin.
SAMEFRAME = 1e-6


def _sameframe(p: Mapping[str, Any]) -> str | None:
    tilt, radial, axial = float(p["tilt"]), float(p["com_radial"]), float(p["com_axial"])
    if tilt != 0 and abs(math.sin(tilt / 2)) < 2 * SAMEFRAME:
        return f"tilt = {tilt:.10g} rad (quaternion component sin(tilt/2) = {math.sin(tilt / 2):.3g})"
    if (radial, axial) != (0.0, 0.0) and max(abs(radial), abs(axial)) < 2 * SAMEFRAME:
        return f"com_radial = {radial:.10g} m, com_axial = {axial:.10g} m"
    return None


DOMAINS = (
    Domain(
        "mujoco-sameframe",
        "R8 (MuJoCo: body_sameframe)",
        "tilt = 0 or |sin(tilt/2)| >= 2e-6 (|tilt| >= 4e-6 rad), and the CoM at O or max(|com_radial|, |com_axial|) "
        ">= 2e-6 m: MuJoCo's compiler takes an inertial frame within 1e-6 of the body's (each quaternion component, "
        "each coordinate in m) for the body's own (body_sameframe) and simulates with it, dropping the tilt or the "
        "offset that body_iquat and body_ipos still hold (an engine limit)",
        _sameframe,
    ),
    Domain(
        "resolvable-torque",
        "R8 (the torque's size against its round-off)",
        f"unbalance u = sqrt(I_xz^2 + I_yz^2) / |I_O| >= {MIN_UNBALANCE:g} (|I_O| the largest moment about O): the "
        "torque sensor's round-off is ~eps omega^2 |I_O|, eps / u of the torque, which must stay well below the 1e-9 "
        "tolerances (a tilt near 0, or I2 = I3, leaves a torque below the arithmetic's resolution: the balanced case "
        "checks that one absolutely)",
        _resolvable_torque,
        ("tilted-disc", "off-axle"),
    ),
    Domain(
        "resolvable-force",
        "R8 note (the force's size against its round-off)",
        f"|com_radial| >= {MIN_OFFSET:g} r_g, r_g = sqrt(|I_O| / m) the radius of gyration about O: the force "
        "sensor's round-off is ~eps m omega^2 r_g, eps r_g / |rho| of the force m omega^2 rho",
        _resolvable_force,
        ("off-axle",),
    ),
    Domain(
        "axle-inertia",
        "R8 (omega held constant by theta'' = 0)",
        f"kappa = |I_O| / I_zz <= {MAX_KAPPA:g}: MuJoCo's bias force about the hinge is zero only to ~eps omega^2 "
        "|I_O|, which accelerates the hinge by eps kappa omega^2 and drifts its rate by eps kappa omega T over the run "
        "(a rotor nearly a rod along the axle, with its CoM far along it, has almost no moment about the axle to hold "
        "its rate)",
        _axle_inertia,
    ),
)


# ---- the run: the trajectory and the reaction at every state ---------------------------------------------------


@dataclass(frozen=True)
class AxleTrajectory(Trajectory):
    """A `Trajectory` with the axle's reaction on the rotor at every state (the site ``bearing``'s sensors).

    Attributes
    ----------
    torque_B : ndarray, shape (n + 1, 3)
        Torque about O that the world, through the hinge, exerts on the rotor, in the rotor's axes (N m).
    force_B : ndarray, shape (n + 1, 3)
        Net force it exerts on the rotor, in the rotor's axes (N).
    """

    torque_B: np.ndarray | None = None
    force_B: np.ndarray | None = None


def sensor_slice(model: mujoco.MjModel, name: str) -> slice:
    """Where sensor `name`'s numbers are in ``sensordata``."""
    s = model.sensor(name)
    return slice(int(s.adr[0]), int(s.adr[0]) + int(s.dim[0]))


def reactions(model: mujoco.MjModel, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bearing torque and force (each (n, 3), rotor axes) at full-physics `states` (n, nstate) of `model`:
    ``mj_forward`` at each (the sensors' acceleration stage runs ``mj_rnePostConstraint``)."""
    data = mujoco.MjData(model)
    torque, force = sensor_slice(model, "bearing-torque"), sensor_slice(model, "bearing-force")
    out_t, out_f = np.empty((len(states), 3)), np.empty((len(states), 3))
    for i, state in enumerate(states):
        mujoco.mj_setState(model, data, state, STATE)
        mujoco.mj_forward(model, data)
        out_t[i], out_f[i] = data.sensordata[torque], data.sensordata[force]
    return out_t, out_f


def theory(model: mujoco.MjModel, data: mujoco.MjData) -> ba.BentAxle:
    """R8 for the compiled rotor and the state in `data`: mass properties read back from the model (``body_mass``,
    ``body_inertia`` about the CoM along ``body_iquat``, ``body_ipos``), taken about the site ``bearing`` (on the
    axle), and the hinge's angle and rate."""
    b = model.body("rotor")
    rotation = frames.quat_to_matrix(np.asarray(b.iquat, dtype=float))
    inertia = ba.inertia_about_point(
        float(b.mass[0]), np.asarray(b.inertia, dtype=float), rotation, b.ipos, model.site("bearing").pos
    )
    com = np.asarray(b.ipos, dtype=float) - model.site("bearing").pos
    return ba.BentAxle(float(b.mass[0]), inertia, com, float(data.qvel[0]), float(data.qpos[0]))


_PARAMS = (
    Param("mass", "kg", "rotor mass m", Range(1e-3, 1e3), BodyMass("rotor")),
    Param(
        "I1",
        "kg m^2",
        "principal moment about the CM along e1 (the rotor's x axis)",
        Range(1e-6, 1e3),
        BodyInertia("rotor", (0,)),
    ),
    Param(
        "I2",
        "kg m^2",
        "principal moment about the CM along e2 (in the rotor's yz-plane, tilt from y)",
        Range(1e-6, 1e3),
        BodyInertia("rotor", (1,)),
    ),
    Param(
        "I3",
        "kg m^2",
        "principal moment about the CM along e3 (tilt from the axle)",
        Range(1e-6, 2e3),
        BodyInertia("rotor", (2,)),
        within=Bound(
            "[max(|I1 - I2|, 1e-6), I1 + I2] (the triangle inequality of every rigid body)",
            lambda p: Range(max(abs(p["I1"] - p["I2"]), 1e-6), p["I1"] + p["I2"]),
            ("I1", "I2"),
        ),
    ),
    Param(
        "tilt",
        "rad",
        "angle between the principal axis e3 and the axle, turned about the rotor's x axis (e3 leans towards -y)",
        Range(-math.pi / 2, math.pi / 2),
        BodyTilt("rotor", "disc"),
    ),
    Param(
        "com_radial",
        "m",
        "CoM distance from the axle, along the rotor's x axis (rho)",
        Range(-1.0, 1.0),
        RotorCom("rotor", "disc", 0),
    ),
    Param("com_axial", "m", "CoM position along the axle from O (a)", Range(-1.0, 1.0), RotorCom("rotor", "disc", 2)),
    Param(
        "omega",
        "rad/s",
        "axle rate about +z (the hinge's initial and, in theory, constant rate)",
        Range(1e-2, 1e3, magnitude=True),
        Numeric("omega"),
    ),
)
_ON_AXLE = Range(0.0, 0.0)
_BALANCED = "a statically balanced rotor has its CoM on the axle (com_radial = 0)"


class BentAxle(Scenario):
    """A rotor turning at constant rate on a fixed axle its principal axes are tilted from: the bearing torque
    omega x L, fixed in the rotor, and the rotating force of a CoM off the axle (docs/theory.md R8)."""

    slug = "bent-axle"
    title = "Bent axle: bearing torque omega x L and the rotating force of an unbalanced rotor"
    env_id = "rigidbench/BentAxle-v0"
    params = _PARAMS
    cases = (
        Case(
            "tilted-disc",
            "a disc-like rotor (I3 = 5/3 I1) tilted 0.2 rad from its axle, CoM on the axle: a pure couple "
            "omega^2 (I3 - I2) sin(tilt) cos(tilt) = 0.16 N m, no net force",
            {
                "mass": 1.0,
                "I1": 3e-3,
                "I2": 3e-3,
                "I3": 5e-3,
                "tilt": 0.2,
                "com_radial": 0.0,
                "com_axial": 0.0,
                "omega": 20.0,
            },
            (*_TORQUE, "residual-force", "axle-rate"),
            ranges={"com_radial": _ON_AXLE},
            regime=_BALANCED,
        ),
        Case(
            "off-axle",
            "Harter's Fig. 6.5.1: a 1 kg point mass (1e-6 kg m^2) at r = 0.1 sqrt(2) m, 45 deg from the axle: "
            "|N| = m omega^2 rho a = 1/2 m r^2 omega^2 = 4 N m and the rotating force m omega^2 rho = 40 N",
            {
                "mass": 1.0,
                "I1": 1e-6,
                "I2": 1e-6,
                "I3": 1e-6,
                "tilt": 0.0,
                "com_radial": 0.1,
                "com_axial": 0.1,
                "omega": 20.0,
            },
            (*_TORQUE, "force-magnitude", "force-direction", "axle-rate"),
        ),
        Case(
            "balanced",
            "the disc untilted, CoM on the axle 0.05 m from O: L parallel to omega, no torque and no force (an "
            "absolute check against the round-off floor)",
            {
                "mass": 1.0,
                "I1": 3e-3,
                "I2": 3e-3,
                "I3": 5e-3,
                "tilt": 0.0,
                "com_radial": 0.0,
                "com_axial": 0.05,
                "omega": 20.0,
            },
            ("residual-torque", "residual-force", "axial-torque", "axle-rate"),
            ranges={"tilt": Range(0.0, 0.0), "com_radial": _ON_AXLE},
            regime="dynamically and statically balanced: principal axis e3 along the axle (tilt = 0) and the CoM on "
            "it (com_radial = 0)",
        ),
    )
    checks = CHECKS
    domains = DOMAINS

    def validate(self, params: Mapping[str, Any]) -> None:
        require_rigid_body_inertia(params["I1"], params["I2"], params["I3"])

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        """The step samples a turn STEPS_PER_TURN times (the trajectory itself is exact at any step)."""
        return {"timestep": reference_step(params["omega"])}

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[0] = 0.0
        data.qvel[0] = params["omega"]

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        axle = theory(model, data)
        return {
            "_theory": axle,
            "_reference_step": reference_step(axle.omega).value,
            "torque-magnitude": axle.torque,
            "torque-direction": 0.0,
            "torque-rate": axle.omega,
            "axial-torque": 0.0,
            "residual-torque": 0.0,
            "force-magnitude": axle.force,
            "force-direction": 0.0,
            "residual-force": 0.0,
            "axle-rate": axle.omega,
            # On a float32 engine the rotor's angle, advanced every step, carries the run's round-off (secular: each
            # step's sum rounded to half an ulp of |theta| <= 2 pi TURNS rad), and the directions and the torque's
            # rotation rate read it (`Scenario.roundoff_scale`); the sensors are evaluated in float64.
            "_roundoff_secular": ("torque-direction", "force-direction", "torque-rate"),
            "_roundoff_scale": {"torque-direction": 2 * math.pi * TURNS, "force-direction": 2 * math.pi * TURNS},
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        # TURNS turns in whole reference steps (not the simulated step: a timestep sweep compares equal runs).
        h = prediction["_reference_step"]
        return round(TURNS * 2 * math.pi / abs(prediction["_theory"].omega) / h) * h

    def simulate(
        self, model: mujoco.MjModel, data: mujoco.MjData, duration: float, *, control: np.ndarray | None = None
    ) -> AxleTrajectory:
        """The run (one rollout, on the current engine), then the sensors at every recorded state (`reactions`)."""
        traj = simulate(model, data, duration, control=control)
        if traj.diverged_at is not None:
            nan = np.full((len(traj.time), 3), np.nan)
            return AxleTrajectory(traj.time, traj.qpos, traj.qvel, traj.diverged_at, traj.states, nan, nan)
        torque, force = reactions(model, traj.states)
        return AxleTrajectory(traj.time, traj.qpos, traj.qvel, None, traj.states, torque, force)

    def measure(self, model: mujoco.MjModel, traj: AxleTrajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        axle: ba.BentAxle = prediction["_theory"]
        t, angle, rate = traj.time, traj.qpos[:, 0], traj.qvel[:, 0]
        torque_W = ba.rotate_about_axle(traj.torque_B, angle)
        force_W = ba.rotate_about_axle(traj.force_B, angle)
        size = np.linalg.norm(traj.torque_B, axis=1)
        worst = int(np.argmax(np.abs(size - axle.torque)))
        fsize = np.linalg.norm(traj.force_B, axis=1)
        fworst = int(np.argmax(np.abs(fsize - axle.force)))
        # The torque's azimuth in space: the rotor's angle (continuous) plus the torque's azimuth in the rotor's axes
        # (constant in theory, so unwrapping it never aliases, whatever the step).
        azimuth = angle + np.unwrap(np.arctan2(traj.torque_B[:, 1], traj.torque_B[:, 0]))
        rworst = int(np.argmax(np.abs(rate - axle.omega)))
        with np.errstate(invalid="ignore"):  # a balanced rotor's predicted torque (force) has no direction
            return {
                "torque-magnitude": float(size[worst]),
                "torque-direction": float(frames.angle_between(torque_W, axle.torque_W(t)).max()),
                "torque-rate": float(np.polyfit(t - t.mean(), azimuth, 1)[0]),
                "axial-torque": float(np.abs(traj.torque_B[:, 2]).max() / axle.torque_scale),
                "residual-torque": float(size.max() / axle.torque_scale),
                "force-magnitude": float(fsize[fworst]),
                "force-direction": float(frames.angle_between(force_W, axle.force_W(t)).max()),
                "residual-force": float(fsize.max() / axle.force_scale),
                "axle-rate": float(rate[rworst]),
            }


def reference_step(omega: float) -> Derived:
    """The reference timestep (s): 2 pi / (STEPS_PER_TURN |omega|), rounded down to one digit."""
    h = round_step(2 * math.pi / (STEPS_PER_TURN * abs(float(omega))))
    return Derived(
        h,
        f"2 pi / ({STEPS_PER_TURN} |omega|) = 2 pi / ({STEPS_PER_TURN} x {abs(float(omega)):.6g}), "
        f"rounded down to one digit: {h:.1g} s (sampling only: theta = omega t is exact at any step)",
    )


class BentAxleEnv(ScenarioEnv):
    """``rigidbench/BentAxle-v0``: a rotor on a fixed axle, its bearing torque and force scored against R8 every step.

    Description
        A rotor turns on a hinge about the world z axis (the axle) through O, its principal axes tilted from the
        axle and its centre of mass possibly off it. With zero action it keeps its rate omega (no torque about
        the axle is needed) and the axle exerts on it the torque ``N = omega x L = omega^2 (-I_yz, I_xz, 0)``
        about O and the force ``m omega x (omega x c)``, both fixed in the rotor and turning with it in space
        (docs/theory.md R8). They are read from MuJoCo's ``torque`` and ``force`` sensors at the site ``bearing``.

    Observation Space
        Box(-inf, inf, (8,)), float64:

        ===== ============================================ ====== ==================================
        idx   quantity                                     unit   MuJoCo source
        ===== ============================================ ====== ==================================
        0     rotor angle theta about the axle             rad    qpos of ``axle``
        1     axle rate theta'                             rad/s  qvel of ``axle``
        2-4   torque on the rotor about O, rotor axes      N m    sensor ``bearing-torque``
        5-7   force on the rotor, rotor axes               N      sensor ``bearing-force``
        ===== ============================================ ====== ==================================

        The sensors are evaluated at the observed state (``mj_forward`` after the step).

    Action Space
        Box(-1, 1, (1,)), float32, normalised: ``action_scale = 0.01`` N m times it is a drive torque about the
        axle, through ``qfrc_applied``; out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -max(|N_W - N_W,theory(t)| / (omega^2 |I_O|), |F_W - F_W,theory(t)| / (omega^2 sqrt(m |I_O|)))``,
        world-frame torque and force against R8 (``|I_O|`` the largest moment about O); ``info["measured"]`` and
        ``info["predicted"]`` hold both vectors (``torque_x`` ... ``force_z``, world axes).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        ``theta = 0``, ``theta' = omega``. Deterministic.

    Episode End
        Truncated after five turns (the validation run's duration); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (tilted-disc, off-axle, balanced), ``params`` (mass, I1, I2, I3, tilt, com_radial, com_axial,
        omega), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10: ten derived steps, 10 ms at
        the default omega), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = BentAxle
    observables = ("torque_x", "torque_y", "torque_z", "force_x", "force_y", "force_z")
    max_torque: ClassVar[float] = 0.01

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(8,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_torque, self.max_torque, shape=(1,), dtype=np.float64)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        self._torque = sensor_slice(self.model, "bearing-torque")
        self._force = sensor_slice(self.model, "bearing-force")
        axle = self.prediction["_theory"]
        self._scales = (axle.torque_scale, axle.force_scale)
        self.start_views()

    def bind_views(self) -> None:
        self._qfrc = self._data.qfrc_applied

    def observe(self) -> np.ndarray:
        data = self._data
        mujoco.mj_forward(self.model, data)  # the sensors at this state (mj_step leaves those of the last stage)
        return np.concatenate(
            [data.qpos[:1], data.qvel[:1], data.sensordata[self._torque], data.sensordata[self._force]]
        )

    def apply_action(self, action: np.ndarray) -> None:
        self._qfrc[0] = action.item()

    def observe_batch(self, worlds) -> np.ndarray:
        # Per copy, with its drive torque too: the sensors include it (the axial torque is I_zz theta'').
        out = np.empty((worlds.nworld, 8))
        with self._scratch() as data:
            for i in range(worlds.nworld):
                data.qpos[:], data.qvel[:], data.time = worlds.qpos[i], worlds.qvel[i], worlds.time[i]
                data.qfrc_applied[:] = worlds.qfrc_applied[i]
                out[i] = self.observe()
        return out

    def apply_actions(self, actions: np.ndarray, worlds) -> None:
        worlds.qfrc_applied[:, 0] = actions[:, 0]

    def theory(self, t: np.ndarray) -> np.ndarray:
        axle = self.prediction["_theory"]
        return np.concatenate([axle.torque_W(t), axle.force_W(t)], axis=1)

    def measured(self, obs: np.ndarray) -> np.ndarray:
        angle = obs[0]
        return np.concatenate([ba.rotate_about_axle(obs[2:5], angle), ba.rotate_about_axle(obs[5:8], angle)])

    def deviation(self, measured, predicted: list[float]) -> float:
        d = np.asarray(measured, dtype=float) - np.asarray(predicted, dtype=float)
        return float(max(np.linalg.norm(d[:3]) / self._scales[0], np.linalg.norm(d[3:]) / self._scales[1]))
