"""Double pendulum, small oscillations: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md O6 (the quartic ``m1 l1 l2 w^4 - (m1 + m2) g (l1 + l2) w^2 + (m1 + m2) g^2 = 0``; equal masses
and lengths ``w^2 = (g/l)(2 -+ sqrt 2)``, shapes ``th2/th1 = +-sqrt 2``; Wilcox Part II prob. 12.4) and O7 (the
eigenproblem, eqs 12.15-12.26), implemented in `rigidbench.analytic.oscillations`. Model:
``models/double_pendulum.xml``.

Angles: the theory uses absolute angles th1, th2 of the rods from the downward vertical; MuJoCo's ``hinge2`` is
relative to rod 1, so th1 = hinge1, th2 = hinge1 + hinge2. The predictions come from T and V of O7 built from
the masses, lengths and bob inertias read back from the compiled model; O6's quartic is their point-bob limit
(the tests check that identity), and the 1e-9 kg m^2 bob inertias move the frequencies by ~1e-9.

Amplitude: the theory is linear. The fast mode bends the rods against each other (th2 - th1 = -2.4 th1 at equal
masses and lengths) and its nonlinear frequency shift is -1.85 (a1/rad)^2, measured and exactly quadratic in
a1 (1.85e-6, 4.6e-7, 1.2e-7 at 1, 0.5, 0.25 mrad), 30 times a lone pendulum's a^2/16: the default 0.25 mrad
keeps it at 1.2e-7, below the 1e-6 tolerance. The first-order amplitude shift of the averaged quartic Lagrangian
(`rigidbench.analytic.oscillations.double_pendulum_quartic`, `amplitude_shifts`) gives the same -1.853 a1^2, and
at every mass and length ratio: each case's regime bounds |amplitude1| so that it stays below a quarter of the
frequency tolerance (and rod 2 starts hanging, at 0, in the two cases that release rod 1 alone).

Time scales: the timestep follows the fast mode (2 ms in the unequal case, 1.76 ms at the defaults) and a run lasts
30.5 periods of the slowest excited mode; omega_fast / omega_slow <= 20 keeps runs below 3.3e5 steps. Its square r
solves r + 2 + 1/r = (1 + m2/m1)(1 + l2/l1)^2 / (l2/l1) (O6's quartic), which bounds length2 to [length1 / 199, 199
length1] and mass2 to [1e-3 mass1, (402 lambda / (1 + lambda)^2 - 1) mass1], lambda = length2 / length1 (ranges
that depend on the others).

Exact companions (issue 35): the linear checks' tolerances are sized by the neglected amplitude^2 terms, so each has a
companion ``<check>-exact`` that applies the same measurement to the exact nonlinear motion of the same model (every
number read back from the compiled model; `rigidbench.analytic.oscillations_exact`), sampled at the simulation's
times, and reports the difference: RK4's error at the run's step is what is left (frequencies and shapes, every case).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench.analytic import oscillations as osc
from rigidbench.analytic import oscillations_exact as exact
from rigidbench.contract import Case, Check, Derived, Scenario, Trajectory
from rigidbench.envs import pendulums
from rigidbench.envs.pendulums import BobMass, PendulumEnv, RodLength
from rigidbench.params import Bound, Gravity, Numeric, Param, Range

_FREQ = (
    "RK4 at dt = 1.02e-2 / omega_fast (<= 2 ms in the default cases): relative frequency error (omega dt)^4/120 "
    "<~ 2e-10; "
    "normal coordinates from the O7 mode vectors, crossings cubic-interpolated over >= 30 periods; nonlinear shift "
    "of the fast mode -1.85 a1^2 (measured, exactly quadratic in a1, and the first-order amplitude shift; the slow "
    "mode's is ~20x smaller): 1.2e-7 at a1 = 0.25 mrad, <= 2.5e-7 in the case regimes"
)
_SHAPE = (
    "least-squares fit of th1, th2 at the measured frequencies over the record; nonlinear terms O(a^2) ~ 1e-6 of "
    "the amplitude leak into the fit, 1e-5 leaves a decade. The ratio r = th2/th1 = tan(psi) of the mode's "
    "direction psi amplifies an error in psi by dr/dpsi = 1 + r^2: the tolerance is 1e-5 (1 + r^2) / (1 + 4.4955^2) "
    "where |r| exceeds 4.4955, the largest ratio of the default cases (unequal's fast mode), and 1e-5 otherwise"
)
# The largest |th2/th1| of the default cases (unequal: m2 = 0.3 kg, l2 = 0.6 m, fast mode): the shape tolerance's
# reference (see _SHAPE).
SHAPE_RATIO_REF = 4.4955
CHECKS = (
    Check("omega-slow", "rad/s", 1e-6, "rel", _FREQ, "O6/O7: slow root of det(V - w^2 T) = 0; (g/l)(2 - sqrt 2)"),
    Check("omega-fast", "rad/s", 1e-6, "rel", _FREQ, "O6/O7: fast root of det(V - w^2 T) = 0; (g/l)(2 + sqrt 2)"),
    Check("shape-slow", "1", 1e-5, "abs", _SHAPE, "O6/O7: th2/th1 in the slow mode (+sqrt 2 for equal m, l)"),
    Check("shape-fast", "1", 1e-5, "abs", _SHAPE, "O6/O7: th2/th1 in the fast mode (-sqrt 2 for equal m, l)"),
    Check(
        "energy-drift",
        "1",
        1e-8,
        "abs",
        "RK4 is not symplectic: relative drift ~ T (omega dt)^6 / (72 dt) <~ 2e-9 over 80 s (fast mode, omega dt = "
        "0.012); 1e-8 leaves a factor 5",
        "O6: E = 1/2 sum m v^2 + I th'^2 + m g z conserved (relative to its initial value)",
    ),
)
# Exact companions (issue 35): each linear check measured the same way on the exact nonlinear motion of the same model
# (`rigidbench.analytic.oscillations_exact`), sampled at the simulation's times.
# The reference's error budget, relative to the amplitude: its a-posteriori bound (`ExactMotion.bound`) is <= 2 eps
# w_max t_run (its phases' rounding) + ~1e-15 (iteration and quadrature), <= 1.7e-12 over the cases' ranges.
_REF = 1e-11
_EXACT_THEORY = (
    "O6/O7 exact: the nonlinear equations of motion of the two links as compiled (Lagrange's equations of T = 1/2 "
    "(m1 c1^2 + I1 + m2 e1^2) th1'^2 + 1/2 (m2 c2^2 + I2) th2'^2 + m2 e1 c2 cos(th1 - th2) th1' th2', V = -(m1 c1 + m2 "
    "e1) g cos th1 - m2 g c2 cos th2), solved by Picard's iteration of Duhamel's formula to <= 1e-11 of the amplitude; "
)
_RK4 = (
    "RK4 at the run's step: relative frequency error eps4 = (omega dt)^4 / 120 of each mode (9e-11 and 2.6e-12 at the "
    "defaults); the same measurement applied to both, so only the integrator's error (and the reference's 1e-11) is "
    "left; "
)
_SHAPE_EXACT = (
    _RK4 + "the fit's ratio moves with the difference of the modes' phase drifts, measured <= {measured} eps4 "
    "omega_fast t_run (1 + r^2) (default cases): tolerance {factor} eps4 omega_fast t_run (1 + r^2) + 1e-11"
)
SHAPE_FACTOR = 1e-3
EXACT_CHECKS = (
    Check(
        "omega-slow-exact",
        "1",
        2.7e-11,
        "abs",
        _RK4 + "tolerance 10 eps4 + 1e-11",
        _EXACT_THEORY + "omega_slow measured / omega_slow of the exact motion, minus 1",
    ),
    Check(
        "omega-fast-exact",
        "1",
        9e-10,
        "abs",
        _RK4 + "tolerance 10 eps4 + 1e-11",
        _EXACT_THEORY + "omega_fast measured / omega_fast of the exact motion, minus 1",
    ),
    Check(
        "shape-slow-exact",
        "1",
        1e-9,
        "abs",
        _SHAPE_EXACT.format(measured="1.4e-5", factor=SHAPE_FACTOR),
        _EXACT_THEORY + "th2/th1 of the slow mode, measured minus exact",
    ),
    Check(
        "shape-fast-exact",
        "1",
        1e-9,
        "abs",
        _SHAPE_EXACT.format(measured="1.4e-5", factor=SHAPE_FACTOR),
        _EXACT_THEORY + "th2/th1 of the fast mode, measured minus exact",
    ),
)
CHECKS = CHECKS + EXACT_CHECKS
_BOTH = (
    "omega-slow",
    "omega-fast",
    "shape-slow",
    "shape-fast",
    "energy-drift",
    *(c.name for c in EXACT_CHECKS),
)
# Float32 (Warp, MJX float32): with both modes excited (`released`, `unequal`) every check's round-off floor grows
# like the step count, (eps / 2) N (`rigidbench.engines.roundoff_floor`, secular), not like sqrt(N). A fast mode rides
# a slow one, so each step's rounding of MuJoCo's coordinates lands on nearly the same digits as the last one's and
# the roundings add up instead of averaging out; at worst each is half an ulp the same way. Measured over 24 Warp
# census draws (seeds 2 and 3), 12 of them with both modes: energy drift up to 0.27 eps N (1.2e-2 at N = 3.7e5 for
# a released chain with l2 / l1 = 181, omega_fast / omega_slow = 19.6; on another draw MJX float32 gave 1.3e-3
# where Warp gave 3.2e-3), frequencies up to 0.025 eps N, mode shapes 0.027 eps N, where the random-walk floor
# 10 eps sqrt(N + 1) was passed by up to 16x. With one mode excited the errors stay below 0.8 eps sqrt(N) and the
# random-walk floor holds. Where (eps / 2) N reaches a tenth of a quantity the check is unresolved on float32.


def _mode_ratio(p: Mapping[str, Any], mode: int) -> float:
    """th2/th1 of a mode, from the requested parameters (for the initial condition only)."""
    modes = osc.normal_modes(*osc.double_pendulum_matrices(p["mass1"], p["mass2"], p["length1"], p["length2"], p["g"]))
    return float(modes.shape_ratios()[1, mode])


# omega_fast / omega_slow <= 20: r = 400 and S = r + 2 + 1/r = (1 + mu)(1 + lambda)^2 / lambda <= 402.0025 (O6's
# quartic, mu = m2/m1, lambda = l2/l1). Half of S bounds lambda (so that mu may reach 1 at its ends), the rest mu.
RATIO_MAX = 20.0
_S_MAX = RATIO_MAX**2 + 2 + RATIO_MAX**-2
LENGTH_RATIO = float((_S_MAX / 2 - 2 + np.sqrt((_S_MAX / 2 - 2) ** 2 - 4)) / 2)  # root of (1 + x)^2 / x = S/2
MASS_RATIO_MIN = 1e-3
SHIFT_SHARE = 0.25  # the neglected first-order amplitude shift may take this fraction of the 1e-6 tolerance
_REGIME = (
    "the linear theory's amplitudes (O6/O7): |amplitude1| <= a_max, where the first-order amplitude shift of the "
    "excited modes (averaged quartic Lagrangian) stays below a quarter of the frequency tolerance (1e-6), and the "
    "energy it moves between the modes (shift x omega_fast / (omega_fast - omega_slow)) below a quarter of the "
    "shapes' (1e-5 / 3 rad in the mode's direction)"
)


def _mass_ratio_max(p: Mapping[str, Any]) -> float:
    lam = p["length2"] / p["length1"]
    return float(_S_MAX * lam / (1 + lam) ** 2 - 1)


def amplitude_limit(p: Mapping[str, Any], mode: int | None) -> float:
    """Largest |amplitude1| (rad) of the linear theory's regime: released in mode `mode`'s shape (0 slow, 1 fast), or
    with rod 2 hanging (None); the first-order amplitude shift below `SHIFT_SHARE` of the 1e-6 tolerance."""
    m1, m2, l1, l2, g = (float(p[x]) for x in ("mass1", "mass2", "length1", "length2", "g"))
    modes = osc.normal_modes(*osc.double_pendulum_matrices(m1, m2, l1, l2, g, 1e-9, 1e-9))
    a = 1e-4
    angles = np.array([a, 0.0]) if mode is None else np.array([a, a * modes.shape_ratios()[1, mode]])
    q = modes.coordinates(angles)
    shift = np.abs(osc.amplitude_shifts(modes, osc.double_pendulum_quartic(m1, m2, l1, l2, g), q))
    excited = np.abs(q) > 1e-6 * np.abs(q).max()
    per_a2 = shift[excited].max() / a**2
    w = modes.frequencies
    limits = [
        SHIFT_SHARE * 1e-6 / per_a2,
        # the energy the shift moves between the modes, ~ shift x omega / (omega_fast - omega_slow), as a direction
        # error of the fitted shapes: a quarter of the 1e-5 / 3 rad the shape tolerance allows at equal masses
        SHIFT_SHARE * 1e-5 / 3 * (w[1] - w[0]) / (per_a2 * w[1]),
    ]
    return float(min(1.0, np.sqrt(min(limits))))


def _in_mode(mode: int) -> Bound:
    """The one amplitude2 that releases the pendulum in mode `mode`'s shape: r amplitude1 (`_mode_ratio`)."""
    text = "r amplitude1, r the " + ("slow" if mode == 0 else "fast") + " mode's ratio th2/th1 (O6)"

    def exact(p: Mapping[str, Any]) -> Range:
        value = _mode_ratio(p, mode) * p["amplitude1"]
        return Range(value, value)

    return Bound(text, exact, ("mass1", "mass2", "length1", "length2", "g", "amplitude1"))


