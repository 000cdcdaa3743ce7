"""A rolling billiard ball rebounding from a cushion whose nose is at a given height: the slip the rebound leaves.
The MuJoCo side, and its gymnasium env.

Theory: docs/theory.md B1 ([DONE] part: a horizontal impulse J at height h above the centre changes the slip by
J (R h / I - 1/M), zero at h = I / (M R) = 2R/5, so a rolling ball rebounds from a cushion of height H = 7/10 of the
diameter still rolling; Harter, Unit 6 Ch. 2, "the bumper height puts the contact point at the CoP"), then B2
for the skid back to rolling. Implemented in `rigidbench.analytic.percussion`.
Model: ``models/cushion_rebound.xml``: the cue-strike ball and cloth, rolling at ``speed`` into a cushion; the
cushion is its ideal impulse (1 + e) M v along -x on the line at ``cushion_height`` above the table, a rectangular
force pulse (`rigidbench.pulse`) through a force and a couple actuator (the model file says why a cushion geom
cannot produce it). Measured from the end of the pulse on, like the cue strike (`CueStrike.measure`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench import pulse
from rigidbench.analytic import percussion
from rigidbench.contract import PER_CHECK, Case, Check, Domain, Trajectory
from rigidbench.envs.cue_strike import (
    BALL_MASS,
    BALL_RADIUS,
    FRICTION,
    SKID_DOMAIN_TEXT,
    TABLE_GRAVITY,
    CueStrike,
    CueStrikeEnv,
    settle,
    skid_outside,
    skid_speed_param,
)
from rigidbench.envs.cue_strike import CHECKS as CUE_CHECKS
from rigidbench.params import Bound, Numeric, Param, Range

_CUE = {c.name: c for c in CUE_CHECKS}
CHECKS = (
    Check(
        "rebound-slip",
        "m/s",
        _CUE["initial-slip"].tolerance,
        "abs",
        _CUE["initial-slip"].reason,
        "B1: u' = (1 + e) v (h M R / I - 1) = (1 + e) v (5 h / (2R) - 1), h = H - R; zero at H = 7/10 of the "
        "diameter ([H] 'bumper height')",
    ),
    *(_CUE[name] for name in ("time-to-roll", "final-speed", "residual-slip", "lift-height", "slip-deceleration")),
)
_SKID = tuple(c.name for c in CHECKS)
_NO_SKID = ("rebound-slip", "final-speed", "residual-slip", "lift-height")


def _rebound_slip(p: Mapping[str, Any]) -> float:
    """The slip (m/s) an ideal cushion blow leaves on a solid ball rolling in at `speed`, from the requested
    parameters: J = -(1 + e) M v at h = H - R above the centre gives u' = (1 + e) v (5h / (2R) - 1)."""
    h = p["cushion_height"] - p["radius"]
    return (1 + p["restitution"]) * p["speed"] * (h / (percussion.SOLID_SPHERE * p["radius"]) - 1)


