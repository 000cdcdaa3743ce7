"""A uniform stick on frictionless ice struck perpendicularly off-centre: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md P1-P3 (Harter, Unit 6 Ch. 2 slides, Fig. 2.4.1: "linear momentum Pi and angular momentum Pi h";
"p = I/(Mh)"; the centre of percussion traces a common cycloid), implemented in `rigidbench.analytic.percussion`.
Model: ``models/struck_stick.xml``: a free stick along body y, no gravity (frictionless ice); the blow is a
rectangular force pulse (`rigidbench.pulse`) of ``impulse`` along world +x, applied at the material point
``offset`` from the centre by a site actuator; measured right after the pulse ends.

Conventions: docs/theory.md section 6: the stick lies along +y, its CM at the origin; the blow at s = +h along +x
turns it clockwise, omega_z = -Pi h / I; the centre of percussion is the point s = -p on the far side.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import pulse, signals
from rigidbench.analytic import percussion
from rigidbench.contract import Case, Check, Derived, Scenario, Trajectory
from rigidbench.envs.planar import BlowEnv, free_body_motion, max_impulse, reference_pulse
from rigidbench.params import Bound, Numeric, Param, Range, RodLength, ScaledBodyMass, SitePosition

# The pulse: the force is fixed along world x (refsite), so the linear impulse is exact; it acts at a material
# point that turns by theta(t) <= omega tau / 2 during the pulse, so the torque is -F h cos(theta): relative error
# in omega ~ (omega tau)^2 / 40 <~ 2e-7 at the defaults (|omega| tau <= 2.4e-3). 1e-5 covers |omega| tau <~ 0.02.
_PULSE = (
    "pulse of tau = 2.4e-3 / |omega| rounded down (reference settings; 0.1 ms at the end-struck default) at a "
    "material point that turns by <= omega tau / 2 while pushed: torque error ~ (omega tau)^2 / 40 <= 1.4e-7; 1e-5 "
    "holds for |omega| tau <~ 0.02"
)
_EXACT = (
    "force direction fixed in the world (refsite) and constant within each step: the delivered linear impulse "
    "is exact; roundoff only"
)
_CUSPS = (
    "set by omega, known to the pulse error above; free rotation afterwards (RK4, omega dt = omega tau / 5 <= "
    "4.8e-4: ~1e-12); "
    "cusps cubic-interpolated from the zero crossings of d|v|^2/dt computed from the state"
)

CHECKS = (
    Check("com-velocity", "m/s", 1e-10, "rel", _EXACT, "P1: V = Pi / M ([H] Fig. 2.4.1)"),
    Check("angular-velocity", "rad/s", 1e-5, "rel", _PULSE, "P1: omega = -Pi h / I (= -3 h Pi / (M l^2), l = L/2)"),
    Check(
        "percussion-distance",
        "m",
        1e-5,
        "rel",
        "p = V / |omega| from the measured velocities: " + _PULSE,
        "P2: the instantaneous centre of rotation is at p = I / (M h) on the far side ([H] 'p = I/(Mh)')",
    ),
    Check(
        "cop-speed",
        "1",
        5e-3,
        "abs",
        "speed of the body point s = -p at the end of the pulse, over V: an ideal blow leaves it at rest, but by "
        "the end of a pulse tau it has turned by |omega| tau / 2 about the centre of rotation, speed ~ V |omega| "
        "tau / 2 (<= 1.2e-3 at the defaults); 5e-3 holds for |omega| tau <= 0.01",
        "P2: v(s) = (Pi/M)(1 + s h / rho^2) = 0 at s = -p",
    ),
    Check(
        "first-cusp-time",
        "s",
        1e-5,
        "rel",
        "time from the pulse's centroid tau/2 (a rectangular pulse acts as an impulse there, up to "
        "O((omega tau)^2)); " + _CUSPS,
        "P3: the centre of percussion is at rest again at t_1 = 2 pi I / (Pi h)",
    ),
    Check("cusp-period", "s", 1e-5, "rel", _CUSPS, "P3: cusps at t_n = 2 pi n I / (Pi h)"),
    Check(
        "cusp-spacing",
        "m",
        1e-5,
        "rel",
        _CUSPS + "; positions at the cusp times",
        "P3: successive cusps of the cycloid 2 pi p apart along the blow",
    ),
    Check(
        "cusp-speed",
        "1",
        1e-5,
        "abs",
        "speed of the point s = -p at its cusps, over V: |V - |omega| p| / V, the relative error of omega "
        "(pulse, above) plus interpolation of the minimum",
        "P3: the centre of percussion traces a common cycloid (speed 2 V |sin(omega t / 2)|, zero at cusps)",
    ),
)
_ALL = tuple(c.name for c in CHECKS)


def _inertia(model: mujoco.MjModel) -> float:
    return float(model.body("stick").inertia[2])  # about body z (the turning axis), through the CM


class StruckStick(Scenario):
    """A free uniform stick on frictionless ice struck perpendicularly at ``offset`` from its centre: the CoM
    and spin just after the blow, the centre of percussion at rest, its cycloid (docs/theory.md P1-P3)."""

    slug = "struck-stick"
    title = "Stick on frictionless ice struck off-centre: centre of percussion and cycloid"
    env_id = "rigidbench/StruckStick-v0"
    params = (
        Param(
            "mass", "kg", "mass M of the stick (its inertia scales with it)", Range(1e-6, 1e3), ScaledBodyMass("stick")
        ),
        Param(
            "length",
            "m",
            "full length L of the uniform stick; I = M L^2 / 12 about its centre",
            Range(1e-3, 100.0),
            RodLength("stick", "stick"),
        ),
        Param(
            "impulse",
            "N s",
            "impulse Pi of the blow, along +x (world)",
            Range(1e-6, 1e3),
            Numeric("impulse"),
            within=Bound(
                "Pi <= Pi_max(M, L): the pulse's accelerations (|omega| <= 6 Pi / (M L), speeds <= 4 Pi / M over "
                "tau >= 1.2e-3 / |omega|) stay below 1e9, MuJoCo treating qacc > mjMAXVAL = 1e10 as a divergence",
                lambda p: Range(1e-6, max_impulse(6 / (p["mass"] * p["length"]), 4 / p["mass"])),
                ("mass", "length"),
            ),
        ),
        Param(
            "offset",
            "m",
            "distance h along the stick from its centre to the strike point, in [L/1000, L/2] (nearer the centre "
            "the centre of percussion lies more than 80 L away)",
            Range(1e-6, 50.0),
            SitePosition("strike", 1),
            within=Bound(
                "[L/1000, L/2]: on the stick", lambda p: Range(p["length"] / 1000, p["length"] / 2), ("length",)
            ),
        ),
    )
    cases = (
        Case(
            "quarter", "struck L/4 from the centre: p = L/3, on the stick", {"offset": lambda p: p["length"] / 4}, _ALL
        ),
        Case(
            "end", "struck at the end: p = L/6 (docs/theory.md P6 rule 2)", {"offset": lambda p: p["length"] / 2}, _ALL
        ),
        Case(
            "near-centre",
            "struck L/20 from the centre: p = 5L/3, the centre of percussion lies off the stick",
            {"offset": lambda p: p["length"] / 20},
            _ALL,
        ),
    )
    checks = CHECKS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        inertia = params["mass"] * params["length"] ** 2 / 12
        omega = params["impulse"] * params["offset"] / inertia
        return reference_pulse(omega, "Pi h / I, I = M L^2 / 12")

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[:] = [0, 0, 0, 1, 0, 0, 0]
        data.qvel[:] = 0.0

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        mass = float(model.body("stick").mass[0])
        offset = float(model.site("strike").pos[1])
        impulse = float(model.numeric("impulse").data[0])
        theory = percussion.struck_stick(mass, _inertia(model), impulse, offset)
        return {
            "_theory": theory,
            "_impulse": impulse,
            "_tau": pulse.duration(model),
            "com-velocity": theory.com_velocity,
            "angular-velocity": theory.angular_velocity,
            "percussion-distance": theory.percussion_distance,
            "cop-speed": 0.0,
            "first-cusp-time": theory.cusp_period,
            "cusp-period": theory.cusp_period,
            "cusp-spacing": theory.cusp_spacing,
            "cusp-speed": 0.0,
            # Float32 (`Scenario.roundoff_scale`): the spacing is a difference of positions x = V t up to two
            # spacings from the start, advanced by V dt every step (a secular rounding, like a clock's).
            "_roundoff_scale": {"cusp-spacing": 2.0},
            "_roundoff_secular": ("cusp-spacing",),
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return prediction["_tau"] + 2.3 * prediction["cusp-period"]  # three cusps (t_1, t_2 and the start)

    def control(self, model: mujoco.MjModel, timestep: float, nstep: int) -> np.ndarray:
        return pulse.control(model, nstep, "strike", float(model.numeric("impulse").data[0]))

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        m = free_body_motion(model, traj, "stick")
        theory = prediction["_theory"]
        n = pulse.steps(model)
        tau = prediction["_tau"]
        cop_B = np.array([0.0, -theory.percussion_distance, 0.0])
        v, w = m.v_W[n], m.omega_W[n, 2]
        # Instantaneous centre of rotation relative to the CM: z x V / omega; on the far side if it lies at s < 0.
        icr = np.cross([0.0, 0.0, 1.0], v) / w
        side = -np.sign(icr @ m.R_WB[n][:, 1])
        after = m.time > tau
        t = m.time[after]
        vel = m.point_velocity_W(cop_B)[after]
        acc = m.point_acceleration_W(cop_B)[after]
        cusps = signals.crossings(t, np.sum(vel * acc, axis=1), direction=1)  # minima of |v|^2
        speed = np.sqrt(np.sum(vel**2, axis=1))
        at_cusp = (
            np.array([np.sqrt(max(signals.interpolate(t, speed**2, c)[0], 0.0)) for c in cusps]) if cusps.size else []
        )
        pos = m.point_W(cop_B)[after]
        x_cusp = signals.interpolate(t, pos[:, 0], cusps) if cusps.size else np.array([])
        V = theory.com_velocity
        return {
            "com-velocity": float(v[0]),
            "angular-velocity": float(w),
            "percussion-distance": float(side * np.linalg.norm(v) / abs(w)),
            "cop-speed": float(np.linalg.norm(m.point_velocity_W(cop_B)[n]) / V),
            "first-cusp-time": float(cusps[0] - tau / 2) if cusps.size else np.nan,
            "cusp-period": float(np.mean(np.diff(cusps))) if cusps.size >= 2 else np.nan,
            "cusp-spacing": float(np.mean(np.diff(x_cusp))) if cusps.size >= 2 else np.nan,
            "cusp-speed": float(np.max(at_cusp) / V) if cusps.size else np.nan,
        }


class StruckStickEnv(BlowEnv):
    """``rigidbench/StruckStick-v0``: the struck stick on frictionless ice, scored against theory every step.

    Description
        A uniform stick (mass ``mass``, length ``length``) lies on frictionless ice along world y. ``reset``
        strikes it: a force pulse of impulse ``impulse`` along +x at ``offset`` from its centre, lasting
        ``pulse_duration`` (2.4e-3 / |omega| rounded down: 0.1 ms at the default end strike). With zero action
        it then moves as docs/theory.md P1-P3 say: the CM at V = Pi/M, turning at omega = -Pi h/I, the point s = -p =
        -I/(M h) tracing a cycloid.

    Observation Space
        See `BlowEnv`: CM position (x, y) (m), heading of the stick (rad), CM velocity (v_x, v_y) (m/s) and
        omega_z (rad/s), shape (6,), float64.

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = 0.1`` times it is an extra force (f_x, f_y) (N)
        at the CM and torque tau_z (N m) on the stick, world frame, through ``xfrc_applied``; clipped.
        Zero action = the textbook problem.

    Rewards
        ``reward = -(|x - V t'| + |y|) / L - |heading - omega t'| / pi``, t' = t - tau/2 the time since the
        pulse's centroid: the negative deviation of the pose from the closed form. ``info["measured"]`` and
        ``info["predicted"]`` hold x (m), y (m) and heading (rad).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        At rest at the origin along y, then struck during ``reset``: the first observation is just after the
        pulse.

    Episode End
        Truncated after the scenario's duration (tau + 2.3 cusp periods 2 pi / |omega|); terminated on
        divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (quarter, end, near-centre), ``params`` (mass, length, impulse, offset), ``profile``,
        ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 2 pulse durations), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = StruckStick
    body = "stick"

    observables = ("x", "y", "heading")

    def theory(self, t: np.ndarray) -> np.ndarray:
        return self._stick_pose_theory(t)

    def measured(self, obs: np.ndarray) -> list[float]:
        return obs.tolist()[:3]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        return self._pose_deviation(measured, predicted)

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        return obs[:, :3]

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        return self._pose_deviations(measured, predicted)
