"""One collision of two smooth elastic spheres: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md C1-C5 and C8 (Wilcox Part II sections 9.6-9.9, eqs 9.16, 9.33, 9.36, 9.46, 9.53), in
`rigidbench.analytic.scattering`. Model: ``models/hard_spheres.xml`` (two free spheres, gravity off, condim 1,
an undamped direct-solref contact spring of stiffness k).

What MuJoCo simulates is not a hard sphere but the soft sphere V = 1/2 mu k (a - r)^2 (`rigidbench.contact`).
The checks therefore come in two kinds: against the soft prediction (C8 quadrature), which MuJoCo must match to
its integration error, and against the hard-sphere closed forms, which it matches only to the soft shift
~ pi (b/a) u / (a sqrt(k)), a bound that scales as k^-1/2 (and a check that fits that exponent from a run at
k/16). Conventions: the target rests at the origin; the projectile moves along +x at ``speed``, offset by ``b``
along +y; LAB angles are measured from +x.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import mujoco
import numpy as np

from rigidbench.analytic import scattering
from rigidbench.contact import MIN_STEPS, ContactSpring, ContactStiffness, contact_spring, elastic_contact
from rigidbench.contract import MAX_ACCELERATION, Case, Check, Derived, Domain, Scenario, Trajectory, round_step
from rigidbench.envs.pair import FreePairEnv
from rigidbench.params import BodyMass, Bound, GeomSize, Numeric, Param, Range
from rigidbench.simulate import final_states, initial_states, simulate

# Steps of free flight before the spheres touch: the contact begins on a step boundary (the force's kink at
# zero penetration then falls between RK4 steps instead of inside one).
LEAD_STEPS = 20
# RK4's error on each measured angle (rad), as the _RK4 reason states; the smallest soft shift (rad) whose exponent
# is measured (its tolerance then <= 1e-2).
ANGLE_ERROR = 5e-6
SHIFT_MIN = 2.5e-4
# MuJoCo's default solver tolerance, kept down to the defaults' peak contact deceleration u sqrt(k) (1 m/s at k =
# 1e8 1/s^2), scaled below it (see pivoted-stick).
SOLVER_TOLERANCE = 1e-8
DECELERATION_DEFAULT = 1e4
# Steps per contact time pi / sqrt(k) of the reference timestep (the model file's 0.5 us at k = 1e8 1/s^2).
STEPS_PER_CONTACT = 628
# Probe run for the k^-1/2 scaling: the same collision at stiffness k / SOFTER (4x the penetration).
SOFTER = 16.0

_RK4 = (
    "RK4 at 0.5 us, 628 steps per contact pi/sqrt(k); the force's kink at contact exit lands inside a step, where "
    "RK4 is second order: normal-velocity error <= (sqrt(k) dt)^2/24 = 1.0e-6 relative (RK4 as Simpson's rule on "
    "the kinked force), measured <= 9e-7 in angles, energies and restitution; 5e-6 leaves a factor 5"
)
# The contact time's RK4 error per kink, in units of z^3 = (sqrt(k) dt)^3 (relative), and its round-off factor.
CONTACT_TIME_KINK = 1e-2
_CONTACT_TIME = (
    "the contact's entry and exit times, each extrapolated along the free flight from the last state before and the "
    "first after (exact in free flight), read from the run; RK4 integrates the kinked force k max(delta, 0) across "
    "each kink like Simpson's rule: per kink a position error <= k u_n dt^3 / 68 and a velocity error <= k u_n "
    "dt^2 / 72 carried back over <= dt, i.e. a time error <= k dt^3 / 35 = z^3 / (35 pi) T, z = sqrt(k) dt; "
    "tolerance 1e-2 z^3 per kink (2e-2 z^3, 2.5e-9 at the defaults' z = 5e-3; measured <= 2.4e-10, and <= 1.9e-3 "
    "z^3 for z = 5e-3 .. 8e-2) + 10 eps a / delta_n (a position rounded to eps a read against the normal "
    "penetration delta_n = u_n / sqrt(k)), set per run. MuJoCo's force law is this spring to round-off: with "
    "solimp dmin = dmax = d, aref = -k/d delta and the solver's acceleration d aref (R = (1-d)/d A, A = 1/m1 + "
    "1/m2 exact for a smooth sphere pair): measured relative normal acceleration / (k delta) - 1 <= 3.3e-16, "
    "tangential / normal <= 1.3e-12, for m1/m2 = 1e-6 .. 3.4e3"
)
_ROUNDOFF = "equal and opposite contact forces at every RK4 stage: conserved to round-off (~1e-16 per step)"
_SOFT_BOUND = (
    "k^-1/2 bound: 1.5 |d(angle)/d(theta)| pi (b/a) u / (a sqrt(k)) (+ its square for psi) + 5e-6 rad (RK4), "
    "the first-order soft shift "
    "(C8, analytic.scattering.soft_sphere_shift_first_order) with 50 % for the higher orders (measured <= 5 % "
    "for penetrations <= 1e-2 a and b <= 0.99 a); set per run, listed at the defaults (b -> a, |dpsi/dtheta| <= 1)"
)

CONTACT_ROUNDOFF_RULE = (
    "contact: the force k delta is read from a penetration delta <= u_n / sqrt(k) that the engine computes from "
    "positions up to a = r1 + r2 from the origin, each rounded to ~eps a: a penetration error ~eps a that holds "
    "over the contact, moving the impulse and the energy by ~4 eps a / delta (C = 10 in place of 4); or, if "
    "larger, the steady projectile's quantised advance: a body moving u dt a step on a grid of spacing <= eps X "
    "advances a whole number of grid steps, so its effective speed is off by up to eps X / (2 u dt), relative, "
    "where its speed is steady through the contact (its change 2 m2 / (m1 + m2) u moves u dt by S < 1 grid step); "
    "by 1/S of that where the sweep S > 1 decorrelates the rounding"
)


def contact_floor(eps: float, a: float, depth: float, steady: tuple[float, float, float]) -> float:
    """The relative error (of the impulse, the energy, the speeds) that positions rounded to `eps` put into an
    elastic contact (`CONTACT_ROUNDOFF_RULE`): the larger of the penetration's C eps a / `depth` and the steady
    projectile's quantised advance (``steady = (u dt, X, 2 m2 / (m1 + m2))``, see `_contact_roundoff`)."""
    from rigidbench.engines import ROUNDOFF_FACTOR

    advance, extent, share = steady
    quantised = 0.0
    if advance > 0:
        grid_steps = advance / (eps * extent)
        sweep = share * grid_steps
        quantised = 0.5 / grid_steps * min(1.0, 1.0 / sweep) if sweep > 0 else 0.5 / grid_steps
    return max(ROUNDOFF_FACTOR * eps * a / depth, quantised)


