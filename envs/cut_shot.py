"""The rolling cut shot: a rolling cue ball hits an equal resting ball off-centre; the MuJoCo side, and its env.

Theory: docs/theory.md B4 (the "30 degree rule"), with B2-B3 for each ball's skid and C2/C8 for the impact, in
`rigidbench.analytic.cut_shot`. Model: ``models/cut_shot.xml``: two free solid balls on the cloth of
``models/cue_strike.xml`` (Coulomb friction ``mu``), their impact a frictionless elastic contact pair (the undamped
direct-solref spring of ``models/hard_spheres.xml``, `rigidbench.contact`). Conventions (`analytic.cut_shot`): the
object ball rests at the origin, the cue ball rolls along +x at ``speed`` on the +y side, offset 2 R sin(phi), and
touches it after `LEAD_STEPS` steps; the object ball leaves at -phi, the cue ball is deflected towards +y.

What MuJoCo simulates is a soft impact lasting t_c = pi / sqrt(k) (60 steps), during which the table's friction
acts too. The checks therefore compare against the impact MuJoCo's spring makes (C8's CM angle, and the friction
impulse mu M g t_c the two balls' opposite slips add to the impact), to the integration error, and against the
hard-sphere closed forms of B4 to the soft shift ~ pi sin(phi) V / (2 R sqrt(k)), set per run.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import frames, signals
from rigidbench.analytic import cut_shot, scattering
from rigidbench.contact import contact_spring, elastic_contact
from rigidbench.contract import Case, Check, Derived, Scenario, Trajectory
from rigidbench.envs.base import ScenarioEnv
from rigidbench.envs.cue_strike import TABLE_GRAVITY, billiard_settings, skid_speed_param
from rigidbench.envs.planar import dot, free_body_motion
from rigidbench.params import GeomFriction, Numeric, Param, Range, ScaledBodyMass, SphereRadius

BALLS = ("cue", "object")
# Steps per impact pi / sqrt(k) (the derived pair stiffness): RK4's error on the impact falls as its square, the
# contact friction's effects grow with it (module docstring); LEAD_STEPS + IMPACT_STEPS stay below the env's frame.
IMPACT_STEPS = 60
# Steps of rolling before the balls touch: the impact's force begins on a step boundary (hard-spheres' LEAD_STEPS).
LEAD_STEPS = 20
# Cut angles (rad) the scenario covers: 5.7 to 74.5 degrees. Below, the cue ball all but stops (its speed after the
# impact is V sin phi) and its direction is ill-defined; above, the object ball barely moves (V cos phi).
CUT_RANGE = (0.1, 1.3)
# The friction-free margin a rolling run keeps after the slower ball rolls (in roll times).
AFTER_ROLL = 0.5

_RK4 = (
    f"RK4 over the impact: {IMPACT_STEPS} steps per contact pi / sqrt(k), the force's kink at the exit inside a "
    "step (second order there): velocity error ~ (sqrt(k) dt)^2 / 24 = 1.1e-4 relative in the normal direction"
)
_FRICTION = (
    "the table's friction during the soft impact (t_c = pi / sqrt(k)): the two balls slip oppositely along the line "
    "of centres, so their friction impulses (mu M g t_c each) cancel in the total momentum and add mu M g t_c to the "
    "spring's impulse (predicted); what remains is second order, the slip direction turning by the soft shift"
)
CHECKS = (
    Check(
        "opening-angle",
        "rad",
        1e-3,
        "abs",
        "angle between the two velocities at the end of the impact (the separation crossing 2 R, cubic-interpolated). "
        + _RK4
        + "; "
        + _FRICTION
        + ": bound 2 (pi/60)^2/24 + 2 mu g t_c (1 / |v_cue| + 1 / |v_object|) / 10 per run",
        "B4, C2 for equal masses: psi + zeta = pi / 2 after any elastic central impact ([D] B4: 'the two leave at 90 "
        "degrees')",
    ),
    Check(
        "object-direction",
        "rad",
        1e-3,
        "abs",
        "object ball's direction at the end of the impact: " + _RK4 + "; the soft impact's CM angle from C8's "
        "quadrature; bound as opening-angle",
        "B4, C8: zeta = (pi - theta_soft) / 2, theta_soft the CM angle of the spring V = 1/2 mu k (2R - r)^2",
    ),
    Check(
        "object-direction-hard",
        "rad",
        5e-3,
        "abs",
        "as object-direction, plus 1.5 times the first-order soft shift / 2 (C8: pi (b / a) V / (a sqrt(k)), a = 2R, "
        "k^-1/2), set per run; listed at the defaults",
        "B4 / C5: the object ball leaves along the line of centres at the touch, at the cut angle phi",
    ),
    Check(
        "deflection",
        "rad",
        1e-3,
        "abs",
        "cue ball's final direction from its first line (both balls rolling, end of the run): angular momentum about "
        "its table contact point is conserved through the skid, so only the impact's impulse matters: "
        + _RK4
        + "; bound 2 (pi/60)^2/24 + 1e-4: MuJoCo's contact point sits in the resting penetration delta, a lever "
        "R - delta/2 for B2's R (delta / R = 1 / (k T^2) = 3.4e-5 for every ball, the settings following T), "
        "~1e-5 on the rolling velocities; with the hops' friction put back (see measure); measured <= 1e-5",
        "B4 (with B2-B3): v_cue = V x - J / (M (1 + gamma)), J the impact's impulse (C8's soft CM angle plus the "
        "friction impulse mu M g t_c)",
    ),
    Check(
        "deflection-closed-form",
        "rad",
        1e-2,
        "abs",
        "as deflection, plus 1.5 times the soft impact's and the contact friction's moves of delta from B4's "
        "hard-sphere value (|d delta / d theta| pi (b / a) V / (a sqrt(k)), k^-1/2; and what mu M g t_c adds), "
        "set per run; listed at the defaults",
        "B4: tan delta = 5 sin phi cos phi / (2 cos^2 phi + 7 sin^2 phi)",
    ),
    Check(
        "max-deflection",
        "rad",
        1e-2,
        "abs",
        "as deflection-closed-form (at phi*, d delta / d phi = 0: the value is insensitive to the cut angle)",
        "B4: delta* = 33.75 degrees at tan phi* = sqrt(2/7) (the '30 degree rule')",
    ),
    Check(
        "final-angle",
        "rad",
        1e-3,
        "abs",
        "angle between the two rolling velocities at the end of the run; bound as deflection",
        "B4: the impact's J: v_cue = V x - J / (M (1 + gamma)), v_object = J / (M (1 + gamma)); arctan(3.5 tan phi) "
        "for hard spheres",
    ),
    Check(
        "cue-final-speed",
        "m/s",
        1e-3,
        "rel",
        "cue ball's rolling speed at the end of the run: " + _RK4 + "; relative to the cue speed V",
        "B4 (B2's 2/7 rule as vectors): |V x - (5/7) J / M|, (V / 7) sqrt(4 + 45 sin^2 phi) for hard spheres",
    ),
    Check(
        "object-final-speed",
        "m/s",
        1e-3,
        "rel",
        "object ball's rolling speed at the end of the run: " + _RK4 + "; relative to the cue speed V",
        "B4, B2's 5/7 rule: |v_object| = (5/7) |J| / M, (5/7) V cos phi for hard spheres",
    ),
)
_TOLERANCE = {c.name: c.tolerance for c in CHECKS}
_ALL = tuple(c.name for c in CHECKS if c.name != "max-deflection")


@dataclass(frozen=True)
class Both:
    """One parameter target applied to both balls (equal balls): read back from the first."""

    targets: tuple[Any, ...]

    def apply(self, spec: mujoco.MjSpec, value: Any) -> None:
        for target in self.targets:
            target.apply(spec, value)

    def read(self, model: mujoco.MjModel) -> Any:
        return self.targets[0].read(model)


_MAX_CUT = cut_shot.max_deflection()[0]
# Half-width (rad) of the max-deflection case's cut angles around phi* = arctan sqrt(2/7).
MAX_CUT_WIDTH = 5e-3


def _max_cut(p: Mapping[str, Any]) -> float:
    return _MAX_CUT


def settle(model: mujoco.MjModel, data: mujoco.MjData) -> float:
    """Let both balls settle on the cloth, apart (30 contact time constants, as cue_strike.settle); return the
    resting height (m) of their centres."""
    radius = float(model.geom("cue").size[0])
    for i, body in enumerate(BALLS):
        adr = model.jnt_qposadr[model.body(body).jntadr[0]]
        data.qpos[adr : adr + 7] = [0, 4 * radius * i, radius, 1, 0, 0, 0]
    data.qvel[:] = 0.0
    solref = model.geom("cue").solref
    time_constant = solref[0] if solref[0] > 0 else 1.0 / np.sqrt(-solref[0])
    mujoco.mj_step(model, data, nstep=max(1, round(30 * time_constant / model.opt.timestep)))
    return float(data.qpos[model.jnt_qposadr[model.body("cue").jntadr[0]] + 2])


class CutShot(Scenario):
    """A rolling cue ball cuts an equal resting ball: 90 degrees after the impact, then the 30 degree rule."""

    slug = "cut-shot"
    title = "Rolling cut shot: the balls part at 90 degrees, the cue ball re-rolls off by at most 33.75 degrees"
    env_id = "rigidbench/CutShot-v0"
    params = (
        Param(
            "radius",
            "m",
            "radius R of both solid balls (I = 2/5 M R^2)",
            Range(1e-3, 1.0),
            Both((SphereRadius("cue", "cue"), SphereRadius("object", "object"))),
        ),
        Param(
            "mass",
            "kg",
            "mass M of each ball",
            Range(1e-6, 100.0),
            Both((ScaledBodyMass("cue"), ScaledBodyMass("object"))),
        ),
        Param(
            "mu",
            "1",
            "Coulomb friction coefficient between the balls and the cloth (the balls' impact is frictionless)",
            Range(1e-3, 2.0),
            GeomFriction(("cue", "object", "table")),
        ),
        # Each ball's slip after the impact is V cos(phi) (hard spheres): cos(1.3) .. cos(0.1) of V.
        skid_speed_param("speed V of the rolling cue ball before the impact", (math.cos(CUT_RANGE[1]), 1.0)),
        Param(
            "cut",
            "rad",
            "cut angle phi between the cue ball's velocity and the line of centres at the touch",
            Range(*CUT_RANGE),
            Numeric("cut"),
        ),
        TABLE_GRAVITY,
    )
    cases = (
        Case("thirty", "cut at 30 degrees: the cue ball re-rolls 33.7 degrees off its line", {}, _ALL),
        Case(
            "max-deflection",
            "cut at tan phi = sqrt(2/7) (28.1 degrees): the largest deflection, 33.75 degrees",
            {"cut": _max_cut},
            (*_ALL, "max-deflection"),
            ranges={"cut": Range(_MAX_CUT - MAX_CUT_WIDTH, _MAX_CUT + MAX_CUT_WIDTH)},
            regime=f"|phi - phi*| <= {MAX_CUT_WIDTH:g} rad: delta is stationary at phi*, so it falls below 33.75 "
            "degrees by only ~1.4 (phi - phi*)^2 <= 3.4e-5 rad (added to the tolerance per run)",
        ),
        Case("full", "a full hit, 10 degrees: the cue ball nearly stops, then follows at 2/7 V", {"cut": 0.1745}, _ALL),
        Case("thin", "a thin cut, 60 degrees: the object ball leaves slowly", {"cut": 1.0472}, _ALL),
    )
    checks = CHECKS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        derived = billiard_settings(params)
        derived.pop("pulse_duration")  # no cue pulse: the cue ball starts rolling
        dt = derived["timestep"].value
        k = (math.pi / (IMPACT_STEPS * dt)) ** 2
        derived["impact_stiffness"] = Derived(
            k, f"k = (pi / ({IMPACT_STEPS} dt))^2 = {k:.6g} 1/s^2: the ball-ball impact lasts {IMPACT_STEPS} steps"
        )
        return derived

    def apply_derived(self, spec: mujoco.MjSpec, name: str, value: float) -> None:
        if name == "contact_stiffness":
            for geom in (*BALLS, "table"):
                spec.geom(geom).solref = [-value, -2 * math.sqrt(value)]
        elif name == "solver":
            spec.option.solver = mujoco.mjtSolver(int(value))
        elif name == "impact_stiffness":
            spec.pair("impact").solref = [-value, 0.0]
        else:
            super().apply_derived(spec, name, value)

    def check_model(self, model: mujoco.MjModel) -> None:
        dt = float(model.opt.timestep)
        for solref in (model.geom("cue").solref, model.pair_solref[0]):
            if solref[0] < 0:  # direct format: MuJoCo's safety clamp is off; refuse an unresolvable contact
                elastic_contact(timestep=dt, stiffness=float(-solref[0]))

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        z = settle(model, data)
        radius, speed, cut = float(model.geom("cue").size[0]), float(params["speed"]), float(params["cut"])
        a = 2 * radius
        lead = speed * LEAD_STEPS * float(model.opt.timestep)
        start = {"cue": (-a * math.cos(cut) - lead, a * math.sin(cut)), "object": (0.0, 0.0)}
        data.qvel[:] = 0.0
        for body in BALLS:
            jnt = model.body(body).jntadr[0]
            data.qpos[model.jnt_qposadr[jnt] : model.jnt_qposadr[jnt] + 7] = [*start[body], z, 1, 0, 0, 0]
        mujoco.mj_forward(model, data)
        # Rolling without slip at MuJoCo's contact point, the middle of the resting penetration: lever z - z_contact.
        cue = model.body("cue").id
        lever = next(
            z - float(c.pos[2])
            for c in data.contact[: data.ncon]
            if cue in (model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2])
        )
        dof = model.jnt_dofadr[model.body("cue").jntadr[0]]
        data.qvel[dof : dof + 6] = [speed, 0.0, 0.0, 0.0, speed / lever, 0.0]
        data.time = 0.0

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        p = self.read_params(model)
        mu, g = p["mu"], p["g"]
        radius = float(model.geom("cue").size[0])
        a = 2 * radius
        gamma = float(model.body("cue").inertia[1] / (model.body("cue").mass[0] * radius**2))
        q = {b: model.jnt_qposadr[model.body(b).jntadr[0]] for b in BALLS}
        d = {b: model.jnt_dofadr[model.body(b).jntadr[0]] for b in BALLS}
        speed = float(data.qvel[d["cue"]])
        offset = float(data.qpos[q["cue"] + 1] - data.qpos[q["object"] + 1])  # b (m)
        gap = float(data.qpos[q["object"]] - data.qpos[q["cue"]]) - math.sqrt(a * a - offset * offset)
        phi = math.asin(offset / a)
        spring = contact_spring(model.pair_solref[0], float(model.opt.timestep))
        k = spring.stiffness
        t_c = math.pi / math.sqrt(k)
        # C8's soft sphere is the model's undamped spring; a damped pair (a profile's solref) is not the theory's
        # elastic impact: then the hard sphere is predicted, with no soft allowance (the checks measure the miss).
        elastic = spring.elastic and 1 / math.sqrt(k) < a / speed
        theta = float(scattering.soft_sphere_cm_angle(offset, a, k, speed)) if elastic else math.pi - 2 * phi
        soft = cut_shot.object_impulse(speed, theta)
        # The friction impulse the opposite slips add to the spring's impulse (module docstring): mu M g t_c.
        impulse = soft * (1.0 + mu * g * t_c / float(np.hypot(*soft))) if elastic else soft
        shot = cut_shot.CutShot(speed, impulse, mu, g, gamma)
        hard = cut_shot.cut_shot(speed, phi, mu, g, gamma)
        # Per-run tolerances (module docstring, the checks' reasons).
        rk4 = 2 * (math.sqrt(k) * float(model.opt.timestep)) ** 2 / 24
        after = rk4 + 0.2 * mu * g * t_c * (1 / np.hypot(*shot.cue_after) + 1 / np.hypot(*shot.object_after))
        shift = float(scattering.soft_sphere_shift_first_order(offset, a, k, speed)) if elastic else 0.0
        step = 1e-6
        slope = (
            cut_shot.cut_shot(speed, phi, mu, g, gamma, cm_angle=math.pi - 2 * phi + step).deflection - hard.deflection
        ) / step
        moved = abs(slope) * shift + abs(
            shot.deflection - cut_shot.cut_shot(speed, phi, mu, g, gamma, cm_angle=theta).deflection
        )
        final = rk4 + 1e-4
        return {
            "_tolerance": {
                "opening-angle": after,
                "object-direction": after,
                "object-direction-hard": after + 0.75 * shift,
                "deflection": final,
                "deflection-closed-form": final + 1.5 * moved,
                "max-deflection": final
                + 1.5 * moved
                + (cut_shot.max_deflection(gamma)[1] - cut_shot.deflection(phi, gamma)),
                "final-angle": final,
                "cue-final-speed": final,
                "object-final-speed": final,
            },
            "_floor": {"cue-final-speed": speed, "object-final-speed": speed},
            "_shot": shot,
            "_mu": mu,
            "_t0": gap / speed,
            "_t_c": t_c,
            "_a": a,
            "opening-angle": math.pi / 2,
            "object-direction": 0.5 * (math.pi - theta),
            "object-direction-hard": phi,
            "deflection": shot.deflection,
            "deflection-closed-form": float(cut_shot.deflection(phi, gamma)),
            "max-deflection": cut_shot.max_deflection(gamma)[1],
            "final-angle": shot.final_angle,
            "cue-final-speed": float(np.hypot(*shot.cue_final)),
            "object-final-speed": float(np.hypot(*shot.object_final)),
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        shot: cut_shot.CutShot = prediction["_shot"]
        return prediction["_t0"] + prediction["_t_c"] + (1 + AFTER_ROLL) * shot.time_to_roll

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        cue, obj = (free_body_motion(model, traj, b) for b in BALLS)
        t = cue.time
        separation = np.hypot(*(cue.com_W[:, :2] - obj.com_W[:, :2]).T) - prediction["_a"]
        exits = signals.crossings(t, separation, direction=1)
        if not len(exits):
            return {c.name: np.nan for c in CHECKS}
        touches = signals.crossings(t, separation, direction=-1)
        t_e = np.array([exits[0]])
        v_cue = np.array([float(signals.interpolate(t, cue.v_W[:, i], t_e)[0]) for i in range(2)])
        v_obj = np.array([float(signals.interpolate(t, obj.v_W[:, i], t_e)[0]) for i in range(2)])
        # The hop's friction put back (the friction clock of cue-strike): MuJoCo's soft cone raises the table's
        # normal force during the impact (the balls leave it at v_z ~ 1.5 g t_c), and each ball's friction, mu
        # times that normal impulse M (g t_c + dv_z), pushes the balls together: the impact's impulse grows by mu M
        # dv_z (mean of the two balls) beyond the predicted mu M g t_c, along the impulse. Put back from the final
        # velocities (v = +-J / (M (1 + gamma))).
        window = np.array([touches[0] if len(touches) else t[0], exits[0]])
        dvz = np.mean([np.diff(signals.interpolate(t, mo.v_W[:, 2], window))[0] for mo in (cue, obj)])
        gamma = prediction["_shot"].gamma
        along = v_obj / np.hypot(*v_obj)
        hop = prediction["_mu"] * dvz * along / (1 + gamma)
        cue_final, obj_final = cue.v_W[-1, :2] + hop, obj.v_W[-1, :2] - hop
        delta = math.atan2(cue_final[1], cue_final[0])
        return {
            "opening-angle": cut_shot.angle_between(v_cue, v_obj),
            "object-direction": math.atan2(-v_obj[1], v_obj[0]),
            "object-direction-hard": math.atan2(-v_obj[1], v_obj[0]),
            "deflection": delta,
            "deflection-closed-form": delta,
            "max-deflection": delta,
            "final-angle": cut_shot.angle_between(cue_final, obj_final),
            "cue-final-speed": float(np.hypot(*cue_final)),
            "object-final-speed": float(np.hypot(*obj_final)),
        }


class CutShotEnv(ScenarioEnv):
    """``rigidbench/CutShot-v0``: the rolling cut shot, scored every step against the object ball's line (B4, C8).

    Description
        Two solid balls (radius ``radius``, mass ``mass``) on a cloth with Coulomb friction ``mu``: the object ball
        rests at the origin, the cue ball rolls along +x at ``speed`` and touches it at cut angle ``cut`` after 20
        physics steps. With zero action the balls part at 90 degrees and each skids (docs/theory.md B3) until it
        rolls; the cue ball ends up deflected by tan delta = 5 sin phi cos phi / (2 cos^2 phi + 7 sin^2 phi) (B4).

    Observation Space
        Box(-inf, inf, (12,)), float64, world frame, from the free joints ``cue`` and ``object``:

        ====  ==========================================  =====  ======================================
        idx   quantity                                    unit   MuJoCo source
        ====  ==========================================  =====  ======================================
        0-1   cue ball's centre (x, y)                    m      qpos
        2-3   object ball's centre (x, y)                 m      qpos
        4-5   cue ball's velocity (v_x, v_y)              m/s    qvel
        6-7   object ball's velocity (v_x, v_y)           m/s    qvel
        8-9   cue ball's angular velocity (w_x, w_y)      rad/s  qvel, rotated to world
        10-11 object ball's angular velocity (w_x, w_y)   rad/s  qvel, rotated to world
        ====  ==========================================  =====  ======================================

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``max_force = 0.1`` N times it is a force on the cue ball's centre
        in world axes, through ``xfrc_applied``; clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|w_across| / V``: the object ball's rolling velocity w = (v - gamma R z x omega) / (1 + gamma)
        (B2: the velocity it rolls at once its slip is gone; table friction and MuJoCo's hops leave it unchanged)
        across the line the prediction sends it along (C8's soft impact, angle ``object-direction``), over the cue
        speed V. ``info["measured"]`` and ``info["predicted"]`` hold ``object_across`` and ``object_along`` (m/s;
        the latter, (5/7) |J| / M after the impact, is reported, not scored: MuJoCo's impact hop moves it by ~mu
        dv_z, see docs/cut-shot.md). Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        Both balls on the cloth at their resting penetration; the cue ball rolling without slip.

    Episode End
        Truncated after the scenario's duration (the impact, then 1.5 roll times); terminated on divergence.
        The diverged step pays -10 for itself and for each step left (`ScenarioEnv`).

    Arguments
        ``case`` (thirty, max-deflection, full, thin), ``params`` (radius, mass, mu, speed, cut, g), ``profile``,
        ``integrator``, ``timestep``, ``frame_skip`` (default 100, i.e. 1 ms, after the impact's 80 steps),
        ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = CutShot
    default_frame_skip: ClassVar[int] = 100
    max_force: ClassVar[float] = 0.1
    observables: ClassVar[tuple[str, ...]] = ("object_across", "object_along")

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(12,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_force, self.max_force, shape=(3,), dtype=np.float64)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        model, p = self.model, self.prediction
        self._q = [int(model.jnt_qposadr[model.body(b).jntadr[0]]) for b in BALLS]
        self._d = [int(model.jnt_dofadr[model.body(b).jntadr[0]]) for b in BALLS]
        self._body_id = model.body("cue").id
        shot: cut_shot.CutShot = p["_shot"]
        zeta = p["object-direction"]
        self._line = (math.cos(zeta), -math.sin(zeta))
        self._rolling = shot.gamma * float(model.geom("object").size[0])  # gamma R
        self._speed = shot.speed
        self.start_views()

    def observe(self) -> np.ndarray:
        qpos, qvel = self.data.qpos, self.data.qvel
        out = [*qpos[self._q[0] : self._q[0] + 2], *qpos[self._q[1] : self._q[1] + 2]]
        out += [*qvel[self._d[0] : self._d[0] + 2], *qvel[self._d[1] : self._d[1] + 2]]
        for q, d in zip(self._q, self._d, strict=True):
            rows = frames.matrix_rows(*qpos[q + 3 : q + 7].tolist())
            omega_b = qvel[d + 3 : d + 6].tolist()
            out += [dot(rows[0], omega_b), dot(rows[1], omega_b)]
        return np.array(out)

    def apply_action(self, action: np.ndarray) -> None:
        self.data.xfrc_applied[self._body_id, :3] = action

    def theory(self, t: np.ndarray) -> np.ndarray:
        """Across the line: 0 at all times; along it: 0 before the impact, (5/7) |J| / M after (impulsive)."""
        p = self.prediction
        t = np.atleast_1d(np.asarray(t, dtype=float))
        along = np.where(t >= p["_t0"] + p["_t_c"], float(np.hypot(*p["_shot"].object_final)), 0.0)
        return np.column_stack([np.zeros(len(t)), along])

    def measured(self, obs: np.ndarray) -> list[float]:
        o = obs.tolist()
        gr = self._rolling
        w_x = (o[6] + gr * o[11]) / (1 + self.prediction["_shot"].gamma)
        w_y = (o[7] - gr * o[10]) / (1 + self.prediction["_shot"].gamma)
        (c, s) = self._line
        return [-s * w_x + c * w_y, c * w_x + s * w_y]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        return abs(measured[0] - predicted[0]) / self._speed
