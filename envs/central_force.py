"""A body about a fixed centre under central power-law forces: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md K2 (the Runge-Lenz vector), K5 (stability of circular orbits and the apsidal angle in
F = -k / r^n) and K6 (the pericentre advance from a small r^-4 force), Wilcox Part II sections 8.3, 8.6 and 8.7, in
`rigidbench.analytic.central_force`. Model: ``models/central_force.xml``: a planet on two slide joints in the x-y
plane and a centre welded to the world, the force between them declared for `rigidbench.forces` as power-law terms
(``k / r^n`` and ``k4 / r^4``), added by MuJoCo's passive-force callback at every RK4 stage.

The planet starts on +x at ``separation`` with its velocity along +y at ``speed_ratio`` (>= 1) times the circular
speed: at its pericentre. The stable cases read the azimuth swept between apsides (r.v = 0, cubic-interpolated)
against the exact apsidal angle of Binet's equation (integrated by scipy at rtol 1e-13) and against the closed form
pi / sqrt(3 - n), whose second-order term sets that check's tolerance; the unstable case (n > 3) reads the time the
offset from the circular radius takes to grow a hundredfold against the linearised rate; the perihelion case reads the
pericentre's advance per orbit against 2 pi eps, its second-order term setting the tolerance.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import forces, signals
from rigidbench.analytic import central_force as cf
from rigidbench.contract import Case, Check, Derived, Domain, Scenario, Trajectory, round_step
from rigidbench.envs.base import ScenarioEnv
from rigidbench.params import BodyMass, Numeric, Param, Range, Value

# Reference timestep (`CentralForce.reference_settings`): STEP of the pericentre passage r0 / v0 (the body starts
# there): RK4's orbit error at 0.01 is ~1e-9 r0 over the runs (measured; / 16 per halving, fourth order). An unstable
# orbit takes UNSTABLE_STEP of 1 / lambda: RK4's own circular orbit lies ~h^4 off r*, which is what a start (s - 1)
# above the circular speed is measured against (2.3e-3 of the rate at h = 0.01 / lambda, s - 1 = 1e-8; 3.4e-6 at
# 0.002, fourth order).
STEP = 0.01
UNSTABLE_STEP = 0.002
# Run lengths: 2.25 radial periods (four apsidal angles after the start's), PERIHELION_ORBITS + 0.25 for the advance,
# and past the hundredfold growth (GROWTH) of an unstable offset.
RADIAL_PERIODS = 2.25
PERIHELION_ORBITS = 3
GROWTH = 100.0
# Smallest eccentricity whose apsides are read: r.v = 0 has slope ~e v^2 there, so an orbit error delta (units of r0)
# moves an apsis by ~delta / e rad; largest eccentricity of the near-circular cases: the first-order apsidal angle's
# O(e^4) remainder stays below 1e-2 of its second-order term (tests/test_central_force_analytic.py).
MIN_ECCENTRICITY = 0.01
MAX_NEAR_CIRCULAR = 0.1
# The pericentre advance's first order holds to its second-order term while eps <= MAX_EPSILON (the third-order
# remainder is below 4 % of the second-order term there: 3.5 % at eps = 1e-2, e = 0.69; the analytic tests).
MAX_EPSILON = 1e-2
PERIHELION_EPSILON = 1e-3  # the perihelion case's default eps
# RK4's error on the orbit (units of r0), the base of the orbit and apsis tolerances: ten times the worst measured.
ORBIT_ERROR = 1e-7

_RK4 = f"RK4 at h = {STEP:g} r0 / v0 (fourth order, / 16 per halving)"
CHECKS = (
    Check(
        "apsidal-angle",
        "rad",
        ORBIT_ERROR / MIN_ECCENTRICITY,
        "abs",
        _RK4 + ": an orbit error delta (units of r0, <= 1e-8 measured) moves an apsis (r.v = 0, cubic-interpolated) "
        f"by ~delta / e rad; tolerance {ORBIT_ERROR:g} / e, set per run, listed at the smallest e = "
        f"{MIN_ECCENTRICITY:g}; the farthest from theory of the run's apsidal angles",
        "K5: the azimuth between successive apsides, exactly the integral of Binet's equation u'' + u = "
        "(mu / l^2) sum k u^(n - 2) from one apsis to the next (Wilcox eq. 8.128; pi for Kepler at every e)",
    ),
    Check(
        "apsidal-near-circular",
        "rad",
        2.0e-4,
        "abs",
        "the closed form's own remainder: twice its second-order term pi / sqrt(3 - n) |(n - 2)(n + 1)| e^2 / 24 "
        "(Lindstedt; the O(e^4) rest is below 1e-2 of it at e <= 0.1), plus the apsidal-angle check's RK4 "
        "tolerance; set per run, listed at the log-potential default (n = 1, e = 0.02)",
        "K5: pi / sqrt(3 - n) for a near-circular orbit in F = -k / r^n (Wilcox section 8.7, eqs 8.132-8.137)",
    ),
    Check(
        "growth-rate",
        "1/s",
        1e-3,
        "rel",
        "the linearisation's remainder: the offset is read when it has grown to 100 x its start, <= 8e-4 r0 over "
        "the ranges, where the radial equation's quadratic term shifts the rate by ~0.3 x 100 dr(0) / r* (measured "
        "1.8e-4 at n = 3.25, s - 1 = 1e-6); RK4 at h = 0.002 / lambda: its circular orbit lies ~h^4 off r*, 3.4e-6 "
        "of the rate at s - 1 = 1e-8; 1e-3 leaves a factor 5",
        "K5: circular orbits are unstable for n > 3; dr(t) = dr(0) cosh(lambda t), lambda = sqrt((n - 3) k / "
        "(mu r*^(n + 1))) (Wilcox eqs 8.132-8.137)",
    ),
    Check(
        "runge-lenz-drift",
        "1",
        1e-8,
        "abs",
        _RK4 + ": max |A(t) - A(0)| / (mu k): RK4's error in the orbit's orientation and shape, measured <= 4.1e-10 "
        "over the ranges (13 x the energy drift of the same runs); 1e-8 leaves a factor 25",
        "K2: A = p x L - mu k r_hat is constant for the inverse square (Wilcox eqs 8.64, 8.77)",
    ),
    Check(
        "perihelion-advance",
        "rad",
        4e-5,
        "abs",
        "the first order's remainder: twice the second-order term 2 pi eps^2 (5/2 + 5 e^2 / 12) (Lindstedt on u'' + "
        "u = A + B u^2; the third order is below 4 % of it at eps <= 1e-2), plus the pericentres' RK4 error "
        f"{ORBIT_ERROR:g} / e; set per run, listed at the default (eps = 1e-3, e = 0.44)",
        "K6: the pericentre advances by 2 pi eps per orbit, eps = mu^2 k k4 / l^4, in F = -k / r^2 - k4 / r^4 "
        "(6 pi GM / (c^2 a (1 - e^2)) for k4 = 3 k h^2 / c^2; Wilcox section 8.6)",
    ),
    Check(
        "orbit",
        "1",
        ORBIT_ERROR,
        "abs",
        _RK4 + ": max |r(t) - r_ref(t)| / r_max (the apocentre; r0 for an unstable orbit) over the run, measured "
        f"<= 1.6e-8 over the ranges (e = 0.8, 3.25 orbits); {ORBIT_ERROR:g} leaves a factor 6",
        "K5: the orbit of F = -sum k / r^n from the launch state, integrated by scipy's DOP853 at rtol 1e-13 (the "
        "theory's own equations of motion; closed forms exist only at n = 2 and -1)",
    ),
    Check(
        "energy-drift",
        "1",
        1e-9,
        "abs",
        _RK4 + ": max |E(t) - E(0)| / (mu v0^2 / 2), measured <= 3.5e-11 over the ranges; 1e-9 leaves a factor 29",
        "K2, K5: E = mu v^2 / 2 + U(r) conserved (U = -k r^(1 - n) / (n - 1), k ln r at n = 1)",
    ),
    Check(
        "momentum-drift",
        "1",
        1e-9,
        "abs",
        _RK4 + ": max |l(t) - l(0)| / l(0); a central force has no torque, RK4 keeps l to 1.3e-11 (measured over "
        "the ranges); 1e-9 leaves a factor 75",
        "K2: l = mu r x v conserved (central force)",
    ),
)


@dataclass(frozen=True)
class LawEntry:
    """One number of a `rigidbench.forces` power-law declaration: entry ``index`` of the custom numeric ``name``,
    written as ``sign`` times the parameter (the declaration's strengths attract when negative)."""

    name: str
    index: int
    sign: float = 1.0

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        numeric = spec.numeric(self.name)
        data = list(numeric.data)
        data[self.index] = self.sign * float(value)
        numeric.data = data

    def read(self, model: mujoco.MjModel) -> Value:
        return self.sign * float(model.numeric(self.name).data[self.index]) + 0.0  # + 0.0: -0.0 reads as 0


def _law(p: Mapping[str, Any]) -> cf.Law:
    return cf.Law((p["strength"], p["correction"]), (p["exponent"], 4.0))


def _launch(p: Mapping[str, Any]) -> tuple[float, float]:
    """(r0, v0): the launch distance (m) and speed (m/s)."""
    r0 = p["separation"]
    return r0, p["speed_ratio"] * cf.circular_speed(p["mass"], _law(p), r0)


def _epsilon(p: Mapping[str, Any]) -> float:
    """eps = mu^2 k k4 / l^4 of the requested orbit (K6)."""
    r0, v0 = _launch(p)
    return p["strength"] * p["correction"] / (r0 * v0) ** 4


def _correction(p: Mapping[str, Any]) -> float:
    """The r^-4 strength k4 (N m^4) that gives eps = PERIHELION_EPSILON: with x = k4 / (k r0^2) and l^2 = mu s^2
    (k r0 + k4 / r0), eps = x / (s^4 (1 + x)^2), the small root of a x^2 + (2a - 1) x + a = 0, a = s^4 eps."""
    a = p["speed_ratio"] ** 4 * PERIHELION_EPSILON
    x = ((1 - 2 * a) - math.sqrt(1 - 4 * a)) / (2 * a)
    return x * p["strength"] * p["separation"] ** 2


def _apsides(p: Mapping[str, Any]) -> cf.Apsides:
    r0, v0 = _launch(p)
    return cf.apsides(p["mass"], _law(p), r0, p["mass"] * r0 * v0)


def _eccentricity(p: Mapping[str, Any]) -> str | None:
    if p["exponent"] > 3:
        return None
    e = _apsides(p).eccentricity
    if e < MIN_ECCENTRICITY:
        return f"speed_ratio = {p['speed_ratio']:.10g}, exponent = {p['exponent']:g} (e = {e:.3g})"
    return None


def _near_circular(p: Mapping[str, Any]) -> str | None:
    e = _apsides(p).eccentricity
    if e > MAX_NEAR_CIRCULAR:
        return f"speed_ratio = {p['speed_ratio']:.10g}, exponent = {p['exponent']:g} (e = {e:.3g})"
    return None


def _bound(p: Mapping[str, Any]) -> str | None:
    if p["exponent"] <= 1 or p["exponent"] > 3:
        return None
    # E = mu v0^2 / 2 + U(r0) < 0 with U -> 0 at infinity (n > 1). A large r^-4 term can unbind the start: it
    # raises the circular speed v0 is scaled from by more than it deepens the well at r0.
    r0, v0 = _launch(p)
    energy = 0.5 * p["mass"] * v0 * v0 + float(_law(p).potential(r0))
    if energy >= 0:
        return f"speed_ratio = {p['speed_ratio']:.10g}, exponent = {p['exponent']:g} (E = {energy:.3g} J >= 0)"
    return None


def _first_order(p: Mapping[str, Any]) -> str | None:
    eps = _epsilon(p)
    return f"correction = {p['correction']:.6g} N m^4 (eps = {eps:.3g})" if eps > MAX_EPSILON else None


_NEAR_CIRCULAR = ("log-potential", "constant-force", "steep")
DOMAINS = (
    Domain(
        "bound",
        "K5 (apsides)",
        "1 < n <= 3: a bound orbit, E < 0 (s^2 < 2 / (n - 1) without the correction; a large r^-4 correction "
        "raises the launch speed past escape): an escaping body has one apsis",
        _bound,
    ),
    Domain(
        "apsides",
        "K5 (apsidal angle)",
        f"e >= {MIN_ECCENTRICITY:g} (n < 3): a circle has no apsides, and an orbit error delta moves a measured "
        "apsis by ~delta / e rad",
        _eccentricity,
    ),
    Domain(
        "near-circular",
        "K5 (pi / sqrt(3 - n) is the limit e -> 0)",
        f"e <= {MAX_NEAR_CIRCULAR:g}: the closed form's O(e^4) remainder stays below 1e-2 of the second-order term "
        "that sets its tolerance",
        _near_circular,
        _NEAR_CIRCULAR,
    ),
    Domain(
        "first-order",
        "K6 (first order in eps)",
        f"eps = mu^2 k k4 / l^4 <= {MAX_EPSILON:g}: the third-order remainder stays below 4 % of the second-order "
        "term that sets the advance's tolerance",
        _first_order,
        ("perihelion",),
    ),
)

_NO_CORRECTION = {"correction": Range(0.0, 0.0)}
_STABLE = (
    "near-circular (e <= 0.1, domain 'near-circular') in a power law -1 <= n <= 2.75 below the instability at n = 3; "
    "no r^-4 correction"
)
_STABLE_RANGES = {**_NO_CORRECTION, "exponent": Range(-1.0, 2.75), "speed_ratio": Range(1.01, 1.05)}
_STABLE_CHECKS = ("apsidal-angle", "apsidal-near-circular", "orbit", "energy-drift", "momentum-drift")


class CentralForce(Scenario):
    """A planet about a fixed centre under F = -k / r^n (and a small -k4 / r^4): apsidal angles exact and to first
    order, the Runge-Lenz vector, the growth of an unstable circular orbit, the pericentre advance (docs/theory.md
    K2, K5, K6)."""

    slug = "central-force"
    title = "Central power-law forces: apsidal angles, stability, Runge-Lenz, pericentre advance"
    env_id = "rigidbench/CentralForce-v0"
    params = (
        Param("mass", "kg", "mass of the planet (mu: the centre is fixed)", Range(0.1, 10.0), BodyMass("planet")),
        Param(
            "exponent",
            "1",
            "n of the attraction F = -k / r^n (rigidbench.forces power law)",
            Range(-1.0, 5.0),
            LawEntry(forces.POWER_LAW_EXPONENT, 0),
        ),
        Param(
            "strength",
            "N m^n",
            "k of the attraction F = -k / r^n",
            Range(1e-2, 1e3),
            LawEntry(forces.POWER_LAW, 0, -1.0),
        ),
        Param(
            "correction",
            "N m^4",
            "k4 of the small extra attraction -k4 / r^4 (K6; 3 k h^2 / c^2 in general relativity's orbit equation)",
            Range(0.0, 1e3),
            LawEntry(forces.POWER_LAW, 1, -1.0),
        ),
        Param(
            "separation", "m", "initial distance r0 from the centre, along +x", Range(0.1, 10.0), Numeric("separation")
        ),
        Param(
            "speed_ratio",
            "1",
            "initial speed (along +y) in units of the circular speed at r0: >= 1 starts at the pericentre",
            Range(1.0, 1.5),
            Numeric("speed_ratio"),
        ),
    )
    cases = (
        Case(
            "kepler",
            "inverse square, e = 0.44: the Runge-Lenz vector stays put and the apsidal angle is pi",
            {"exponent": 2.0, "strength": 1.0, "correction": 0.0, "speed_ratio": 1.2},
            ("apsidal-angle", "runge-lenz-drift", "orbit", "energy-drift", "momentum-drift"),
            ranges={**_NO_CORRECTION, "exponent": Range(2.0, 2.0), "speed_ratio": Range(1.01, 1.34)},
            regime="the inverse square alone, a bound ellipse with 0.02 <= e = s^2 - 1 <= 0.8",
        ),
        Case(
            "log-potential",
            "F = -k / r (n = 1), e = 0.02: apsidal angle pi / sqrt(2) = 127.3 degrees",
            {"exponent": 1.0, "strength": 1.0, "correction": 0.0, "speed_ratio": 1.02},
            _STABLE_CHECKS,
            ranges=_STABLE_RANGES,
            regime=_STABLE,
        ),
        Case(
            "constant-force",
            "F = -k (n = 0), e = 0.013: apsidal angle pi / sqrt(3) = 103.9 degrees",
            {"exponent": 0.0, "strength": 1.0, "correction": 0.0, "speed_ratio": 1.02},
            _STABLE_CHECKS,
            ranges=_STABLE_RANGES,
            regime=_STABLE,
        ),
        Case(
            "steep",
            "F = -k / r^2.5, e = 0.04: apsidal angle pi / sqrt(0.5) = 254.6 degrees",
            {"exponent": 2.5, "strength": 1.0, "correction": 0.0, "speed_ratio": 1.01},
            _STABLE_CHECKS,
            ranges=_STABLE_RANGES,
            regime=_STABLE,
        ),
        Case(
            "unstable",
            "F = -k / r^4 (n = 4), 1e-8 above the circular speed: the offset grows as cosh(lambda t)",
            {"exponent": 4.0, "strength": 1.0, "correction": 0.0, "speed_ratio": 1.0 + 1e-8},
            ("growth-rate", "energy-drift", "momentum-drift"),
            ranges={**_NO_CORRECTION, "exponent": Range(3.25, 5.0), "speed_ratio": Range(1.0 + 1e-8, 1.0 + 1e-6)},
            regime="n > 3 (unstable, K5), n >= 3.25: a start 1e-8 to 1e-6 above the circular speed puts the offset "
            "dr(0) = 2 (s - 1) r0 / (n - 3) <= 8e-6 r0, so at 100 x it is still <= 8e-4 r0 (linear to 2e-4), and "
            ">= 4e-9 r0, far above RK4's own shift of the circle",
        ),
        Case(
            "perihelion",
            "inverse square plus a small -k4 / r^4 (eps = 1e-3), e = 0.44: the pericentre advances 2 pi eps per orbit",
            {"exponent": 2.0, "strength": 1.0, "correction": _correction, "speed_ratio": 1.2},
            ("apsidal-angle", "perihelion-advance", "orbit", "energy-drift", "momentum-drift"),
            ranges={"exponent": Range(2.0, 2.0), "speed_ratio": Range(1.05, 1.34), "correction": Range(1e-8, 1e3)},
            regime=f"the inverse square with a small r^-4 attraction, eps <= {MAX_EPSILON:g} (domain 'first-order'), "
            "e <= 0.8",
        ),
    )
    checks = CHECKS
    domains = DOMAINS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        r0, v0 = _launch(params)
        scale, rule = r0 / v0, f"r0 / v0 = {r0:.4g} m / {v0:.4g} m/s"
        n = params["exponent"]
        fraction = STEP
        if n > 3:
            scale /= math.sqrt(n - 3)
            fraction = UNSTABLE_STEP
            rule += f" / sqrt(n - 3) (1 / lambda, n = {n:g})"
        h = round_step(fraction * scale)
        return {"timestep": Derived(h, f"{fraction:g} x {rule}, rounded down to one digit: {h:.1g} s")}

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        law = _model_law(model)
        r0 = params["separation"]
        v0 = params["speed_ratio"] * cf.circular_speed(float(model.body("planet").mass[0]), law, r0)
        data.qpos[:2] = [r0, 0.0]
        data.qvel[:2] = [0.0, v0]

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        mu, law = float(model.body("planet").mass[0]), _model_law(model)
        r0, v0 = np.array([*data.qpos[:2], 0.0]), np.array([*data.qvel[:2], 0.0])
        ell = mu * float(np.cross(r0, v0)[2])
        d0 = float(np.linalg.norm(r0))
        k, n = law.k[0], law.n[0]
        out: dict[str, Any] = {
            "_mu": mu,
            "_law": law,
            "_r0": r0,
            "_v0": v0,
            "_l": ell,
            "_energy_scale": 0.5 * mu * float(v0 @ v0),
            "orbit": 0.0,
            "energy-drift": 0.0,
            "momentum-drift": 0.0,
            "runge-lenz-drift": 0.0,
        }
        tolerance: dict[str, float] = {}
        if n > 3:
            r_star, rate = cf.unstable_growth(mu, k, n, ell)
            out.update({"_r_star": r_star, "_offset": d0 - r_star, "growth-rate": rate})
            out["_duration"] = 1.2 * math.acosh(GROWTH) / rate
            out["_size"] = d0
        else:
            aps = cf.apsides(mu, law, d0, ell)
            e = aps.eccentricity
            out.update({"_apsides": aps, "apsidal-angle": aps.angle, "_size": max(aps.r0, aps.r1)})
            apsidal = ORBIT_ERROR / max(e, MIN_ECCENTRICITY)
            tolerance["apsidal-angle"] = apsidal
            orbits = RADIAL_PERIODS
            if law.k[1] != 0:
                first, second = cf.perihelion_advance(mu, k, law.k[1], ell, e)
                out["perihelion-advance"] = first
                tolerance["perihelion-advance"] = 2 * abs(second) + 2 * apsidal / PERIHELION_ORBITS
                orbits = PERIHELION_ORBITS + 0.25
            else:
                first_order = cf.apsidal_angle_first_order(n)
                out["apsidal-near-circular"] = first_order
                tolerance["apsidal-near-circular"] = (
                    2 * abs(cf.apsidal_angle_second_order(n, e) - first_order) + apsidal
                )
            out["_duration"] = orbits * 2 * aps.time
        out["_tolerance"] = tolerance
        return out

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return prediction["_duration"]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        t = np.asarray(traj.time)
        r = np.column_stack([traj.qpos[:, :2], np.zeros(len(t))])
        v = np.column_stack([traj.qvel[:, :2], np.zeros(len(t))])
        mu, law, l0 = prediction["_mu"], prediction["_law"], prediction["_l"]
        dist = np.sqrt(np.einsum("ij,ij->i", r, r))
        energy = 0.5 * mu * np.einsum("ij,ij->i", v, v) + law.potential(dist)
        out: dict[str, float] = {
            "energy-drift": float(np.max(np.abs(energy - energy[0])) / prediction["_energy_scale"]),
            "momentum-drift": float(np.max(np.abs(mu * np.cross(r, v)[:, 2] - l0)) / abs(l0)),
        }
        r_ref, _ = cf.trajectory(mu, law, prediction["_r0"], prediction["_v0"], t)
        out["orbit"] = float(np.max(np.linalg.norm(r - r_ref, axis=1)) / prediction["_size"])
        if "growth-rate" in prediction:
            offset = prediction["_offset"]
            cross = signals.crossings(t, (dist - prediction["_r_star"]) / offset - GROWTH, +1)
            out["growth-rate"] = math.acosh(GROWTH) / float(cross[0]) if cross.size else math.nan
            return out
        k = law.k[0]
        big_a = cf.runge_lenz(mu, k, r, v)
        out["runge-lenz-drift"] = float(np.max(np.linalg.norm(big_a - big_a[0], axis=1)) / (mu * k))
        phase = np.unwrap(np.arctan2(r[:, 1], r[:, 0]))
        rv = np.einsum("ij,ij->i", r, v)
        peri, apo = signals.crossings(t, rv, +1), signals.crossings(t, rv, -1)
        events = np.sort(np.concatenate([[0.0], peri, apo]))  # the start is a pericentre (v perpendicular to r)
        angles = np.diff(signals.interpolate(t, phase, events)) if events.size > 1 else np.array([])
        expected = prediction["apsidal-angle"]
        out["apsidal-angle"] = float(angles[np.argmax(np.abs(angles - expected))]) if angles.size else math.nan
        if "apsidal-near-circular" in prediction:
            first = prediction["apsidal-near-circular"]
            out["apsidal-near-circular"] = float(angles[np.argmax(np.abs(angles - first))]) if angles.size else math.nan
        if "perihelion-advance" in prediction:
            if peri.size:
                swept = float(signals.interpolate(t, phase, peri[-1:])[0]) - phase[0]
                out["perihelion-advance"] = swept / peri.size - 2 * math.pi
            else:
                out["perihelion-advance"] = math.nan
        return out


def _model_law(model: mujoco.MjModel) -> cf.Law:
    """The compiled model's power-law terms as an attraction law (k > 0 attracts), read back (house rule 3)."""
    law = forces.power_law(model)
    if law is None:
        raise ValueError("models/central_force.xml must declare the rigidbench:power-law terms")
    return cf.Law(tuple(float(-k) for k in law.k), tuple(float(n) for n in law.n))


class CentralForceEnv(ScenarioEnv):
    """``rigidbench/CentralForce-v0``: a planet about a fixed centre under a power-law force, scored against the
    reference orbit every step.

    Description
        A planet of mass m on two slide joints in the x-y plane, attracted to a fixed centre by F = -k / r^n (and a
        small -k4 / r^4 in the perihelion case), started at its pericentre. With zero action it is the textbook
        central-force problem (docs/theory.md K2, K5, K6).

    Observation Space
        Box(-inf, inf, (4,)), float64: [0-1] planet position x, y (m), qpos of joints ``x``, ``y``; [2-3] its
        velocity (m/s), their qvel.

    Action Space
        Box(-1, 1, (2,)), float32, normalised: ``max_force = 0.1`` N times it is a force on the planet along x and y,
        through ``qfrc_applied``. Zero action = the textbook problem.

    Rewards
        ``-|r - r_ref(t)| / r0``: the distance between the planet and the reference orbit (the equations of motion
        integrated at rtol 1e-13), in units of the launch distance; ``info["measured"]`` and ``info["predicted"]``
        hold ``x, y`` (m). Each step's deviation counts up to ``DEVIATION_CAP``.

    Starting State
        The case's pericentre: r = separation along +x, velocity along +y at speed_ratio times the circular speed.

    Episode End
        Truncated at the validation run's duration; terminated on divergence.

    Arguments
        ``case`` (kepler, log-potential, constant-force, steep, unstable, perihelion), ``params`` (mass, exponent,
        strength, correction, separation, speed_ratio), ``profile``, ``integrator``, ``timestep``, ``frame_skip``,
        ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = CentralForce
    observables: ClassVar[tuple[str, ...]] = ("x", "y")
    max_force: ClassVar[float] = 0.1

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(4,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_force, self.max_force, shape=(2,), dtype=np.float64)

    def observe(self) -> np.ndarray:
        return np.array([self.data.qpos[0], self.data.qpos[1], self.data.qvel[0], self.data.qvel[1]])

    def apply_action(self, action: np.ndarray) -> None:
        self.data.qfrc_applied[:2] = action

    def theory(self, t: np.ndarray) -> np.ndarray:
        p = self.prediction
        times = np.asarray(t, dtype=float) - self._time0
        r, _ = cf.trajectory(p["_mu"], p["_law"], p["_r0"], p["_v0"], np.maximum(times, 0.0))
        return r[:, :2]

    def measured(self, obs: np.ndarray) -> list[float]:
        return [float(obs[0]), float(obs[1])]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        scale = float(np.linalg.norm(self.prediction["_r0"]))
        return math.hypot(measured[0] - predicted[0], measured[1] - predicted[1]) / scale