@dataclass(frozen=True)
class ContactFloor:
    """A check's contact floor as a function of eps (`contact_floor` times the check's scale); a class, not a
    closure, so a prediction holding it pickles with its env."""

    a: float
    depth: float
    steady: tuple[float, float, float]
    scale: float

    def __call__(self, eps: float) -> float:
        return self.scale * contact_floor(eps, self.a, self.depth, self.steady)


def _contact_roundoff(
    a: float, depth: float, prediction: Mapping[str, Any], *, steady: tuple[float, float, float]
) -> dict[str, Any]:
    """Float32 floors of the collision checks in units of eps (`Scenario._roundoff_check`'s
    ``prediction["_roundoff_eps"]``), each the larger of two mechanisms (`CONTACT_ROUNDOFF_RULE`), times each check's
    scale (1 for an energy or speed fraction and for an angle in rad; 2 for the opening angle, a sum of two; the
    soft-shift exponent's own propagation of an angle error, as its tolerance).

    - The penetration's rounding eps a against the deepest penetration `depth` (m), times the random walk's factor
      C = 10 (`engines.ROUNDOFF_FACTOR`). Measured on MJX float32 head-on (a = 0.1 m, delta = u / sqrt(k) = 1e-4 m):
      energy 6.2e-4 off, 5.2 eps a / delta; this floor is 10 eps a / delta = 1.2e-3.
    - The steady projectile's quantised advance, ``steady = (u dt, X, share)``: its step's advance u dt (m), the
      largest coordinate X (m) its position takes before and in the contact (the grid spacing is <= eps X), and the
      share 2 m2 / (m1 + m2) of u its speed changes by in the contact. Relative speed error eps X / (2 u dt) x
      min(1, 1/S), S = share u dt / (eps X) the grid steps the advance sweeps in the contact. Not proportional to
      eps where S > 1, so the floor is a function of eps. Measured with float32 storage of the state (C arithmetic,
      the mechanism MJX's contact loss was traced to): m1/m2 = 2.4e3, u dt = 2.7e-6 m, X = 0.1 m: restitution
      1.63e-3 off against this floor's 2.33e-3; m1/m2 = 6.4e11 (the MJX census miss): 5.5e-3 against 8.6e-3.
    """

    # Every check but the momentum (exact pairwise forces: the random walk's floor) is read from the impulse.
    scales = {c.name: 1.0 for c in CHECKS if c.name not in ("momentum", "opening-angle", "soft-shift-exponent")}
    scales["opening-angle"] = 2.0
    # The restitution is the impulse's (1 + e): a relative error q of the approach speed the spring sees (delta' = w
    # + q u while the advance's rounding is steady) ends the contact at w = -(1 + 2q) u, so e is off by 2q, at any
    # mass ratio (MJX float32, m1/m2 = 3.35e3: e = 1.01256 against q <= 9.0e-3; 1.63e-3 and 5.5e-3 at 2.4e3, 6.4e11).
    scales["restitution"] = 2.0
    tolerance = prediction["_tolerance"]["soft-shift-exponent"]
    scales["soft-shift-exponent"] = (tolerance - 1e-3) / ANGLE_ERROR if tolerance > 1e-3 else 0.0
    return {
        "_roundoff_eps": {
            name: ContactFloor(a, depth, tuple(steady), scale) for name, scale in scales.items() if scale > 0
        },
        "_roundoff_eps_rule": CONTACT_ROUNDOFF_RULE,
    }