class CushionRebound(CueStrike):
    """A rolling ball rebounds from a cushion of nose height ``cushion_height``: the slip the rebound leaves
    (zero at 7/10 of the diameter, docs/theory.md B1) and the skid back to rolling (B2)."""

    slug = "cushion-rebound"
    title = "Rolling ball rebounding from a cushion: no skid at 7/10 of the diameter"
    env_id = "rigidbench/CushionRebound-v0"
    params = (
        BALL_RADIUS,
        BALL_MASS,
        FRICTION,
        # |u'| / v = (1 + e) |5h / (2R) - 1|: from 0.5 (h = R/5 or 3R/5, e = 0) to 2 (the equator, e = 1) over the
        # skidding cases.
        skid_speed_param("speed v of the ball, rolling without slip, toward the cushion", (0.5, 2.0)),
        Param(
            "cushion_height",
            "m",
            "height H of the cushion's nose above the table, 0 < H < 2R",
            Range(1e-6, 2.0),
            Numeric("cushion_height"),
            within=Bound(
                "(0, 2R): the cushion touches the ball",
                lambda p: Range(0.0, 2 * p["radius"], low_open=True, high_open=True),
                ("radius",),
            ),
        ),
        Param(
            "restitution", "1", "coefficient of restitution e of the cushion", Range(0.0, 1.0), Numeric("restitution")
        ),
        TABLE_GRAVITY,
    )
    cases = (
        Case(
            "no-skid",
            "nose at H = 7/10 of the diameter: the ball comes back rolling",
            {"cushion_height": lambda p: 1.4 * p["radius"]},
            _NO_SKID,
        ),
        Case(
            "equator",
            "nose at the ball's centre height: the spin is untouched, the ball comes back skidding",
            {"cushion_height": lambda p: p["radius"]},
            _SKID,
        ),
        Case("low", "nose at H = 0.6 of the diameter", {"cushion_height": lambda p: 1.2 * p["radius"]}, _SKID),
        Case(
            "high",
            "nose at H = 0.8 of the diameter: overspin reversed",
            {"cushion_height": lambda p: 1.6 * p["radius"]},
            _SKID,
        ),
    )
    checks = CHECKS
    domains = (
        Domain(
            "skid",
            "B2 (skid to roll, after the cushion)",
            SKID_DOMAIN_TEXT,
            lambda p: skid_outside(
                _rebound_slip(p),
                p,
                f"cushion_height = {p['cushion_height']:g} m (R = {p['radius']:g} m), mu = {p['mu']:g}, speed = "
                f"{p['speed']:g} m/s, restitution = {p['restitution']:g}",
            ),
            cases=("equator", "low", "high"),
        ),
    )

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        settle(model, data)
        speed, radius = params["speed"], float(model.geom("ball").size[0])
        data.qvel[:] = [speed, 0, 0, 0, speed / radius, 0]  # rolling along +x (body frame = world frame here)

    def after_blow(self, model: mujoco.MjModel, data: mujoco.MjData) -> tuple[percussion.SkidToRoll, float]:
        p = self.read_params(model)
        radius, mass = p["radius"], p["mass"]
        inertia = float(model.body("ball").inertia[1])
        v, spin = float(data.qvel[0]), float(data.qvel[4])  # the state simulated (world = body axes at t = 0)
        impulse = -(1 + p["restitution"]) * mass * v  # along x, on the line at h = H - R above the centre
        h = p["cushion_height"] - radius
        theory = percussion.skid_to_roll(
            radius, p["mu"], p["g"], v + impulse / mass, spin + impulse * h / inertia, inertia / (mass * radius**2)
        )
        return theory, v

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        out = super().predict(model, data)
        out["rebound-slip"] = out.pop("initial-slip")
        # The same in every entry keyed by check (`scenario.PER_CHECK`): the slip's float32 floors are keyed by it
        # too (left behind under the old name, an MJX float32 census draw scored its rebound slip with none). The
        # cue strike's checks this scenario lacks (skid distance, energy lost) are dropped from them:
        # `Scenario.check_prediction_keys` refuses a key that names no check.
        names = {c.name for c in self.checks}
        for entry in PER_CHECK:
            keyed = out.get(entry)
            if isinstance(keyed, dict):
                if "initial-slip" in keyed:
                    keyed["rebound-slip"] = keyed.pop("initial-slip")
                out[entry] = {k: v for k, v in keyed.items() if k in names}
        return out

    def control(self, model: mujoco.MjModel, timestep: float, nstep: int) -> np.ndarray:
        p = self.read_params(model)
        impulse = -(1 + p["restitution"]) * p["mass"] * p["speed"]
        ctrl = pulse.control(model, nstep, "push", impulse)
        ctrl += pulse.control(model, nstep, "couple", impulse * (p["cushion_height"] - p["radius"]))
        return ctrl

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        out = super().measure(model, traj, prediction)
        out["rebound-slip"] = out.pop("initial-slip")
        return out


class CushionReboundEnv(CueStrikeEnv):
    """``rigidbench/CushionRebound-v0``: a rolling ball rebounds from a cushion, scored against theory every step.

    Description
        A solid ball rolls at ``speed`` on a cloth with Coulomb friction ``mu`` into a cushion whose nose is at
        ``cushion_height`` H above the table. ``reset`` delivers the cushion's impulse (1 + e) M v as a 1 ms pulse
        on the line at H. With zero action the ball comes back rolling if H = 7/10 of the diameter (docs/theory.md
        B1), otherwise with slip u' = (1 + e) v (5 (H - R) / (2R) - 1), and skids back to rolling (B2).

    Observation Space
        As `CueStrikeEnv`: x, height above rest, v_x, v_z, omega_y, slip (m, m, m/s, m/s, rad/s, m/s).

    Action Space
        As `CueStrikeEnv`: Box(-1, 1, (2,)), float32; 0.1 times it is an extra force f_x (N) and torque tau_y
        (N m); clipped.

    Rewards
        As `CueStrikeEnv`: ``-|x - x_theory(t)| / max(|s|, R)`` after the rebound.
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        Rolling at ``speed`` toward +x at the resting height; the rebound happens during ``reset``.

    Episode End
        Truncated after the pulse + 1.5 times the time to roll again (at least 50 ms); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (no-skid, equator, low, high), ``params`` (radius, mass, mu, speed, cushion_height, restitution,
        g), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 0.1 ms), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = CushionRebound