def _amplitude_regime(mode: int | None) -> Bound:
    return Bound(
        "[-a_max, a_max], a_max(mass1, mass2, length1, length2, g) from the first-order amplitude shift (case regime)",
        lambda p: Range(-amplitude_limit(p, mode), amplitude_limit(p, mode)),
        ("mass1", "mass2", "length1", "length2", "g"),
    )


def _omega_fast(p: Mapping[str, Any]) -> float:
    """The fast mode's frequency (rad/s) from the requested parameters (point bobs, O6)."""
    return float(osc.double_pendulum_frequencies(p["mass1"], p["mass2"], p["length1"], p["length2"], p["g"])[1])


class DoublePendulum(Scenario):
    """A double pendulum oscillating about its lower equilibrium: its two normal modes (docs/theory.md O6, O7)."""

    slug = "double-pendulum"
    title = "Double pendulum: small-oscillation normal modes"
    env_id = "rigidbench/DoublePendulum-v0"
    # Bounds: 1 g to 1 t, 1 mm to 100 m, microgravity to 100 g; the ratios m2/m1 and l2/l1 within the ranges
    # that keep omega_fast / omega_slow <= 20 (module docstring).
    params = (
        Param("mass1", "kg", "mass of the upper point bob", Range(1e-3, 1e3), BobMass(("pendulum1",))),
        Param(
            "mass2",
            "kg",
            "mass of the lower point bob",
            Range(1e-3, 1e3),
            BobMass(("pendulum2",)),
            within=Bound(
                "[1e-3 mass1, (402 lambda / (1 + lambda)^2 - 1) mass1], lambda = length2/length1 (omega_fast / "
                "omega_slow <= 20)",
                lambda p: Range(MASS_RATIO_MIN * p["mass1"], _mass_ratio_max(p) * p["mass1"]),
                ("mass1", "length1", "length2"),
            ),
        ),
        Param("length1", "m", "pivot to upper bob", Range(1e-3, 100.0), RodLength(("pendulum1",))),
        Param(
            "length2",
            "m",
            "upper bob to lower bob",
            Range(1e-3, 100.0),
            RodLength(("pendulum2",)),
            within=Bound(
                f"[length1 / {LENGTH_RATIO:.0f}, {LENGTH_RATIO:.0f} length1] (omega_fast / omega_slow <= 20)",
                lambda p: Range(p["length1"] / LENGTH_RATIO, LENGTH_RATIO * p["length1"]),
                ("length1",),
            ),
        ),
        Param("amplitude1", "rad", "release angle of rod 1 from the vertical", Range(-1.0, 1.0), Numeric("amplitude1")),
        Param(
            "amplitude2",
            "rad",
            "release angle of rod 2 from the vertical (absolute, not relative to rod 1)",
            Range(-1.0, 1.0),
            Numeric("amplitude2"),
        ),
        Param("g", "m/s^2", "gravitational acceleration (along -z)", Range(1e-6, 1e3), Gravity()),
    )
    cases = (
        Case(
            "slow-mode",
            "released in the slow mode's shape (th2/th1 = +sqrt 2 for equal masses and lengths)",
            {"amplitude2": lambda p: _mode_ratio(p, 0) * p["amplitude1"]},
            ("omega-slow", "shape-slow", "energy-drift", "omega-slow-exact", "shape-slow-exact"),
            ranges={"amplitude1": _amplitude_regime(0), "amplitude2": _in_mode(0)},
            regime=_REGIME
            + "; released in the mode's shape (amplitude2 = r amplitude1): another amplitude2 mixes both "
            "modes, whose frequencies and shapes the case's checks read one at a time",
        ),
        Case(
            "fast-mode",
            "released in the fast mode's shape (th2/th1 = -sqrt 2 for equal masses and lengths)",
            {"amplitude2": lambda p: _mode_ratio(p, 1) * p["amplitude1"]},
            ("omega-fast", "shape-fast", "energy-drift", "omega-fast-exact", "shape-fast-exact"),
            ranges={"amplitude1": _amplitude_regime(1), "amplitude2": _in_mode(1)},
            regime=_REGIME
            + "; released in the mode's shape (amplitude2 = r amplitude1): another amplitude2 mixes both "
            "modes, whose frequencies and shapes the case's checks read one at a time",
        ),
        Case(
            "released",
            "rod 1 displaced, rod 2 hanging: both modes",
            {"amplitude2": 0.0},
            _BOTH,
            ranges={"amplitude1": _amplitude_regime(None), "amplitude2": Range(0.0, 0.0)},
            regime=_REGIME + "; rod 2 starts hanging (amplitude2 = 0)",
        ),
        Case(
            "unequal",
            "light short lower pendulum (m2 = 0.3 kg, l2 = 0.6 m), rod 1 displaced: the general O6 quartic",
            {"amplitude2": 0.0, "mass2": 0.3, "length2": 0.6},
            _BOTH,
            ranges={"amplitude1": _amplitude_regime(None), "amplitude2": Range(0.0, 0.0)},
            regime=_REGIME + "; rod 2 starts hanging (amplitude2 = 0)",
        ),
    )
    checks = CHECKS

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        """The timestep follows the fast mode (2 ms at the model's defaults)."""
        return {"timestep": pendulums.timestep_for(_omega_fast(params), _rate0(type(self)), "omega_fast")}

    def validate(self, params: Mapping[str, Any]) -> None:
        if params["amplitude1"] == 0 and params["amplitude2"] == 0:
            raise ValueError("parameters 'amplitude1' and 'amplitude2' are both 0: nothing moves (valid: not both 0)")

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[:] = [params["amplitude1"], params["amplitude2"] - params["amplitude1"]]  # hinge2 is relative
        data.qvel[:] = 0.0

    @staticmethod
    def modes(model: mujoco.MjModel) -> osc.NormalModes:
        """Normal modes (absolute angles) from the compiled masses, lengths and bob inertias."""
        p1, p2 = pendulums.pendulums(model)
        T, V = osc.double_pendulum_matrices(
            p1.mass, p2.mass, p1.length, p2.length, pendulums.gravity(model), p1.inertia_cm, p2.inertia_cm
        )
        return osc.normal_modes(T, V)

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        modes = self.modes(model)
        angles0 = absolute(data.qpos[None])[0]
        excited = np.abs(modes.coordinates(angles0)) > 1e-6 * np.abs(modes.coordinates(angles0)).max()
        ratios = modes.shape_ratios()[1]
        duration = 30.5 * 2 * np.pi / modes.frequencies[excited].min()
        eps4 = [pendulums.rk4_frequency_error(float(w), float(model.opt.timestep)) for w in modes.frequencies]
        drift = eps4[1] * float(modes.frequencies[1]) * duration
        tolerance = {
            name: self.check(name).tolerance * max(1.0, (1 + r**2) / (1 + SHAPE_RATIO_REF**2))
            for name, r in (("shape-slow", ratios[0]), ("shape-fast", ratios[1]))
        }
        tolerance.update(
            {
                "omega-slow-exact": 10 * eps4[0] + _REF,
                "omega-fast-exact": 10 * eps4[1] + _REF,
                "shape-slow-exact": SHAPE_FACTOR * drift * (1 + ratios[0] ** 2) + _REF,
                "shape-fast-exact": SHAPE_FACTOR * drift * (1 + ratios[1] ** 2) + _REF,
            }
        )
        return {
            "_modes": modes,
            "_excited": excited,
            "_angles0": angles0,
            "_scale": float(np.abs(angles0).max()),
            "_energy_scale": float(energy(model, data.qpos[None], data.qvel[None])[0]),
            "_duration": duration,
            "omega-slow": float(modes.frequencies[0]),
            "omega-fast": float(modes.frequencies[1]),
            "shape-slow": float(ratios[0]),
            "shape-fast": float(ratios[1]),
            "energy-drift": 0.0,
            **{c.name: 0.0 for c in EXACT_CHECKS},
            "_tolerance": tolerance,
            # A float32 engine's floor (`Scenario._roundoff_check`): secular with both modes excited (see `_BOTH`).
            "_roundoff_secular": _BOTH if excited.all() else (),
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return prediction["_duration"]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        t = traj.time
        sim = _observe(t, absolute(traj.qpos), prediction)
        ref = exact.motion(t, exact_model(model).acceleration, prediction["_modes"], prediction["_angles0"])
        valid = ref.bound <= _REF  # else the reference did not converge (beyond the linear regime): the companions fail
        ex = _observe(t, ref.angles, prediction) if valid else sim
        return {
            **sim,
            "energy-drift": pendulums.energy_drift(energy(model, traj.qpos, traj.qvel), prediction["_energy_scale"]),
            "omega-slow-exact": sim["omega-slow"] / ex["omega-slow"] - 1 if valid else np.nan,
            "omega-fast-exact": sim["omega-fast"] / ex["omega-fast"] - 1 if valid else np.nan,
            "shape-slow-exact": sim["shape-slow"] - ex["shape-slow"] if valid else np.nan,
            "shape-fast-exact": sim["shape-fast"] - ex["shape-fast"] if valid else np.nan,
        }


def _observe(t: np.ndarray, theta: np.ndarray, prediction: Mapping[str, Any]) -> dict[str, float]:
    """The measured frequencies and shapes of a motion (absolute angles sampled at `t`)."""
    omegas, shapes = pendulums.two_modes(t, theta, prediction["_modes"], prediction["_excited"])
    return {
        "omega-slow": omegas[0],
        "omega-fast": omegas[1],
        "shape-slow": shapes.get(0, np.nan),
        "shape-fast": shapes.get(1, np.nan),
    }


def exact_model(model: mujoco.MjModel) -> exact.DoublePendulumModel:
    """The two links as the exact equations of motion take them, read back from the compiled model.

    Raises
    ------
    ValueError
        If the model has a force those equations leave out (joint damping, armature, friction loss) or hinge 2 is not
        on link 1's axis.
    """
    present = [x for x in ("dof_damping", "dof_armature", "dof_frictionloss") if np.any(getattr(model, x) != 0)]
    b2 = model.jnt_bodyid[1]
    if present or np.any(model.body_pos[b2][:2] != 0) or np.any(model.jnt_pos != 0):
        raise ValueError(f"the exact double pendulum has no {present} and its hinges on the links' axes")
    p1, p2 = pendulums.pendulums(model)
    return exact.DoublePendulumModel(
        mass=(p1.mass, p2.mass),
        com=(p1.length, p2.length),
        inertia_cm=(p1.inertia_cm, p2.inertia_cm),
        hinge2=float(-model.body_pos[b2][2]),
        g=pendulums.gravity(model),
    )


@functools.cache
def _rate0(cls: type[DoublePendulum]) -> float:
    return pendulums.default_rate(cls(), _omega_fast)


def absolute(qpos: np.ndarray) -> np.ndarray:
    """Absolute rod angles (th1, th2) from the vertical, shape (n, 2), from MuJoCo's (hinge1, hinge1-relative)."""
    return np.stack([qpos[:, 0], qpos[:, 0] + qpos[:, 1]], axis=-1)


def energy(model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
    """Total energy (J) from the full nonlinear geometry, zero at the lower equilibrium.

    Bob 1 at ``l1 (-sin th1, -cos th1)``, bob 2 at bob 1 + ``l2 (-sin th2, -cos th2)`` (absolute angles); each bob
    also spins with its rod (inertia I_cm about y). 1 - cos is written 2 sin^2(th/2) (no cancellation).
    """
    p1, p2 = pendulums.pendulums(model)
    g = pendulums.gravity(model)
    th = absolute(qpos)
    w = absolute(qvel)
    vx1 = -p1.length * np.cos(th[:, 0]) * w[:, 0]
    vz1 = p1.length * np.sin(th[:, 0]) * w[:, 0]
    vx2 = vx1 - p2.length * np.cos(th[:, 1]) * w[:, 1]
    vz2 = vz1 + p2.length * np.sin(th[:, 1]) * w[:, 1]
    kinetic = 0.5 * (p1.mass * (vx1**2 + vz1**2) + p2.mass * (vx2**2 + vz2**2))
    kinetic += 0.5 * (p1.inertia_cm * w[:, 0] ** 2 + p2.inertia_cm * w[:, 1] ** 2)
    h1 = 2 * p1.length * np.sin(0.5 * th[:, 0]) ** 2
    h2 = 2 * p2.length * np.sin(0.5 * th[:, 1]) ** 2
    return kinetic + g * (p1.mass * h1 + p2.mass * (h1 + h2))


class DoublePendulumEnv(PendulumEnv):
    """``rigidbench/DoublePendulum-v0``: the double pendulum near its lower equilibrium, scored against its modes.

    Description
        Point bob 1 on a massless rod hinged at the origin, point bob 2 on a massless rod hinged at bob 1, both
        swinging about the world y axis. With zero action and small angles the motion is the superposition of
        the two normal modes of docs/theory.md O6/O7 (equal masses and lengths: ``w^2 = (g/l)(2 -+ sqrt 2)``,
        ``th2/th1 = +-sqrt 2``).

    Observation Space
        Box(-inf, inf, (4,)), float64:

        ==== =============================================== ====== ==================
        idx  quantity                                        unit   MuJoCo source
        ==== =============================================== ====== ==================
        0    angle of rod 1 from the downward vertical       rad    qpos of ``hinge1``
        1    angle of rod 2 relative to rod 1                rad    qpos of ``hinge2``
        2    rate of rod 1                                   rad/s  qvel of ``hinge1``
        3    rate of rod 2 relative to rod 1                 rad/s  qvel of ``hinge2``
        ==== =============================================== ====== ==================

        The absolute angle of rod 2 is obs[0] + obs[1]. A positive angle turns a bob towards -x.

    Action Space
        Box(-1, 1, (1,)), float32, normalised: ``action_scale = 0.1`` N m times it is a torque on rod 1 about
        its pivot, through ``qfrc_applied``;
        out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -max_i |hinge_i - hinge_i,theory(t)| / max(|th1(0)|, |th2(0)|)``, the theory being the linear
        normal-mode solution (O7); ``info["measured"]["angles"]`` and ``info["predicted"]["angles"]`` hold both
        (rad, hinge coordinates).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        At rest with absolute rod angles (``amplitude1``, ``amplitude2``) (rad).

    Episode End
        Truncated after 30.5 periods of the slowest excited mode; terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (slow-mode, fast-mode, released, unequal), ``params`` (mass1, mass2, length1, length2,
        amplitude1, amplitude2, g), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10: ten
        derived steps, 17.6 ms at the defaults), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = DoublePendulum

    def theory(self, t: np.ndarray) -> np.ndarray:
        th = self.prediction["_modes"].angles(t, self.prediction["_angles0"])
        return np.stack([th[:, 0], th[:, 1] - th[:, 0]], axis=-1)  # hinge coordinates: hinge2 is relative