CHECKS = (
    Check("cm-angle", "rad", 5e-6, "abs", _RK4, "C8: theta = pi - 2 int b dr / (r^2 sqrt(1 - b^2/r^2 - V/E)), eq 9.16"),
    Check("cm-angle-hard", "rad", 5e-3, "abs", _SOFT_BOUND, "C5: theta = 2 arccos(b/a), Wilcox section 9.9"),
    Check("projectile-lab-angle", "rad", 5e-6, "abs", _RK4, "C2: tan psi = sin theta / (cos theta + x), eq 9.33"),
    Check("target-lab-angle", "rad", 5e-6, "abs", _RK4, "C2: zeta = (pi - theta) / 2"),
    Check("projectile-lab-angle-hard", "rad", 5e-3, "abs", _SOFT_BOUND, "C2 + C5 at theta = 2 arccos(b/a)"),
    Check("target-lab-angle-hard", "rad", 2.5e-3, "abs", _SOFT_BOUND, "C2 + C5: zeta = arcsin(b/a)"),
    Check(
        "projectile-energy", "1", 5e-6, "abs", _RK4, "C4: T1/T0 = (m1^2 + m2^2 + 2 m1 m2 cos theta)/(m1+m2)^2, eq 9.46"
    ),
    Check("target-energy", "1", 5e-6, "abs", _RK4, "C4: T2/T0 = 4 m1 m2 sin^2(theta/2)/(m1+m2)^2"),
    Check(
        "projectile-speed",
        "1",
        5e-6,
        "abs",
        _RK4,
        "C4: v1/u1 = (x cos psi +- sqrt(1 - x^2 sin^2 psi))/(1 + x), eq 9.53; + (stretch) for theta < arccos(-1/x), "
        "- (short) beyond (x > 1 only)",
    ),
    Check(
        "contact-time",
        "s",
        2.5e-9,
        "rel",
        _CONTACT_TIME,
        "C8: t_c = 2 int_{r_min}^a dr / (u sqrt(1 - b^2/r^2 - k (a - r)^2 / u^2)); pi / sqrt(k) head-on",
    ),
    Check("momentum", "1", 1e-12, "abs", _ROUNDOFF, "C1: total momentum conserved (|P - P0| / |P0|)", identity=True),
    Check("energy", "1", 5e-6, "abs", _RK4, "C1: elastic, T conserved (|T - T0| / T0)"),
    Check(
        "restitution",
        "1",
        5e-6,
        "abs",
        _RK4 + "; e = -(v_rel' . n)/(v_rel . n), n along the impulse; set per run to 5e-6 (1 + tan alpha), "
        "tan alpha = b / sqrt(a^2 - b^2): n is measured from the velocity change, whose RK4 error lets the tangential "
        "relative velocity (tan alpha times the normal one) leak into the normal one e divides by (measured error / "
        "tan alpha <= 1e-6 for b/a = 0.5 .. 0.9997: 5.5e-6 at b/a = 0.999, 3.8e-5 at 0.9997); listed at b = 0",
        "C5 validity: elastic spheres, e = 1",
    ),
    Check(
        "opening-angle",
        "rad",
        1e-5,
        "abs",
        _RK4 + " (sum of two angles)",
        "C2: psi + zeta = pi/2 for m1 = m2, eqs 9.37-9.39 (any central force; otherwise the C2 sum)",
    ),
    Check(
        "soft-shift-exponent",
        "1",
        0.02,
        "abs",
        "two-point exponent of |theta - theta_hard| at k and k/16 against the same exponent of the C8 quadrature "
        "(exact: 0.5 only asymptotically, 0.588 at an overlap of 0.08 a); tolerance (5e-6 / d_k + 5e-6 / d_16) / ln "
        "16 + 1e-3 per run, d the two shifts (RK4's angle error over each), 0.02 listed; the shift at k must be >= "
        "2.5e-4 rad in the case regimes (the tolerance <= 1e-2 there; it grows as the shift shrinks outside them)",
        "C8 vs C5: theta_hard - theta_soft = pi (b/a) u / (a sqrt(k)) + O(1/k)",
    ),
    Check(
        "max-lab-angle",
        "rad",
        1e-5,
        "abs",
        "probe at b0: psi is stationary there, so the soft shift dtheta at b0 moves it by only ~|psi''| dtheta^2 / "
        "2, psi'' ~ 1/x: tolerance 1e-5 + (1.5 dtheta_1)^2 / x per run, dtheta_1 the first-order shift at b0 (1e-5 "
        "listed: ~1e-6 at the defaults; measured 2.9e-4 at x = 28 and a 5.7 % overlap, where the bound is 1.3e-3); "
        "RK4 error <= 1e-6 (measured 5e-7)",
        "C3: sin psi_max = m2/m1 at b0 = a sqrt((x-1)/(2x)), eq 9.36 (pi at b = 0 for x < 1)",
    ),
)
_COMMON = (
    "cm-angle",
    "cm-angle-hard",
    "projectile-lab-angle",
    "target-lab-angle",
    "projectile-lab-angle-hard",
    "target-lab-angle-hard",
    "projectile-energy",
    "target-energy",
    "projectile-speed",
    "momentum",
    "energy",
    "restitution",
    "contact-time",
)


def _a(p: Mapping[str, Any]) -> float:
    return p["r1"] + p["r2"]


def _shift_regime(ratio: float) -> dict[str, Bound]:
    """The regime of a case whose impact parameter is `ratio` a: stiffnesses whose first-order soft shift pi ratio u /
    (a sqrt(k)) is at least SHIFT_MIN, within the stiffness's own range."""
    return {
        "stiffness": Bound(
            f"k <= (pi {ratio:g} u / ({SHIFT_MIN:g} a))^2: a soft shift the exponent can be measured from",
            lambda p: Range(1.0, (np.pi * ratio * p["speed"] / (SHIFT_MIN * _a(p))) ** 2),
            ("speed", "r1", "r2"),
        )
    }


def stiffness_param(overlap: float, why: str) -> Param:
    """The contact stiffness k (1/s^2) of a sphere pair, within [(u / (overlap a))^2, (1e9 / u)^2]: the head-on
    penetration u / sqrt(k) at most `overlap` of a = r1 + r2 (`why`), the contact's peak deceleration u sqrt(k) below
    MuJoCo's divergence limit (mjMAXVAL = 1e10) by a decade. An empty range (a fast, small pair) means no contact
    meets both: a census draws again."""
    return Param(
        "stiffness",
        "1/s^2",
        "contact spring k: penetration'' = -k penetration (direct solref (-k, 0))",
        Range(1.0, 1e18),
        ContactStiffness(("projectile", "target")),
        within=Bound(
            f"[(u / ({overlap:g} a))^2, (1e9 / u)^2], a = r1 + r2, u = speed: the head-on overlap u / sqrt(k) <= "
            f"{overlap:g} a ({why}), the peak deceleration u sqrt(k) <= 1e9 m/s^2 (MuJoCo: mjMAXVAL = 1e10 is a "
            "divergence)",
            lambda p: Range((p["speed"] / (overlap * _a(p))) ** 2, (MAX_ACCELERATION / p["speed"]) ** 2),
            ("speed", "r1", "r2"),
        ),
    )


