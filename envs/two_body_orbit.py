"""Two free bodies under a central force, in the LAB and CM views: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md K1-K5 (Wilcox Part II chapter 8, eqs 8.33-8.39, 8.64-8.78, 8.118, 8.132-8.137, 8.148; Harter's
"Ptolemaic vs Copernican views" and CoulIt pictures, seed 001), in `rigidbench.analytic.orbits`. Model:
``models/two_body_orbit.xml``: two free bodies, gravity off, joined either by a zero-length spatial tendon spring
(Hooke, native MuJoCo) or by an inverse-square attraction declared for `rigidbench.forces` (Kepler, added by
MuJoCo's passive-force callback at every RK4 stage).

The bodies start at an apsis of their relative orbit, ``r = r1 - r2`` along +x, the relative velocity along +y,
with the CM at the origin, at rest (the CM view) or moving along +y (the LAB view with body 2 initially at rest,
as in 001). Every orbit check reads the bodies about the CM line the initial state predicts, ``R0 + V0 t``: a
CM that wanders shows in every one of them, and in ``cm-motion``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from rigidbench import forces, signals
from rigidbench.analytic import orbits
from rigidbench.contract import Case, Check, Derived, Domain, Scenario, Trajectory, round_step
from rigidbench.envs.pair import FreePairEnv
from rigidbench.params import Numeric, Param, Range, ScaledBodyMass, Value

# Reference timestep (`TwoBodyOrbit.reference_settings`), a fixed fraction of the fastest time scale:
# - kepler: the pericentre passage t_p = r_p / v_p. KEPLER_STEP = 0.01: RK4's orbit error is ~3.5e-9 a over three
#   periods at e = 0.44 and 1.6e-8 a at e = 0.77 (measured; / 16 per halving of the step, fourth order);
# - hooke: 1 / w, w = sqrt(k / mu). HOOKE_STEP = 0.005: the linear oscillator's phase error (w h)^4 / 120 = 5e-12
#   per radian, 3e-11 a over 2.25 periods.
KEPLER_STEP = 0.01
HOOKE_STEP = 0.005
# Run length: 2.25 periods (two whole periods for the virial average, two azimuth crossings of pi + 2 pi j for the
# period, and four Kepler or eight Hooke apsides).
PERIODS = 2.25
# Largest Kepler eccentricity covered: the pericentre passage lasts t_p = T (1 - e)^(3/2) / (2 pi sqrt(1 + e)), so a
# run holds 2.25 T / (0.01 t_p) steps: 2.1e4 at e = 0.8 (up to 4.2e4 where the step's rounding down to one digit halves
# it), each paying the Python force callback four times (~110-130 us a step on this shared machine), 3-5 s; beyond, the
# run budget goes to resolving one pericentre.
MAX_KEPLER_ECCENTRICITY = 0.8
# Smallest eccentricity whose apsides are measured: an apsis is where r . v = 0, whose slope there is ~e w^2 a^2, so
# an orbit error delta (in units of a) moves it by ~delta / e rad in azimuth; a circle has none.
MIN_ECCENTRICITY = 0.01
# The orbit error the checks allow (units of the orbit's semi-major axis): ten times RK4's worst measured over the
# ranges, 1.0e-8 at e = 0.8 over 2.25 periods (a census of 60 sets and the ranges' corners: e = 0.8 at either apsis,
# m1/m2 = 1/100 and 100, cm_speed = +-3, hooke s = 0.1 and 3).
ORBIT_ERROR = 1e-7
# energy-partition's tolerance before MuJoCo's round-off floor (`_roundoff_floors`): RK4's energy error (<= 2e-10
# measured over the ranges) times 50.
ENERGY_PARTITION = 1e-8

# The shape checks (e, a, b): set by E and L, which RK4 keeps far better than the phase (~2e-10), read from the
# cubic-interpolated apsides of each body's orbit: measured <= 1.0e-9 (e; Hooke near-circular, where e = sqrt(1 -
# (r_min/r_max)^2) amplifies as 1e-11 / e, e >= 0.01) and <= 3.7e-10 (a, b) over 120 census draws. SHAPE_ERROR is
# ten times that; each run adds the positions' round-off floor of its own orbit (`_roundoff_floors`): up to 7.8e-9
# measured at the ranges' corners (m1/m2 = 100, cm_speed = 3: the heavy body's orbit, a/100, read far from the
# origin), where that floor is 1.3e-8.
SHAPE_ERROR = 1e-8
_SHAPE = (
    "shape from E and L (RK4 keeps them to ~2e-10), read from cubic-interpolated apsides: measured <= 1e-9 over 120 "
    f"census draws (e of a near-circular Hooke orbit: ~1e-11 / e); {SHAPE_ERROR:g} leaves 10x; + the run's "
    "position round-off floor n eps (reach + 2 a_i) / a_i (x 2 for e; x 1/e for a Hooke orbit's e), set per run: a "
    "heavy body's small orbit carried far by a fast CM (7.8e-9 measured at the corners, floor 1.3e-8)"
)
_RK4 = (
    "RK4 at h = 0.01 r_p / v_p (kepler) or 0.005 / w (hooke): orbit error measured <= 1.0e-8 a over the ranges (at "
    "e = 0.8; fourth order, / 16 per halving of h), <= 1e-10 a for hooke"
)
_CONSERVED = (
    "equal and opposite central forces at every RK4 stage conserve momentum and angular momentum to round-off; "
    "RK4 is not symplectic"
)
CHECKS = (
    *(
        Check(
            f"period-{i}",
            "s",
            1e-8,
            "rel",
            _RK4 + f"; the time between two crossings of body {i}'s azimuth about the CM through pi + 2 pi j, "
            "cubic-interpolated: the orbit's phase error over a period, measured <= 4e-10 relative; 1e-8 leaves a "
            "factor 25",
            "K2: T = 2 pi sqrt(mu a^3 / k) (Kepler III, Wilcox section 8.5); K3: T = 2 pi sqrt(mu / k) (Hooke), "
            "the same for both bodies",
        )
        for i in (1, 2)
    ),
    *(
        Check(
            f"eccentricity-{i}",
            "1",
            SHAPE_ERROR,
            "abs",
            _SHAPE + f"; from body {i}'s distance to the CM at its apsides (r.v = 0, cubic-interpolated): e = "
            "(r_max - r_min)/(r_max + r_min) (kepler) or sqrt(1 - (r_min/r_max)^2) (hooke)",
            "K2: e = sqrt(1 + 2 E l^2 / (mu k^2)) (Wilcox eq. 8.78); K3: both CM-frame orbits share it",
        )
        for i in (1, 2)
    ),
    *(
        Check(
            f"semi-major-{i}",
            "m",
            SHAPE_ERROR,
            "rel",
            _SHAPE + f"; (r_max + r_min)/2 (kepler) or r_max (hooke) of body {i} about the CM, cubic-interpolated "
            "apsides",
            "K2: a = -k / (2E); K3: a_i = (mu / m_i) a (a_i m_i = a mu)",
        )
        for i in (1, 2)
    ),
    *(
        Check(
            f"semi-minor-{i}",
            "m",
            SHAPE_ERROR,
            "rel",
            _SHAPE
            + f"; the largest extent of body {i}'s orbit across its measured apse line (extrema located from the "
            "velocity, cubic-interpolated; a tilt delta/e of the apse line moves it by ~e delta)",
            "K2: b = a sqrt(1 - e^2); K3: b_i = (mu / m_i) b",
        )
        for i in (1, 2)
    ),
    *(
        Check(
            f"orbit-{i}",
            "1",
            ORBIT_ERROR,
            "abs",
            _RK4 + f"; max over the run of |r{i}'(t) - r{i}'_theory(t)| / a_{i}, r{i}' about the predicted CM line "
            f"R0 + V0 t: {ORBIT_ERROR:g}, ten times the worst measured, + MuJoCo's round-off floor n eps max|x_{i}| / "
            f"a_{i} (n steps; a heavy body's small orbit carried far by the CM), set per run, listed without it",
            "K3: r1' = (m2/M) r, r2' = -(m1/M) r, mass-scaled copies of r(t): Kepler's equation n t = psi - e sin psi "
            "(K2, Wilcox eq. 8.118), or r0 cos wt + (v0/w) sin wt (Hooke)",
        )
        for i in (1, 2)
    ),
    Check(
        "cm-motion",
        "1",
        1e-9,
        "abs",
        _CONSERVED + ": max |R(t) - R0 - V0 t| / a is round-off, measured <= 3.3e-11 over the ranges (m1/m2 = 100, "
        "cm_speed = 3); 1e-9 leaves a factor 30",
        "K1: R = (m1 r1 + m2 r2) / M moves uniformly (Wilcox eqs 8.33-8.36)",
    ),
    Check(
        "momentum-drift",
        "1",
        1e-9,
        "abs",
        _CONSERVED + ": max |L(t) - L(0)| / |L(0)| about the CM is round-off, measured <= 1.8e-11 over the ranges; "
        "1e-9 leaves a factor 50",
        "K2: L = mu r x v conserved (central force)",
    ),
    Check(
        "energy-drift",
        "1",
        1e-8,
        "abs",
        "RK4's energy error: measured <= 1.9e-10 |E| over the ranges (kepler at e = 0.8, h = 0.01 t_p), <= 5e-13 "
        "(hooke); 1e-8 leaves a factor 50",
        "K2, K3: E = mu v^2 / 2 + U(r) conserved",
    ),
    Check(
        "energy-partition",
        "1",
        ENERGY_PARTITION,
        "abs",
        "max over the run and both bodies of |m_i E_i(t) / (mu E) - 1|: RK4's energy error (<= 2.2e-10 measured) "
        f"times 50, {ENERGY_PARTITION:g}, + MuJoCo's round-off floor n eps m_i^2 max|v_i'| max|v_i| / (mu |E|): each "
        "step rounds the LAB velocity v_i, and a heavy body's small CM-frame velocity v_i' = v_i - V inherits it "
        "(measured 1.5e-8 at m1/m2 = 100, e = 0.8, cm_speed = 3, where the floor is 2.8e-8); set per run, listed "
        "without it",
        "K3 [DONE]: E_i = m_i v_i'^2/2 + U_i(r_i') with U_i = -k (m_j/M)^2 / r_i' (Kepler) or k (M/m_j) r_i'^2/2 "
        "(Hooke) is conserved and equals (mu / m_i) E",
    ),
    Check(
        "virial",
        "1",
        1e-8,
        "rel",
        "2 <T> / (-<U>) (kepler) or <T> / <U> (hooke) over two whole predicted periods from an apsis: cumulative "
        "Simpson quadrature of the samples (fourth order in h, 100 steps per pericentre passage), interpolated at "
        "2 T, plus the orbit error: measured <= 1.0e-9 over the ranges (e = 0.8); 1e-8 leaves a factor 10",
        "K4: <T> = -<U>/2 = -E (Kepler), <T> = <U> (Hooke) (Wilcox section 8.8, eq. 8.148)",
    ),
    Check(
        "apsidal-angle",
        "rad",
        ORBIT_ERROR / MIN_ECCENTRICITY,
        "abs",
        "azimuth of r from an apsis (r.v = 0, cubic-interpolated) to the next, the one farthest from theory: r.v "
        "has slope ~e w^2 a^2 there, so an orbit error delta moves an apsis by ~delta / e rad; tolerance "
        f"{ORBIT_ERROR:g} / e, set per run, listed at the smallest e = {MIN_ECCENTRICITY:g}",
        "K5: pi / sqrt(3 - n) for F = -k / r^n: pi (Kepler, n = 2), pi/2 (Hooke, n = -1); exact at every e for "
        "these closed orbits (Wilcox section 8.7)",
    ),
)
_ALL = tuple(c.name for c in CHECKS)


@dataclass(frozen=True)
class TendonStiffness:
    """The linear stiffness (N/m) of a spatial tendon (its spring's higher-order coefficients stay 0); a tendon with
    none is drawn transparent (it exerts no force)."""

    tendon: str

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        tendon = spec.tendon(self.tendon)
        tendon.stiffness = [float(value), 0.0, 0.0]
        if float(value) == 0.0:
            tendon.rgba = [*tendon.rgba[:3], 0.0]

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.tendon_stiffness[model.tendon(self.tendon).id])


@dataclass(frozen=True)
class InverseSquareStrength:
    """The strength k (N m^2) of the model's one inverse-square attraction, U = -k / r (`rigidbench.forces`): the
    declaration's strength is -k; k = 0 removes the declaration (no force, no callback)."""

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        numeric, text = spec.numeric(forces.INVERSE_SQUARE), spec.text(forces.INVERSE_SQUARE)
        if float(value) == 0.0:
            spec.delete(numeric)
            spec.delete(text)
        else:
            numeric.data = [-float(value)]

    def read(self, model: mujoco.MjModel) -> Value:
        law = forces.inverse_square(model)
        return 0.0 if law is None else float(-law.k[0])


def _law(p: Mapping[str, Any]) -> str:
    return "kepler" if p["strength"] > 0 else "hooke"


def _mu(p: Mapping[str, Any]) -> float:
    return orbits.reduced_mass(p["m1"], p["m2"])


def _time_scale(p: Mapping[str, Any]) -> tuple[float, str]:
    """The fastest time scale (s) of the requested orbit, and its rule in words."""
    mu, r0, s = _mu(p), p["separation"], p["speed_ratio"]
    if _law(p) == "hooke":
        w = math.sqrt(p["stiffness"] / mu)
        return 1.0 / w, f"1 / w = sqrt(mu / k) = {1.0 / w:.4g} s"
    r_p, v_p = orbits.launch_pericentre(mu, p["strength"], r0, s)
    return r_p / v_p, f"r_p / v_p = {r_p:.4g} m / {v_p:.4g} m/s = {r_p / v_p:.4g} s"


def _body2_at_rest(p: Mapping[str, Any]) -> float:
    """cm_speed for the LAB view of 001: body 2 starts at rest, so V = (m1 / M) v0."""
    return p["m1"] / (p["m1"] + p["m2"])


def _one_law(p: Mapping[str, Any]) -> str | None:
    if (p["stiffness"] > 0) == (p["strength"] > 0):
        return f"stiffness = {p['stiffness']:g} N/m and strength = {p['strength']:g} N m^2 (one must be 0, not both)"
    return None


def _apsides(p: Mapping[str, Any]) -> str | None:
    e = orbits.launch_eccentricity(_law(p), p["speed_ratio"])
    if e < MIN_ECCENTRICITY:
        return f"speed_ratio = {p['speed_ratio']:.10g} ({_law(p)}: e = {e:.3g})"
    return None


def _kepler_budget(p: Mapping[str, Any]) -> str | None:
    if _law(p) != "kepler":
        return None
    s = p["speed_ratio"]
    if s * s >= 2:
        return f"speed_ratio = {s:.10g} (E = k (s^2/2 - 1) / r0 >= 0: unbound)"
    e = orbits.launch_eccentricity("kepler", s)
    if e > MAX_KEPLER_ECCENTRICITY:
        return f"speed_ratio = {s:.10g} (e = |s^2 - 1| = {e:.3g})"
    return None


DOMAINS = (
    Domain(
        "one-force-law",
        "K2 (Kepler) or K3 (Hooke)",
        "exactly one of stiffness (the zero-length spring, U = k r^2/2) and strength (the inverse-square attraction, "
        "U = -k/r) is nonzero: the closed forms cover one law at a time",
        _one_law,
    ),
    Domain(
        "bound-ellipse",
        "K2 (Wilcox eqs 8.70-8.78)",
        f"kepler: a bound ellipse, E < 0 (speed_ratio s < sqrt(2): at or above it the bodies escape on a parabola or "
        f"hyperbola, the rutherford scenario's theory), with e = |s^2 - 1| <= {MAX_KEPLER_ECCENTRICITY:g}: the "
        "pericentre passage lasts (1 - e)^(3/2) / (2 pi sqrt(1 + e)) of a period and the reference step resolves it "
        "with 100 steps, so beyond e = 0.8 a run of 2.25 periods exceeds 2.1e4-4.2e4 steps of the Python force "
        "callback (3-5 s)",
        _kepler_budget,
    ),
    Domain(
        "apsides",
        "K5 (apsidal angle), K2 (eccentricity)",
        f"e >= {MIN_ECCENTRICITY:g} (kepler e = |s^2 - 1|, hooke e = sqrt(1 - min(s, 1/s)^2)): a circular orbit has "
        "no apsides, and an orbit error delta moves a measured apsis by ~delta / e rad",
        _apsides,
    ),
)

# The regimes of the cases: the Kepler cases leave the spring out and the Hooke cases the attraction; the law they keep
# has a strength of at least 1e-2 (a census draws it over five decades, log-uniformly).
_KEPLER_ONLY = {"stiffness": Range(0.0, 0.0), "strength": Range(1e-2, 1e3)}
_HOOKE_ONLY = {"strength": Range(0.0, 0.0), "stiffness": Range(1e-2, 1e3)}
_KEPLER_REGIME = (
    f"the attraction alone (stiffness 0); a bound ellipse with e = |s^2 - 1| <= {MAX_KEPLER_ECCENTRICITY:g} "
    "(domain 'bound-ellipse': s < sqrt(2) is E < 0)"
)


class TwoBodyOrbit(Scenario):
    """Two free bodies bound by a zero-length spring or an inverse-square attraction, read in the LAB and CM frames:
    periods, eccentricities and semi-axes of both CM-frame orbits (mass-scaled copies of the relative orbit), the CM
    moving uniformly, conservation, energy partition, the virial theorem and the apsidal angle (docs/theory.md
    K1-K5)."""

    slug = "two-body-orbit"
    title = "Two-body orbits, LAB vs CM (Kepler and Hooke)"
    env_id = "rigidbench/TwoBodyOrbit-v0"
    params = (
        Param(
            "m1", "kg", "mass of body 1 (explicit inertia scaled with it)", Range(0.1, 10.0), ScaledBodyMass("body1")
        ),
        Param(
            "m2", "kg", "mass of body 2 (explicit inertia scaled with it)", Range(0.1, 10.0), ScaledBodyMass("body2")
        ),
        Param(
            "stiffness",
            "N/m",
            "k of the zero-length spring between the centres (U = k r^2 / 2, the tendon 'spring'); 0 switches it off",
            Range(0.0, 1e3),
            TendonStiffness("spring"),
        ),
        Param(
            "strength",
            "N m^2",
            "k of the inverse-square attraction between the centres (U = -k / r, rigidbench.forces); 0 switches it off",
            Range(0.0, 1e3),
            InverseSquareStrength(),
        ),
        Param(
            "separation",
            "m",
            "initial distance r0 = |r1 - r2| between the centres, at an apsis, along +x",
            Range(0.1, 10.0),
            Numeric("separation"),
        ),
        Param(
            "speed_ratio",
            "1",
            "initial relative speed (along +y, perpendicular to r) in units of the circular speed at r0: "
            "sqrt(k / (mu r0)) (kepler) or r0 sqrt(k / mu) (hooke)",
            Range(0.1, 3.0),
            Numeric("speed_ratio"),
        ),
        Param(
            "cm_speed",
            "1",
            "initial CM velocity along +y in units of the relative speed: 0 is the CM view, m1 / M has body 2 at rest "
            "(001's LAB view)",
            Range(-3.0, 3.0),
            Numeric("cm_speed"),
        ),
    )
    cases = (
        Case(
            "kepler",
            "inverse-square attraction, e = 0.44, CM at rest: both bodies trace ellipses with a focus at the CM",
            {"stiffness": 0.0, "strength": 100.0, "speed_ratio": 1.2, "cm_speed": 0.0},
            _ALL,
            ranges={**_KEPLER_ONLY, "speed_ratio": Range(0.1, 1.41)},
            regime=_KEPLER_REGIME + "; s <= 1.41 < sqrt(2)",
        ),
        Case(
            "kepler-eccentric",
            "inverse-square attraction, e = 0.69, LAB view: body 2 starts at rest, the CM moves at m1/M v0",
            {
                "m1": 1.0,
                "m2": 3.0,
                "stiffness": 0.0,
                "strength": 100.0,
                "speed_ratio": 1.3,
                "cm_speed": _body2_at_rest,
            },
            _ALL,
            ranges={**_KEPLER_ONLY, "speed_ratio": Range(1.2, 1.34)},
            regime=_KEPLER_REGIME + "; eccentric: e >= 0.44",
        ),
        Case(
            "kepler-near-circular",
            "a perturbed circular Kepler orbit (speed 1.02 v_c, e = 0.04): the apsidal angle pi (K5, n = 2)",
            {"stiffness": 0.0, "strength": 100.0, "speed_ratio": 1.02, "cm_speed": 0.0},
            _ALL,
            ranges={**_KEPLER_ONLY, "speed_ratio": Range(0.95, 1.05)},
            regime=_KEPLER_REGIME + "; near-circular: |s - 1| <= 0.05 (and e >= 0.01, domain 'apsides')",
        ),
        Case(
            "hooke",
            "zero-length spring, semi-axes r0 and 0.6 r0, LAB view (body 2 starts at rest): ellipses centred on the "
            "moving CM",
            {"stiffness": 30.0, "strength": 0.0, "speed_ratio": 0.6, "cm_speed": _body2_at_rest},
            _ALL,
            ranges=_HOOKE_ONLY,
            regime="the spring alone (strength 0)",
        ),
        Case(
            "hooke-near-circular",
            "a perturbed circular Hooke orbit (speed 1.02 v_c, b/a = 0.98): the apsidal angle pi/2 (K5, n = -1)",
            {"stiffness": 30.0, "strength": 0.0, "speed_ratio": 1.02, "cm_speed": 0.0},
            _ALL,
            ranges={**_HOOKE_ONLY, "speed_ratio": Range(0.95, 1.05)},
            regime="the spring alone (strength 0); near-circular: |s - 1| <= 0.05 (and e >= 0.01, domain 'apsides')",
        ),
    )
    checks = CHECKS
    domains = DOMAINS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        scale, rule = _time_scale(params)
        fraction = KEPLER_STEP if _law(params) == "kepler" else HOOKE_STEP
        h = round_step(fraction * scale)
        return {"timestep": Derived(h, f"{fraction:g} x {rule}, rounded down to one digit: {h:.1g} s")}

    @staticmethod
    def _addresses(model: mujoco.MjModel) -> tuple[int, int, int, int]:
        """qpos and qvel addresses of the two free joints: (qpos1, qpos2, qvel1, qvel2)."""
        j1, j2 = model.joint("body1").id, model.joint("body2").id
        return (
            int(model.jnt_qposadr[j1]),
            int(model.jnt_qposadr[j2]),
            int(model.jnt_dofadr[j1]),
            int(model.jnt_dofadr[j2]),
        )

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        m1, m2 = float(model.body("body1").mass[0]), float(model.body("body2").mass[0])
        law = "kepler" if params["strength"] > 0 else "hooke"
        k = params["strength"] if law == "kepler" else params["stiffness"]
        r0, v0 = orbits.launch(law, orbits.reduced_mass(m1, m2), k, params["separation"], params["speed_ratio"])
        x1, x2, v1, v2 = orbits.lab_states(m1, m2, r0, v0, params["cm_speed"] * v0)
        q1, q2, d1, d2 = self._addresses(model)
        data.qpos[q1 : q1 + 7] = [*x1, 1.0, 0.0, 0.0, 0.0]
        data.qpos[q2 : q2 + 7] = [*x2, 1.0, 0.0, 0.0, 0.0]
        data.qvel[d1 : d1 + 6] = [*v1, 0.0, 0.0, 0.0]
        data.qvel[d2 : d2 + 6] = [*v2, 0.0, 0.0, 0.0]

    def _states(self, model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, ...]:
        """x1, x2, v1, v2 (world frame, m and m/s), shape (n, 3) each, from state rows."""
        q1, q2, d1, d2 = self._addresses(model)
        qpos, qvel = np.atleast_2d(qpos), np.atleast_2d(qvel)
        return qpos[:, q1 : q1 + 3], qpos[:, q2 : q2 + 3], qvel[:, d1 : d1 + 3], qvel[:, d2 : d2 + 3]

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        m1, m2 = float(model.body("body1").mass[0]), float(model.body("body2").mass[0])
        mu, total = orbits.reduced_mass(m1, m2), m1 + m2
        attraction = forces.inverse_square(model)
        x1, x2, v1, v2 = (a[0] for a in self._states(model, data.qpos, data.qvel))
        if attraction is not None:
            orbit = orbits.kepler_orbit(mu, float(-attraction.k[0]), x1 - x2, v1 - v2)
        else:
            orbit = orbits.hooke_orbit(mu, float(model.tendon_stiffness[model.tendon("spring").id]), x1 - x2, v1 - v2)
        bodies = orbits.body_orbits(m1, m2, orbit)
        cm0, cm_velocity = (m1 * x1 + m2 * x2) / total, (m1 * v1 + m2 * v2) / total
        out: dict[str, Any] = {
            "_theory": orbit,
            "_bodies": bodies,
            "_masses": (m1, m2),
            "_cm0": cm0,
            "_cm_velocity": cm_velocity,
            "_tolerance": {
                "apsidal-angle": ORBIT_ERROR / orbit.eccentricity,
                **_roundoff_floors(model, orbit, bodies, cm0, cm_velocity),
            },
            "cm-motion": 0.0,
            "momentum-drift": 0.0,
            "energy-drift": 0.0,
            "energy-partition": 0.0,
            "virial": 1.0,
            "apsidal-angle": orbit.apsidal_angle,
        }
        for i, body in enumerate(bodies, start=1):
            out[f"period-{i}"] = body.period
            out[f"eccentricity-{i}"] = body.eccentricity
            out[f"semi-major-{i}"] = body.semi_major
            out[f"semi-minor-{i}"] = body.semi_minor
            out[f"orbit-{i}"] = 0.0
        return out

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return PERIODS * prediction["_theory"].period

    def cm_frame(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, Any]:
        """The trajectory in the LAB and CM views: positions x_i, CM R (world, m), and r_i', v_i' about the
        predicted CM line R0 + V0 t (m, m/s), shape (n, 3) each."""
        x1, x2, v1, v2 = self._states(model, traj.qpos, traj.qvel)
        m1, m2 = prediction["_masses"]
        t = np.asarray(traj.time)[:, None]
        centre = prediction["_cm0"] + prediction["_cm_velocity"] * t
        velocity = prediction["_cm_velocity"]
        return {
            "x1": x1,
            "x2": x2,
            "cm": (m1 * x1 + m2 * x2) / (m1 + m2),
            "centre": centre,
            "r1": x1 - centre,
            "r2": x2 - centre,
            "v1": v1 - velocity,
            "v2": v2 - velocity,
        }

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        orbit: orbits.Orbit = prediction["_theory"]
        m1, m2 = prediction["_masses"]
        mu = orbits.reduced_mass(m1, m2)
        t = np.asarray(traj.time)
        v = self.cm_frame(model, traj, prediction)
        r_rel, v_rel = v["x1"] - v["x2"], v["v1"] - v["v2"]
        plane_z = orbit.momentum / np.linalg.norm(orbit.momentum)
        out: dict[str, float] = {}
        rel_theory, _ = orbit.position(t)
        for i, body in enumerate(prediction["_bodies"], start=1):
            r, vel = v[f"r{i}"], v[f"v{i}"]
            shape = _ellipse(t, r, vel, plane_z, orbit.law)
            out[f"period-{i}"] = shape["period"]
            out[f"eccentricity-{i}"] = _farthest(shape["eccentricity"], body.eccentricity)
            out[f"semi-major-{i}"] = _farthest(shape["semi_major"], body.semi_major)
            out[f"semi-minor-{i}"] = _farthest(shape["semi_minor"], body.semi_minor)
            out[f"orbit-{i}"] = float(np.max(_norm(r - body.scale * rel_theory)) / body.semi_major)
        cm = v["cm"]
        out["cm-motion"] = float(np.max(_norm(cm - v["centre"])) / orbit.semi_major)
        momentum = m1 * np.cross(v["r1"], v["v1"]) + m2 * np.cross(v["r2"], v["v2"])
        out["momentum-drift"] = signals.max_relative_drift(momentum)
        kinetic = 0.5 * (m1 * _dot(v["v1"], v["v1"]) + m2 * _dot(v["v2"], v["v2"]))
        potential = orbit.potential(_norm(r_rel))
        energy = kinetic + potential
        out["energy-drift"] = float(np.max(np.abs(energy - energy[0])) / abs(energy[0]))
        partition = [
            orbits.body_energy(mass, body, orbit.law, v[f"r{i}"], v[f"v{i}"]) * mass / (mu * orbit.energy) - 1.0
            for i, (mass, body) in enumerate(zip((m1, m2), prediction["_bodies"], strict=True), start=1)
        ]
        out["energy-partition"] = float(np.max(np.abs(partition)))
        out["virial"] = _virial(t, kinetic, potential, orbit)
        out["apsidal-angle"] = _apsidal(t, r_rel, v_rel, plane_z, orbit)
        return out


def _roundoff_floors(
    model: mujoco.MjModel, orbit: orbits.Orbit, bodies: tuple, cm0: np.ndarray, cm_velocity: np.ndarray
) -> dict[str, float]:
    """The checks' tolerances with MuJoCo's round-off floor added where a body's CM-frame motion rides on a larger
    LAB motion (a heavy body, a fast CM): each of the n steps rounds the LAB velocity v_i and position x_i to an ulp,
    systematically where the step's increment is far below one, so v_i' = v_i - V may drift by n eps max|v_i| and
    r_i' by n eps max|x_i| (measured 1.5e-8 in energy-partition at m1/m2 = 100, e = 0.8, cm_speed = 3, where this
    bound gives 2.8e-8). energy-partition: dE_i = m_i v_i' . dv_i against |E_i| = mu |E| / m_i; orbit-i: against
    a_i."""
    m = (float(model.body("body1").mass[0]), float(model.body("body2").mass[0]))
    n = round(PERIODS * orbit.period / model.opt.timestep)
    eps = float(np.finfo(float).eps)
    _, v = orbit.position(np.linspace(0.0, orbit.period, 257))
    speed = float(np.max(_norm(v)))  # the largest relative speed (at the pericentre)
    cm_speed = float(np.linalg.norm(cm_velocity))
    reach = float(np.linalg.norm(cm0)) + cm_speed * PERIODS * orbit.period  # the farthest the CM goes
    energy = max(
        mi * mi * abs(b.scale) * speed * (cm_speed + abs(b.scale) * speed) for mi, b in zip(m, bodies, strict=True)
    )
    floors = {"energy-partition": ENERGY_PARTITION + n * eps * energy / (orbit.mu * abs(orbit.energy))}
    hooke = forces.inverse_square(model) is None
    for i, b in enumerate(bodies, start=1):
        position = n * eps * (reach + b.semi_major * 2) / b.semi_major
        floors[f"orbit-{i}"] = ORBIT_ERROR + position
        # The shape read from the apsides: a and b relative, e absolute (x 2 from (r_max - r_min) / (r_max + r_min);
        # a Hooke orbit's sqrt(1 - (r_min/r_max)^2) amplifies by 1/e).
        floors[f"semi-major-{i}"] = floors[f"semi-minor-{i}"] = SHAPE_ERROR + position
        floors[f"eccentricity-{i}"] = SHAPE_ERROR + position * (1 / orbit.eccentricity if hooke else 2.0)
    return floors


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def _norm(a: np.ndarray) -> np.ndarray:
    return np.sqrt(_dot(a, a))


def _farthest(values: np.ndarray, expected: float) -> float:
    """The value farthest from `expected` (NaN if there is none: the check then fails)."""
    values = np.asarray(values, dtype=float)
    return float(values[np.argmax(np.abs(values - expected))]) if values.size else math.nan


def _azimuth(r: np.ndarray, plane_z: np.ndarray) -> np.ndarray:
    """Unwrapped azimuth (rad) of r in the orbit plane (normal `plane_z`, the sense of L), from r[0]'s direction."""
    x = r[0] / np.linalg.norm(r[0])
    y = np.cross(plane_z, x)
    return np.unwrap(np.arctan2(r @ y, r @ x))


def _apsis_events(t: np.ndarray, r: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times of the apsides (r . v = 0, cubic-interpolated) and whether each is a maximum of |r|."""
    rv = _dot(r, v)
    up, down = signals.crossings(t, rv, +1), signals.crossings(t, rv, -1)  # + -> minimum of |r|, - -> maximum
    times = np.concatenate([up, down])
    is_max = np.concatenate([np.zeros(len(up), bool), np.ones(len(down), bool)])
    order = np.argsort(times)
    return times[order], is_max[order]


def _at(t: np.ndarray, y: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Cubic interpolation of each column of y (n, 3) at `times`."""
    return np.stack([signals.interpolate(t, y[:, j], times) for j in range(y.shape[1])], axis=1)


def _ellipse(t: np.ndarray, r: np.ndarray, v: np.ndarray, plane_z: np.ndarray, law: str) -> dict[str, Any]:
    """Period, eccentricity and semi-axes of one CM-frame orbit from its samples (module docstring)."""
    phase = _azimuth(r, plane_z)
    turns = signals.crossings(t, np.cos(phase / 2))  # azimuth through pi + 2 pi j
    times, is_max = _apsis_events(t, r, v)
    dist = _norm(_at(t, r, times)) if times.size else np.array([])
    r_max, r_min = dist[is_max], dist[~is_max]
    nan = np.array([math.nan])
    if law == "kepler":
        pairs = [(a, b) for a in (r_max if r_max.size else nan) for b in (r_min if r_min.size else nan)]
        ecc = np.array([(a - b) / (a + b) for a, b in pairs])
        semi_major = np.array([(a + b) / 2 for a, b in pairs])
        apse_times = times[~is_max]
    else:
        pairs = [(a, b) for a in (r_max if r_max.size else nan) for b in (r_min if r_min.size else nan)]
        ecc = np.array([math.sqrt(max(0.0, 1 - (b / a) ** 2)) for a, b in pairs])
        semi_major = r_max if r_max.size else nan
        apse_times = times[is_max]
    semi_minor = nan
    if apse_times.size:
        apse = _at(t, r, apse_times[:1])[0]
        across = np.cross(plane_z, apse / np.linalg.norm(apse))
        y, dy = r @ across, v @ across
        _, highs = signals.extrema(t, y, dy, "max")
        _, lows = signals.extrema(t, y, dy, "min")
        semi_minor = np.abs(np.concatenate([highs, lows]))
    return {
        "period": signals.mean_spacing(turns),
        "eccentricity": ecc,
        "semi_major": semi_major,
        "semi_minor": semi_minor,
    }


def _virial(t: np.ndarray, kinetic: np.ndarray, potential: np.ndarray, orbit: orbits.Orbit) -> float:
    """2 <T> / (-<U>) (kepler) or <T> / <U> (hooke) over the whole predicted periods of the run (K4)."""
    from scipy.integrate import cumulative_simpson

    end = math.floor(t[-1] / orbit.period) * orbit.period
    mean_t, mean_u = (
        float(signals.interpolate(t, cumulative_simpson(y, x=t, initial=0.0), np.array([end]))[0]) / end
        for y in (kinetic, potential)
    )
    return 2 * mean_t / -mean_u if orbit.law == "kepler" else mean_t / mean_u


def _apsidal(t: np.ndarray, r: np.ndarray, v: np.ndarray, plane_z: np.ndarray, orbit: orbits.Orbit) -> float:
    """The azimuth swept between successive apsides of the relative orbit, the one farthest from theory (K5)."""
    times, _ = _apsis_events(t, r, v)
    if times.size < 2:
        return math.nan
    phase = signals.interpolate(t, _azimuth(r, plane_z), times)
    return _farthest(np.diff(phase), orbit.apsidal_angle)


class TwoBodyOrbitEnv(FreePairEnv):
    """``rigidbench/TwoBodyOrbit-v0``: two bodies on a Kepler or Hooke orbit, scored against theory every step.

    Description
        Two free bodies (m1, m2), gravity off, attracted by a zero-length spring (U = k r^2/2) or an inverse-square
        force (U = -k/r), started at an apsis of their relative orbit with the CM at rest or moving. With zero
        action it is the textbook two-body problem (docs/theory.md K1-K5): the CM moves uniformly and the relative
        coordinate r = x1 - x2 follows Kepler's equation (K2) or the isotropic oscillator (K3).

    Observation Space
        Box(-inf, inf, (12,)), float64:

        ====  ==========================================  =====  ======================================
        idx   quantity                                    unit   MuJoCo source
        ====  ==========================================  =====  ======================================
        0-2   body 1 centre of mass, world frame          m      qpos of free joint ``body1``
        3-5   body 2 centre of mass, world frame          m      qpos of free joint ``body2``
        6-8   body 1 velocity, world frame                m/s    qvel (linear part) of ``body1``
        9-11  body 2 velocity, world frame                m/s    qvel (linear part) of ``body2``
        ====  ==========================================  =====  ======================================

    Action Space
        Box(-1, 1, (3,)), float32, normalised: ``action_scale = max_force = 1`` N times it is a force on body 1 in
        world axes, through ``xfrc_applied``; out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|r - r_theory(t)| / a``: the distance between the simulated relative position r = x1 - x2 and
        the closed form, in units of the orbit's semi-major axis a; ``info["measured"]`` and ``info["predicted"]``
        hold r as ``r_x, r_y, r_z`` (m).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        The case's apsis: r = separation along +x, relative velocity along +y at speed_ratio times the circular
        speed, CM at the origin moving along +y at cm_speed times the relative speed. Deterministic.

    Episode End
        Truncated after 2.25 periods (the validation run's duration); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (kepler, kepler-eccentric, kepler-near-circular, hooke, hooke-near-circular), ``params`` (m1, m2,
        stiffness, strength, separation, speed_ratio, cm_speed), ``profile``, ``integrator``, ``timestep``,
        ``frame_skip`` (default 10: ten reference steps, 6 ms at the kepler default), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = TwoBodyOrbit

    def load(self, case: str, params) -> None:
        super().load(case, params)
        # Read or written every step: the joints' slices, body 1's id and the semi-major axis, cached here; views into
        # `self.data` (`bind_views`).
        q1, q2, d1, d2 = TwoBodyOrbit._addresses(self.model)
        self._slices = (
            ("qpos", slice(q1, q1 + 3)),
            ("qpos", slice(q2, q2 + 3)),
            ("qvel", slice(d1, d1 + 3)),
            ("qvel", slice(d2, d2 + 3)),
        )
        self._body_id = self.model.body("body1").id
        self._scale = float(self.prediction["_theory"].semi_major)
        self.start_views()

    def theory(self, t: np.ndarray) -> np.ndarray:
        """r(t) of the closed form (zero action), shape (len(t), 3)."""
        r, _ = self.prediction["_theory"].position(np.asarray(t, dtype=float) - self._time0)
        return r