def _b0(p: Mapping[str, Any]) -> float:
    return scattering.critical_impact_parameter(_a(p), p["m1"] / p["m2"])


@dataclass(frozen=True)
class CollisionRun(Trajectory):
    """The collision's trajectory plus probe runs (final states only), keyed by name."""

    probes: Mapping[str, np.ndarray] = field(default_factory=dict)


class HardSpheres(Scenario):
    """One collision of smooth elastic spheres, target at rest: CM and LAB angles, energies, both branches of a
    heavy projectile and its maximum angle, against the soft-sphere prediction and the hard-sphere closed forms
    (docs/theory.md C1-C5, C8)."""

    slug = "hard-spheres"
    title = "Hard-sphere collision (smooth, elastic, target at rest)"
    env_id = "rigidbench/HardSpheres-v0"
    params = (
        Param("m1", "kg", "projectile mass", Range(1e-6, 1e6), BodyMass("projectile")),
        Param("m2", "kg", "target mass", Range(1e-6, 1e6), BodyMass("target")),
        Param("r1", "m", "projectile radius", Range(1e-4, 100.0), GeomSize("projectile")),
        Param("r2", "m", "target radius", Range(1e-4, 100.0), GeomSize("target")),
        Param(
            "speed",
            "m/s",
            "projectile's LAB speed u1 along +x (the target is at rest)",
            Range(1e-3, 1e4),
            Numeric("speed"),
        ),
        Param(
            "b",
            "m",
            "impact parameter, along +y, in [0, r1 + r2)",
            Range(0.0, 1e3),
            Numeric("b"),
            within=Bound("[0, r1 + r2): the spheres touch", lambda p: Range(0.0, _a(p), high_open=True), ("r1", "r2")),
        ),
        stiffness_param(0.1, "the soft shift's first-order bound holds"),
    )
    cases = (
        Case(
            "head-on", "b = 0, m1 < m2: the projectile bounces straight back", {"b": 0.0, "m1": 1.0, "m2": 3.0}, _COMMON
        ),
        Case(
            "equal-mass",
            "m1 = m2, b = a/2: the 90-degree rule psi + zeta = pi/2",
            {"m1": 1.0, "m2": 1.0, "b": lambda p: 0.5 * _a(p)},
            (*_COMMON, "opening-angle", "soft-shift-exponent"),
            ranges=_shift_regime(0.5),
            regime=f"a soft shift of >= {SHIFT_MIN:g} rad, from which its exponent can be measured",
        ),
        Case(
            "light-projectile",
            "m1/m2 = 1/3, b = 0.6 a: one branch, psi up to pi",
            {"m1": 1.0, "m2": 3.0, "b": lambda p: 0.6 * _a(p)},
            (*_COMMON, "soft-shift-exponent"),
            ranges=_shift_regime(0.6),
            regime=f"a soft shift of >= {SHIFT_MIN:g} rad, from which its exponent can be measured",
        ),
        Case(
            "heavy-projectile",
            "m1/m2 = 3, b = 0.8 a > b0 (stretch branch); probe at b0 for psi_max = arcsin(1/3)",
            {"m1": 3.0, "m2": 1.0, "b": lambda p: 0.8 * _a(p)},
            (*_COMMON, "soft-shift-exponent", "max-lab-angle"),
            ranges=_shift_regime(0.8),
            regime=f"a soft shift of >= {SHIFT_MIN:g} rad, from which its exponent can be measured",
        ),
        Case(
            "heavy-projectile-short",
            "m1/m2 = 3, b = 0.3 a < b0 (short branch: the slow projectile of eq 9.53)",
            {"m1": 3.0, "m2": 1.0, "b": lambda p: 0.3 * _a(p)},
            (*_COMMON, "soft-shift-exponent", "max-lab-angle"),
            ranges=_shift_regime(0.3),
            regime=f"a soft shift of >= {SHIFT_MIN:g} rad, from which its exponent can be measured",
        ),
        Case(
            "grazing",
            "b = 0.99 a, m1/m2 = 1/2: small deflection, largest relative soft shift",
            {"m1": 1.0, "m2": 2.0, "b": lambda p: 0.99 * _a(p)},
            (*_COMMON, "soft-shift-exponent"),
            ranges=_shift_regime(0.99),
            regime=f"a soft shift of >= {SHIFT_MIN:g} rad, from which its exponent can be measured",
        ),
    )
    checks = CHECKS
    domains = (
        Domain(
            "head-on",
            "C2, C8 vs C5",
            "b > 0: head-on every central force turns the projectile back or stops it, so the soft shift is 0 at every "
            "k (its exponent is undefined) and an equal-mass projectile stops dead (its LAB angle is undefined)",
            lambda p: None if p["b"] > 0 else f"b = {p['b']:g} m",
            cases=("equal-mass", "light-projectile", "heavy-projectile", "heavy-projectile-short", "grazing"),
        ),
    )

    # ---- validation ---------------------------------------------------------------------------------------

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        t_c = np.pi / np.sqrt(params["stiffness"])
        decel = params["speed"] * np.sqrt(params["stiffness"])
        m1, m2 = params["m1"], params["m2"]
        balance = 4 * m1 * m2 / (m1 + m2) ** 2
        return {
            "solver_tolerance": Derived(
                SOLVER_TOLERANCE * min(1.0, (decel / DECELERATION_DEFAULT) ** 2 * balance),
                f"{SOLVER_TOLERANCE:g} x min(1, (a / {DECELERATION_DEFAULT:g} m/s^2)^2 x 4 m1 m2 / (m1 + m2)^2), a = u "
                f"sqrt(k) = {decel:.3g} m/s^2 the contact's peak deceleration, 4 m1 m2 / (m1 + m2)^2 = {balance:.3g}: "
                "MuJoCo's solver stops when the improvement of its cost (~ reduced mass x a^2) over its mean inertia "
                "falls below the tolerance; a fixed 1e-8 leaves slow collisions and extreme mass ratios unconverged "
                "(measured up to 1.8e-5 rad off; <= 1e-7 at the derived tolerance)",
            ),
            "timestep": Derived(
                round_step(t_c / STEPS_PER_CONTACT),
                f"dt = pi / sqrt(k) / {STEPS_PER_CONTACT} rounded down to one digit (>= {STEPS_PER_CONTACT} steps per "
                f"contact, the model file's 0.5 us at k = 1e8 1/s^2: RK4 error (sqrt(k) dt)^2 / 24 <= 1e-6 across the "
                f"contact's kinks); contact time pi / sqrt(k) = {t_c:.4g} s",
            ),
        }

    def check_model(self, model: mujoco.MjModel) -> None:
        spring = self._spring(model)
        if spring.direct:
            try:
                elastic_contact(timestep=model.opt.timestep, stiffness=spring.stiffness, min_steps=MIN_STEPS)
            except ValueError as exc:
                raise ValueError(f"parameter 'stiffness': {exc}") from None

    # ---- physics layer ------------------------------------------------------------------------------------

    @staticmethod
    def _spring(model: mujoco.MjModel) -> ContactSpring:
        # MuJoCo combines the two geoms' solref (element-wise min for the direct format); both are set together.
        return contact_spring(model.geom("projectile").solref, model.opt.timestep)

    @staticmethod
    def _state(model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray) -> dict[str, np.ndarray]:
        """Positions (m) and linear velocities (m/s, world frame) of both spheres; works on stacked rows."""
        p1 = model.jnt_qposadr[model.joint("projectile").id]
        p2 = model.jnt_qposadr[model.joint("target").id]
        v1 = model.jnt_dofadr[model.joint("projectile").id]
        v2 = model.jnt_dofadr[model.joint("target").id]
        return {
            "x1": qpos[..., p1 : p1 + 3],
            "x2": qpos[..., p2 : p2 + 3],
            "v1": qvel[..., v1 : v1 + 3],
            "v2": qvel[..., v2 : v2 + 3],
        }

    @staticmethod
    def _geometry(model: mujoco.MjModel) -> tuple[float, float, float]:
        m1 = float(model.body("projectile").mass[0])
        m2 = float(model.body("target").mass[0])
        a = float(model.geom("projectile").size[0] + model.geom("target").size[0])
        return m1, m2, a

    @staticmethod
    def place(a: float, b: float, speed: float, lead: float, azimuth: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Projectile position (m) and velocity (m/s) so that it touches the target at the origin after `lead`
        seconds; the impact offset b points along (0, cos azimuth, sin azimuth). Misses (b >= a) start at
        x = -speed lead."""
        x_touch = -np.sqrt(np.maximum(a * a - b * b, 0.0))
        pos = np.stack([x_touch - speed * lead, b * np.cos(azimuth), b * np.sin(azimuth)], axis=-1)
        vel = np.zeros_like(pos)
        vel[..., 0] = speed
        return pos, vel

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        _, _, a = self._geometry(model)
        pos, vel = self.place(a, params["b"], params["speed"], LEAD_STEPS * model.opt.timestep)
        s = self._state(model, data.qpos, data.qvel)
        s["x1"][:] = pos
        s["v1"][:] = vel
        s["x2"][:] = 0.0
        s["v2"][:] = 0.0

    # ---- prediction -----------------------------------------------------------------------------------------

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        m1, m2, a = self._geometry(model)
        s = self._state(model, data.qpos, data.qvel)
        r0, u_vec = s["x1"] - s["x2"], s["v1"] - s["v2"]
        speed = float(np.linalg.norm(u_vec))
        u_hat = u_vec / speed
        b = float(np.linalg.norm(r0 - np.dot(r0, u_hat) * u_hat))
        spring = self._spring(model)
        x = m1 / m2
        theta_hard = float(scattering.hard_sphere_cm_angle(b, a))
        # The soft prediction exists for the undamped spring only; a damped (standard-format) contact is scored
        # against the textbook values, and its failures are the findings.
        elastic = spring.direct and spring.elastic
        theta = float(scattering.soft_sphere_cm_angle(b, a, spring.stiffness, speed)) if elastic else theta_hard
        psi, zeta = (float(v) for v in scattering.lab_angles(theta, x))
        psi_h, zeta_h = (float(v) for v in scattering.lab_angles(theta_hard, x))
        t1, t2 = (float(v) for v in scattering.lab_energy_fractions(theta, m1, m2))
        # Eq 9.53 from the predicted LAB angle, on the branch the CM angle lies on.
        root = np.sqrt(max(1.0 - (x * np.sin(psi)) ** 2, 0.0))
        stretch = x <= 1 or theta <= np.arccos(-1.0 / x)
        branches = ((x * np.cos(psi) + root) / (1 + x), (x * np.cos(psi) - root) / (1 + x))
        shift = float(scattering.soft_sphere_shift_first_order(b, a, spring.stiffness, speed)) if elastic else 0.0
        dpsi = abs((1 + x * np.cos(theta_hard)) / (1 + x * x + 2 * x * np.cos(theta_hard)))  # d psi / d theta
        bound = 1.5 * shift
        b0 = scattering.critical_impact_parameter(a, x) if x > 1 else 0.0
        shift_b0 = float(scattering.soft_sphere_shift_first_order(b0, a, spring.stiffness, speed)) if elastic else 0.0
        # The exponent of the soft shift between k and k / SOFTER, exact (C8 quadrature at both stiffnesses; 0.5 only
        # asymptotically: 0.588 at an overlap of 0.08 a), and its measurement error from RK4's <= 5e-6 rad per angle.
        # (Head-on, b = 0, the shift is 0 at every k: the cases with this check refuse it, the `head-on` domain.)
        exponent, exponent_tol = float("nan"), 0.02
        if elastic and b > 0:
            softer = float(scattering.soft_sphere_cm_angle(b, a, spring.stiffness / SOFTER, speed))
            d_k, d_soft = abs(theta_hard - theta), abs(theta_hard - softer)
            exponent = float(np.log(d_soft / d_k) / np.log(SOFTER))
            exponent_tol = float((ANGLE_ERROR / d_k + ANGLE_ERROR / d_soft) / np.log(SOFTER) + 1e-3)
        # The time in contact: the C8 quadrature of the radial motion (a damped contact is scored against the undamped
        # spring's half period, and fails: a finding); RK4's error per kink and the penetration's rounding.
        root_k = np.sqrt(spring.stiffness)
        t_contact = (
            float(scattering.soft_sphere_contact_time(b, a, spring.stiffness, speed)) if elastic else np.pi / root_k
        )
        normal_depth = speed * np.sqrt(max(1.0 - (b / a) ** 2, 0.0)) / root_k
        contact_time_tol = 2 * CONTACT_TIME_KINK * (root_k * model.opt.timestep) ** 3 + (
            10 * np.finfo(float).eps * a / normal_depth if normal_depth > 0 else np.inf
        )
        out: dict[str, Any] = {
            "_elastic": elastic,
            "_duration": self._run_steps(model, self._contact_time(model)) * model.opt.timestep,
            "_spring": spring,
            "_speed": speed,
            "_b": b,
            "_a": a,
            "_t0": float(data.time),
            "_r0": r0.copy(),
            "_v0": u_vec.copy(),
            "_branches": {"stretch": branches[0], "short": branches[1] if x > 1 else None},
            "_branch": "stretch" if stretch else "short",
            "_b0": scattering.critical_impact_parameter(a, x) if x > 1 else 0.0,
            "cm-angle": theta,
            "cm-angle-hard": theta_hard,
            "projectile-lab-angle": psi,
            "target-lab-angle": zeta,
            "projectile-lab-angle-hard": psi_h,
            "target-lab-angle-hard": zeta_h,
            "projectile-energy": t1,
            "target-energy": t2,
            "projectile-speed": branches[0] if stretch else branches[1],
            "momentum": 0.0,
            "energy": 0.0,
            "restitution": 1.0,
            "opening-angle": np.pi / 2 if m1 == m2 else psi + zeta,
            "soft-shift-exponent": exponent,
            "max-lab-angle": scattering.max_lab_angle(x),
            "contact-time": t_contact,
            "_tolerance": {
                "contact-time": float(contact_time_tol),
                "soft-shift-exponent": exponent_tol,
                "cm-angle-hard": bound + 5e-6,
                # + bound^2: the second-order term, which dominates where psi is stationary (b0, x > 1).
                "projectile-lab-angle-hard": dpsi * bound + bound**2 + 5e-6,
                "target-lab-angle-hard": 0.5 * bound + 5e-6,
                "max-lab-angle": 1e-5 + (1.5 * shift_b0) ** 2 / x if x > 1 else 1e-5,
                # x (1 + tan alpha): the impulse's direction carries RK4's relative error, through which the
                # tangential relative velocity (tan alpha times the normal one) leaks into the normal one
                "restitution": self.check("restitution").tolerance * (1 + b / np.sqrt(max(a * a - b * b, 0.0))),
            },
        }
        if elastic and b < a:
            # The projectile's grid: its coordinates before and in the contact (the target sits at the origin).
            extent = max(float(np.abs(s["x1"]).max()), float(np.abs(s["x2"]).max()) + a)
            steady = (float(np.linalg.norm(s["v1"])) * model.opt.timestep, extent, 2 * m2 / (m1 + m2))
            depth = speed * np.sqrt(1.0 - (b / a) ** 2) / np.sqrt(spring.stiffness)
            out.update(_contact_roundoff(a, depth, out, steady=steady))
        return out

    def _contact_time(self, model: mujoco.MjModel) -> float:
        spring = self._spring(model)
        if spring.direct and spring.elastic:
            return float(np.pi / np.sqrt(spring.stiffness))
        # A damped contact: ten time constants of MuJoCo's standard format (tau clamped to >= 2 dt).
        return 10.0 * max(float(model.geom("projectile").solref[0]), 2 * model.opt.timestep)

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return prediction["_duration"]

    # ---- simulation and measurement -------------------------------------------------------------------------

    def _run_steps(self, model: mujoco.MjModel, contact_time: float) -> int:
        # Lead, then the contact, then as long again: an oblique contact lasts a little longer than pi/sqrt(k).
        return LEAD_STEPS + 2 * int(np.ceil(contact_time / model.opt.timestep)) + LEAD_STEPS

    def simulate(
        self, model: mujoco.MjModel, data: mujoco.MjData, duration: float, *, control: np.ndarray | None = None
    ) -> CollisionRun:
        traj = simulate(model, data, duration, control=control)
        m1, m2, a = self._geometry(model)
        s = self._state(model, data.qpos, data.qvel)
        speed = float(np.linalg.norm(s["v1"] - s["v2"]))
        b = float(np.linalg.norm((s["x1"] - s["x2"])[1:]))
        lead = LEAD_STEPS * model.opt.timestep
        runs: dict[str, tuple[mujoco.MjModel, float]] = {}
        spring = self._spring(model)
        if spring.direct and spring.elastic and b > 0:
            softer = copy.copy(model)
            for name in ("projectile", "target"):
                softer.geom(name).solref[0] = model.geom(name).solref[0] / SOFTER
            runs["softer"] = (softer, b)
        if m1 > m2:
            runs["b0"] = (model, scattering.critical_impact_parameter(a, m1 / m2))
        elif m1 < m2:
            runs["b0"] = (model, 0.0)  # the largest angle, pi, at b = 0
        probes = {}
        if runs:
            models = [m for m, _ in runs.values()]
            qpos = np.repeat(data.qpos[None], len(runs), axis=0)
            qvel = np.repeat(data.qvel[None], len(runs), axis=0)
            for i, (_, bi) in enumerate(runs.values()):
                pos, _ = self.place(a, bi, speed, lead)
                self._state(model, qpos[i], qvel[i])["x1"][:] = pos
            nstep = max(self._run_steps(m, self._contact_time(m)) for m in models)
            states, diverged = final_states(models, initial_states(model, data, qpos, qvel), nstep, nthread=1)
            for i, name in enumerate(runs):
                probes[name] = np.where(diverged[i], np.nan, states[i])
        return CollisionRun(time=traj.time, qpos=traj.qpos, qvel=traj.qvel, diverged_at=traj.diverged_at, probes=probes)

    def outgoing(self, model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray, v0: np.ndarray) -> dict[str, Any]:
        """Angles and energies of a finished collision from its final state (rows or one state).

        `v0` is the projectile's initial velocity (the beam direction). NaN where the spheres still overlap.
        """
        m1, m2, a = self._geometry(model)
        s = self._state(model, qpos, qvel)
        v1, v2 = s["v1"], s["v2"]
        rel = s["x1"] - s["x2"]
        apart = (np.linalg.norm(rel, axis=-1) > a) & (np.einsum("...i,...i", rel, v1 - v2) >= 0)
        nan = np.where(apart, 1.0, np.nan)
        return {
            "theta": _angle(v1 - v2, v0) * nan,
            "psi": _angle(v1, v0) * nan,
            "zeta": _angle(v2, v0) * nan,
            "v1": v1,
            "v2": v2,
            "apart": apart,
        }

    def measure(self, model: mujoco.MjModel, traj: CollisionRun, prediction: Mapping[str, Any]) -> dict[str, float]:
        m1, m2, a = self._geometry(model)
        s0 = self._state(model, traj.qpos[0], traj.qvel[0])
        u = s0["v1"] - s0["v2"]
        out = self.outgoing(model, traj.qpos[-1], traj.qvel[-1], s0["v1"])
        v1, v2 = out["v1"], out["v2"]
        t0 = 0.5 * m1 * u @ u
        p0 = m1 * s0["v1"] + m2 * s0["v2"]
        rel_f = v1 - v2
        impulse = rel_f - u
        n = impulse / np.linalg.norm(impulse)
        speed_ratio = np.linalg.norm(v1) / np.linalg.norm(s0["v1"])
        result = {
            "cm-angle": out["theta"],
            "cm-angle-hard": out["theta"],
            "projectile-lab-angle": out["psi"],
            "target-lab-angle": out["zeta"],
            "projectile-lab-angle-hard": out["psi"],
            "target-lab-angle-hard": out["zeta"],
            "projectile-energy": 0.5 * m1 * v1 @ v1 / t0,
            "target-energy": 0.5 * m2 * v2 @ v2 / t0,
            "projectile-speed": speed_ratio,
            "momentum": float(np.linalg.norm(m1 * v1 + m2 * v2 - p0) / np.linalg.norm(p0)),
            "energy": abs(0.5 * m1 * v1 @ v1 + 0.5 * m2 * v2 @ v2 - t0) / t0,
            "restitution": -(rel_f @ n) / (u @ n),
            "opening-angle": out["psi"] + out["zeta"],
            "soft-shift-exponent": float("nan"),
            "max-lab-angle": float("nan"),
        }
        result["contact-time"] = contact_time(traj.time, self._state(model, traj.qpos, traj.qvel), a)
        theta_hard = prediction["cm-angle-hard"]
        if "softer" in traj.probes:
            state = traj.probes["softer"]
            soft = self.outgoing(model, *self._split(model, state), s0["v1"])["theta"]
            d_k = abs(theta_hard - out["theta"])
            d_soft = abs(theta_hard - soft)
            result["soft-shift-exponent"] = float(np.log(d_soft / d_k) / np.log(SOFTER))
        if "b0" in traj.probes:
            result["max-lab-angle"] = float(
                self.outgoing(model, *self._split(model, traj.probes["b0"]), s0["v1"])["psi"]
            )
        return {k: float(v) for k, v in result.items()}

    @staticmethod
    def _split(model: mujoco.MjModel, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return state[..., 1 : 1 + model.nq], state[..., 1 + model.nq : 1 + model.nq + model.nv]


def contact_time(time: np.ndarray, states: Mapping[str, np.ndarray], a: float) -> float:
    """Time (s) the spheres spend within a of each other, from a run's rows (`HardSpheres._state` of every step):
    the entry time extrapolated forward from the last row before the contact, the exit time backward from the
    first row after it, both along the free flight (straight lines: exact there). NaN if the run has no complete
    contact (no overlap, or the spheres still touch at its end)."""
    r = states["x1"] - states["x2"]
    v = states["v1"] - states["v2"]
    inside = np.flatnonzero(np.linalg.norm(r, axis=-1) < a)
    if inside.size == 0 or inside[0] == 0 or inside[-1] + 1 >= len(time):
        return float("nan")

    def crossing(i: int, sign: float) -> float:
        # The s >= 0 at which |r_i + sign v_i s| = a: the nearer root of the quadratic.
        vv, rv, rr = v[i] @ v[i], sign * (r[i] @ v[i]), r[i] @ r[i] - a * a
        return float((-rv - np.sqrt(max(rv * rv - vv * rr, 0.0))) / vv)

    first, last = int(inside[0]) - 1, int(inside[-1]) + 1
    return float(time[last] - crossing(last, -1.0) - (time[first] + crossing(first, 1.0)))


def _angle(v: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Angle (rad) between vectors (stacked rows), by atan2 of |v x w| and v . w (accurate near 0 and pi)."""
    cross = np.linalg.norm(np.cross(v, w), axis=-1)
    return np.arctan2(cross, np.einsum("...i,...i", v, np.broadcast_to(w, np.shape(v))))


class HardSpheresEnv(FreePairEnv):
    """``rigidbench/HardSpheres-v0``: one collision of two smooth spheres, scored against theory every step.

    Description
        A projectile sphere (m1, r1) moving along +x at ``speed`` with impact parameter ``b`` (along +y) hits a
        target sphere (m2, r2) at rest at the origin; gravity off, frictionless, elastic. With zero action the
        relative coordinate follows the soft-contact spring V = 1/2 mu k (a - r)^2 exactly, whose deflection is
        docs/theory.md C8 and tends to the hard-sphere theta = 2 arccos(b/a) (C5) as k grows.

    Observation Space
        Box(-inf, inf, (12,)), float64:

        ====  ==========================================  =====  ======================================
        idx   quantity                                    unit   MuJoCo source
        ====  ==========================================  =====  ======================================
        0-2   projectile centre, world frame              m      qpos of free joint ``projectile``
        3-5   target centre, world frame                  m      qpos of free joint ``target``
        6-8   projectile velocity, world frame            m/s    qvel (linear part) of ``projectile``
        9-11  target velocity, world frame                m/s    qvel (linear part) of ``target``
        ====  ==========================================  =====  ======================================

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = max_force = 1`` N times it is a force on the
        projectile in world axes, through ``xfrc_applied``; out-of-range actions are clipped.
        Zero action = the textbook problem.

    Rewards
        ``reward = -|r - r_theory(t)| / a``: the distance between the simulated relative position
        r = x1 - x2 and the soft-contact solution (`analytic.scattering.soft_sphere_relative_motion`), in units
        of the contact distance a = r1 + r2; ``info["measured"]`` and ``info["predicted"]`` hold r as
        ``r_x, r_y, r_z`` (m).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        Target at rest at the origin; the projectile touches it after 20 physics steps.

    Episode End
        Truncated once the collision is over (20 steps of lead, twice the contact time pi/sqrt(k), 20 more
        steps); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (head-on, equal-mass, light-projectile, heavy-projectile, heavy-projectile-short, grazing),
        ``params`` (m1, m2, r1, r2, speed, b, stiffness), ``profile``, ``integrator``, ``timestep``,
        ``frame_skip`` (default 40, i.e. 20 us), ``render_mode``. ``reset(options={"params": {"b": 0.02}})``
        chooses the impact parameter, masses and radii per episode.

    Version History
        v0: initial version.
    """

    scenario_cls = HardSpheres
    default_frame_skip: ClassVar[int] = 40
    max_force: ClassVar[float] = 1.0

    def load(self, case: str, params) -> None:
        super().load(case, params)
        # Read or written every step (issue 8): the joints' addresses (`HardSpheres._state` looks four up by name,
        # ~0.4 us each), the projectile's id and the contact distance a, cached here; views into `self.data`
        # (`bind_views`).
        model = self.model
        adr = {name: model.joint(name).id for name in ("projectile", "target")}
        self._slices = tuple(
            (array, slice(int(start[adr[name]]), int(start[adr[name]]) + 3))
            for array, start in (("qpos", model.jnt_qposadr), ("qvel", model.jnt_dofadr))
            for name in ("projectile", "target")
        )
        self._body_id = model.body("projectile").id
        self._scale = float(self.prediction["_a"])  # the deviation's length: the contact distance a
        self.start_views()

    # The soft-contact solutions (closures over scipy's dense output), one per configuration: solved again by a copy
    # that needs one.
    _recomputed: ClassVar[tuple[str, ...]] = ("_motions", "_motion")

    def theory(self, t: np.ndarray) -> np.ndarray:
        """r(t) of the soft-contact ODE (zero action), shape (len(t), 3); solved once per configuration (its initial
        relative state, contact distance, stiffness and run length), not at every reset: a 33-step episode spent
        ~36 ms of each reset on it."""
        p = self.prediction
        key = (tuple(p["_r0"].tolist()), tuple(p["_v0"].tolist()), p["_a"], p["_spring"].stiffness, p["_duration"])
        motions = self.__dict__.setdefault("_motions", {})
        if key not in motions:
            if len(motions) >= 16:  # a few configurations are reused; params drawn per episode are not
                motions.clear()
            motions[key] = scattering.soft_sphere_relative_motion(
                p["_r0"], p["_v0"], p["_a"], p["_spring"].stiffness, p["_duration"] * 1.5
            )
        self._motion = motions[key]
        r, _ = self._motion(np.atleast_1d(np.asarray(t, dtype=float)) - p["_t0"])
        return r.T
