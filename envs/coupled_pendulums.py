"""Two identical pendulums coupled by a spring: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md O3 (normal modes, Wilcox Part II sections 12.1-12.3, eqs 12.10-12.24), O4 (beats and energy
transfer, section 12.4) and O7 (the eigenproblem, eqs 12.15-12.26), implemented in
`rigidbench.analytic.oscillations`. Model: ``models/coupled_pendulums.xml``.

Amplitude. Released in one of the two symmetric shapes, the pair is a one-degree-of-freedom system at any
amplitude, and the checks use its exact period: th1 = th2 never stretches the spring (a lone pendulum, O1's
elliptic period with l = I_O/(M h)); th1 = -th2 keeps the attachment points level, so the spring stays horizontal,
stretched by exactly 2 d sin th (`rigidbench.analytic.oscillations.anti_phase_period`). Those two cases accept
any amplitude up to 1 rad.

Released otherwise (the beats cases), both modes are excited and the theory is linear: the modes exchange energy
through the quartic terms of the Lagrangian, and each frequency is shifted by ``delta_r a^2``
(`rigidbench.analytic.oscillations.amplitude_shifts`, the averaged Lagrangian): in phase ``-(3/4 + 2 kappa)
a^2/16``, anti-phase ``-(3/4 + 4 kappa) a^2 / (16 + 32 kappa)``, kappa = k d^2 / (m g l) (5.0e-8 and 5.1e-8 at the
default 1 mrad, as measured). The beats cases' regime bounds |amplitude1| so that this neglected shift stays
below a quarter of the frequency tolerance, its phase error over the run (shift x omega x duration) below a
quarter of the waveform's, and its change of omega_a - omega_s below a quarter of the transfer time's. The spring
is not exactly linear in the angles: its length is ``L^2 = (s + d (sin th1 - sin th2))^2 + d^2 (cos th1 - cos
th2)^2`` (s = 0.5 m, the pivot spacing). The sine terms are in the quartic Lagrangian; the second term, the
spring's tilt off the horizontal, changes L only at O(d^2 a^4 / s) and the spring energy at O(k d^3 a^5 / s): a
fifth-order term, negligible.

Time scales: the timestep follows the fastest mode, omega_a (2 ms in the weak-coupling case, 1.96 ms at the
defaults), and a run lasts 30.5 periods of the slowest excited mode, or 2.5 transfer times T_x = pi / (omega_a -
omega_s) if both are excited. Two domains keep runs below ~1e6 steps: kappa <= 199.5 (omega_a / omega_s <= 20; a
range of k that depends on m, g, l and d) and, where both modes are excited, kappa >= 2e-3 (T_x <= 250 carrier
periods).

Exact companions (issue 35): the linear checks' tolerances are sized by the neglected amplitude^2 terms, so each has a
companion ``<check>-exact`` that applies the same measurement to the exact nonlinear motion of the same model (every
number read back from the compiled model; `rigidbench.analytic.oscillations_exact`), sampled at the simulation's
times, and reports the difference: RK4's error at the run's step is what is left (the beats cases; the symmetric
releases are predicted exactly already)."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench.analytic import oscillations as osc
from rigidbench.analytic import oscillations_exact as exact
from rigidbench.contract import Case, Check, Derived, Domain, Scenario, Trajectory
from rigidbench.envs import pendulums
from rigidbench.envs.pendulums import BobMass, PendulumEnv, RodLength, SpringHeight, SpringStiffness
from rigidbench.params import Bound, Gravity, Numeric, Param, Range

_FREQ = (
    "RK4 at dt = 6.30e-3 / omega_a (<= 2 ms in the default cases): relative frequency error (omega dt)^4/120 "
    "<~ 1.3e-11; "
    "normal coordinates from the O7 mode vectors, crossings cubic-interpolated over >= 30 periods; a symmetric "
    "release is predicted exactly at any amplitude, a beats release is in the linear theory's regime (first-order "
    "amplitude shift <= 2.5e-7, module docstring)"
) + pendulums.ROUNDOFF.format(factor="0.5", measured="1e-3 .. 0.04 rho")
_SHAPE = (
    "least-squares fit of th1, th2 at the two measured frequencies over the record; nonlinear terms O(a^2) ~ 1e-6 "
    "of the amplitude leak into the fit, 1e-5 leaves a decade"
)
_WAVE = (
    "the linear solution's phase error grows as the first-order amplitude shift times omega t; the regime of the "
    "beats cases keeps it <= 7.5e-5 of the amplitude over the run (5e-5 in the weak-coupling case at 1 mrad); RK4 "
    "adds ~1e-9"
) + pendulums.ROUNDOFF.format(factor="0.5 omega_a t_run x", measured="0.6 rho omega_a t_run")
CHECKS = (
    Check(
        "omega-in-phase",
        "rad/s",
        1e-6,
        "rel",
        _FREQ,
        "O3: omega_s^2 = M g l / I_O (= g/l for a point bob); released in phase, O1's exact 2 pi / T(a)",
    ),
    Check(
        "omega-anti-phase",
        "rad/s",
        1e-6,
        "rel",
        _FREQ,
        "O3: omega_a^2 = omega_s^2 + 2 k d^2 / I_O (Wilcox eqs 12.10-12.24); released in anti-phase, the exact "
        "period of V = 2 M g l (1 - cos th) + 2 k d^2 sin^2 th",
    ),
    Check("shape-in-phase", "1", 1e-5, "abs", _SHAPE, "O3/O7: th2/th1 = +1 in the in-phase mode"),
    Check("shape-anti-phase", "1", 1e-5, "abs", _SHAPE, "O3/O7: th2/th1 = -1 in the anti-phase mode"),
    Check(
        "transfer-time",
        "s",
        1e-4,
        "rel",
        "vertex of a parabola through the peaks of |th2| within 2 % of the envelope maximum: applied to the exact "
        "O4 signal it errs by <= 2.8e-5 for kappa in the beats' regime [2e-3, 0.1] (tests); the case regime keeps "
        "the first-order amplitude shift's change of omega_a - omega_s below 2.5e-5 of itself"
        + pendulums.ROUNDOFF.format(
            factor="0.5 omega_a / (omega_a - omega_s) x", measured="0.04 rho omega_a / (omega_a - omega_s)"
        ),
        "O4: T_x = pi / (omega_a - omega_s), when all the energy is in pendulum 2 (Wilcox section 12.4)",
    ),
    Check(
        "beat-waveform",
        "1",
        3e-4,
        "abs",
        _WAVE,
        "O4: th1 = A cos(omega0 t) cos(omega_b t), th2 = A sin(omega0 t) sin(omega_b t): max |th - th_O4| / A",
    ),
    Check(
        "energy-drift",
        "1",
        1e-8,
        "abs",
        pendulums.SPRING_CHAIN_ENERGY_REASON + pendulums.ROUNDOFF.format(factor="50", measured="4 .. 5.4 rho"),
        "O3: " + pendulums.SPRING_CHAIN_ENERGY,
    ),
)
# Exact companions (issue 35): each linear check measured the same way on the exact nonlinear motion of the same model
# (`rigidbench.analytic.oscillations_exact`), sampled at the simulation's times; what is left is the integrator's.
EXACT_THEORY = (
    "{ids} exact: the nonlinear equations of motion of the model as compiled (I_O th_i'' = -M g h sin th_i - k (L - "
    "L0) dL/dth_i, L the spring's length between its attachment points), solved by Picard's iteration of Duhamel's "
    "formula to <= 1e-11 of the amplitude; {what}"
)
# The reference's error budget, relative to the amplitude: its a-posteriori bound (`ExactMotion.bound`) is <= 2 eps
# w_max t_run (its phases' rounding) + ~1e-15 (iteration and quadrature), <= 1.7e-12 over the cases' ranges.
_REF = 1e-11
_RK4 = (
    "RK4 at the run's step: relative frequency error eps4 = (omega_a dt)^4 / 120 (1.3e-11 in the default cases); the "
    "same measurement applied to both, so only the integrator's error (and the reference's 1e-11) is left; "
)
EXACT_CHECKS = (
    Check(
        "omega-in-phase-exact",
        "1",
        1.4e-10,
        "abs",
        _RK4 + "tolerance 10 eps4 + 1e-11" + pendulums.ROUNDOFF.format(factor="0.5", measured="as omega-in-phase"),
        EXACT_THEORY.format(ids="O3", what="omega_s measured / omega_s of the exact motion, minus 1"),
    ),
    Check(
        "omega-anti-phase-exact",
        "1",
        1.4e-10,
        "abs",
        _RK4 + "tolerance 10 eps4 + 1e-11" + pendulums.ROUNDOFF.format(factor="0.5", measured="as omega-anti-phase"),
        EXACT_THEORY.format(ids="O3", what="omega_a measured / omega_a of the exact motion, minus 1"),
    ),
    Check(
        "shape-in-phase-exact",
        "1",
        5e-11,
        "abs",
        _RK4 + "the fit's ratio moves with the difference of the modes' phase drifts, measured <= 7.4e-4 eps4 omega_a "
        "t_run (default cases): tolerance 0.01 eps4 omega_a t_run + 1e-11"
        + pendulums.ROUNDOFF.format(factor="3", measured="as shape-in-phase"),
        EXACT_THEORY.format(ids="O3/O7", what="th2/th1 of the in-phase mode, measured minus exact"),
    ),
    Check(
        "shape-anti-phase-exact",
        "1",
        5e-11,
        "abs",
        _RK4 + "the fit's ratio moves with the difference of the modes' phase drifts, measured <= 7.4e-4 eps4 omega_a "
        "t_run (default cases): tolerance 0.01 eps4 omega_a t_run + 1e-11"
        + pendulums.ROUNDOFF.format(factor="3", measured="as shape-anti-phase"),
        EXACT_THEORY.format(ids="O3/O7", what="th2/th1 of the anti-phase mode, measured minus exact"),
    ),
    Check(
        "transfer-time-exact",
        "1",
        6e-9,
        "abs",
        _RK4 + "T_x = pi / (omega_a - omega_s) magnifies the frequencies' errors by omega_a / (omega_a - omega_s): "
        "tolerance 10 eps4 omega_a / (omega_a - omega_s) + 1e-11"
        + pendulums.ROUNDOFF.format(factor="0.5 omega_a / (omega_a - omega_s) x", measured="as transfer-time"),
        EXACT_THEORY.format(ids="O4", what="T_x measured / T_x of the exact motion, minus 1"),
    ),
    Check(
        "beat-waveform-exact",
        "1",
        4e-8,
        "abs",
        _RK4
        + "the phase error grows as eps4 omega_a t: tolerance 10 eps4 omega_a t_run + 1e-11"
        + pendulums.ROUNDOFF.format(factor="0.5 omega_a t_run x", measured="as beat-waveform"),
        EXACT_THEORY.format(ids="O4", what="max |th - th_exact| / A over the run"),
    ),
)
CHECKS = CHECKS + EXACT_CHECKS
_BEATS = (
    "omega-in-phase",
    "omega-anti-phase",
    "shape-in-phase",
    "shape-anti-phase",
    "transfer-time",
    "beat-waveform",
    "energy-drift",
    *(c.name for c in EXACT_CHECKS),
)
# too few carrier peaks per beat to locate T_x
_STRONG = tuple(c for c in _BEATS if c not in ("transfer-time", "transfer-time-exact"))
_MODES = ("in-phase", "anti-phase")


# Domains of kappa = k d^2 / (m g l) (module docstring): omega_a / omega_s = sqrt(1 + 2 kappa) <= 20; both modes
# excited: T_x ~ pi / (kappa omega_s) <= 250 carrier periods; a transfer time resolved by the envelope's peaks:
# kappa <= 0.1 (omega_b / omega0 <= 0.0455), where the estimator errs by <= 2.8e-5 on the exact O4 signal (tests).
KAPPA_MAX = (20.0**2 - 1) / 2
KAPPA_MIN = 2e-3
KAPPA_BEATS = (KAPPA_MIN, 0.1)
# The first-order amplitude shift may take this fraction of a check's tolerance (the rest is the integrator's).
SHIFT_SHARE = 0.25
_BEATS_REGIME = (
    "O4's beats: kappa = k d^2 / (m g l) in [2e-3, 0.1]: the transfer time is resolved by the envelope's peaks "
    "(omega_b / omega0 <= 0.0455) and reached within 2.5 T_x <= 625 carrier periods; the linear theory's amplitudes: "
    "|amplitude1| <= a_max, where the first-order amplitude shift of the modes (averaged quartic Lagrangian) stays "
    "below a quarter of the frequency (1e-6), waveform (3e-4 over the run) and transfer-time (1e-4) tolerances; "
    "pendulum 2 starts at rest at 0; the springs' attachment points stay s/10 apart"
)
_STRONG_REGIME = (
    "both modes excited: kappa = k d^2 / (m g l) in [2e-3, 199.5] (2.5 T_x <= 625 carrier periods; omega_a / omega_s "
    "<= 20); the linear theory's amplitudes: |amplitude1| <= a_max, where the first-order amplitude shift of the "
    "modes stays below a quarter of the frequency (1e-6) and waveform (3e-4 over the run) tolerances; pendulum 2 "
    "starts at rest at 0; the springs' attachment points stay s/10 apart"
)


def _kappa_range(low: float, high: float, why: str) -> Bound:
    def bound(p: Mapping[str, Any]) -> Range:
        scale = p["mass"] * p["g"] * p["length"] / p["d"] ** 2
        return Range(low * scale, high * scale, low_open=low == 0.0)

    return Bound(
        f"{'(0' if low == 0 else f'[{low:g}'}, {high:g}] m g l / d^2 ({why})", bound, ("mass", "length", "d", "g")
    )


def _omegas(p: Mapping[str, Any]) -> tuple[float, float]:
    """(omega_s, omega_a) (rad/s) from the requested parameters (point bobs, I_O = m l^2 + the bob's 1e-9 kg m^2)."""
    inertia = p["mass"] * p["length"] ** 2 + 1e-9
    return osc.coupled_frequencies(inertia, p["mass"] * p["g"] * p["length"], p["k"], p["d"])


def amplitude_limit(p: Mapping[str, Any]) -> float:
    """Largest |amplitude1| (rad), pendulum 2 released at rest at 0, at which the linear theory's neglected first-order
    amplitude shift stays below `SHIFT_SHARE` of the frequency, waveform and transfer-time tolerances."""
    inertia = p["mass"] * p["length"] ** 2 + 1e-9
    mgl = p["mass"] * p["g"] * p["length"]
    modes = osc.coupled_modes(inertia, mgl, p["k"], p["d"])
    a = 1e-3
    shift = osc.amplitude_shifts(modes, osc.spring_chain_quartic(mgl, p["k"], p["d"]), modes.coordinates([a, 0.0]))
    per_a2 = np.abs(shift) / a**2  # relative shift of each mode per rad^2
    omega_s, omega_a = modes.frequencies
    duration = max(30.5 * 2 * np.pi / omega_s, 2.5 * np.pi / (omega_a - omega_s))
    tol = {c.name: c.tolerance for c in CHECKS}
    limits = [
        pendulums.spring_collapse_limit(p["d"]) ** 2,
        SHIFT_SHARE * tol["omega-in-phase"] / per_a2.max(),
        SHIFT_SHARE * tol["beat-waveform"] / ((per_a2 * modes.frequencies).max() * duration),
        SHIFT_SHARE * tol["transfer-time"] * (omega_a - omega_s) / abs(np.diff(shift / a**2 * modes.frequencies)[0]),
    ]
    return float(np.sqrt(min(limits)))


def _beats_regime(kappa: tuple[float, float]) -> dict[str, Range | Bound]:
    amplitude = Bound(
        "[-a_max, a_max], a_max(mass, length, k, d, g) from the first-order amplitude shift (case regime)",
        lambda p: Range(-amplitude_limit(p), amplitude_limit(p)),
        ("mass", "length", "k", "d", "g"),
    )
    return {
        "k": _kappa_range(*kappa, "case regime"),
        "amplitude1": amplitude,
        "amplitude2": Range(0.0, 0.0),
    }


def _in_mode(sign: int) -> Bound:
    """The one amplitude2 that releases the pair in the in-phase (+1) or anti-phase (-1) mode's shape: sign x
    amplitude1."""
    text = ("amplitude1" if sign > 0 else "-amplitude1") + ", the " + ("in-phase" if sign > 0 else "anti-phase")
    text += " mode's shape th2/th1 = " + ("+1" if sign > 0 else "-1") + " (O3)"

    def exact(p: Mapping[str, Any]) -> Range:
        value = sign * p["amplitude1"]
        return Range(value, value)

    return Bound(text, exact, ("amplitude1",))


_IN_MODE_REGIME = (
    "released in the mode's shape (amplitude2 = +-amplitude1): another amplitude2 mixes both modes, whose frequencies "
    "and shapes the case's checks read one at a time, and the symmetric motion's exact period no longer applies"
)


class CoupledPendulums(Scenario):
    """Two identical pendulums and a spring at d below the pivots: normal modes, beats, energy transfer
    (docs/theory.md O3, O4, O7)."""

    slug = "coupled-pendulums"
    title = "Two identical pendulums coupled by a spring (normal modes and beats)"
    env_id = "rigidbench/CoupledPendulums-v0"
    # Bounds: 1 g to 1 t, 1 mm to 100 m, microgravity to 100 g. The spring matters through kappa = k d^2 / (m g l),
    # so k's own range is wide and its dependent range bounds kappa (run length: module docstring).
    params = (
        Param("mass", "kg", "mass m of each point bob", Range(1e-3, 1e3), BobMass()),
        Param("length", "m", "distance l from each pivot to its bob", Range(1e-3, 100.0), RodLength()),
        Param(
            "k",
            "N/m",
            "stiffness of the coupling spring (linear, relaxed at equilibrium)",
            Range(1e-15, 1e15),
            SpringStiffness(),
            within=_kappa_range(0.0, KAPPA_MAX, "omega_a / omega_s <= 20: 30 slow periods stay below 6e5 steps"),
        ),
        Param(
            "d",
            "m",
            "distance below the pivots at which the spring is attached, on the rod between pivot and bob",
            Range(1e-6, 100.0),
            SpringHeight(),
            within=Bound("[1e-3 length, length]", lambda p: Range(1e-3 * p["length"], p["length"]), ("length",)),
        ),
        Param("amplitude1", "rad", "release angle of pendulum 1 (at rest)", Range(-1.0, 1.0), Numeric("amplitude1")),
        Param("amplitude2", "rad", "release angle of pendulum 2 (at rest)", Range(-1.0, 1.0), Numeric("amplitude2")),
        Param("g", "m/s^2", "gravitational acceleration (along -z)", Range(1e-6, 1e3), Gravity()),
    )
    cases = (
        Case(
            "in-phase",
            "both released at the same angle: the in-phase mode alone, a lone pendulum at any amplitude",
            {"amplitude2": lambda p: p["amplitude1"]},
            ("omega-in-phase", "shape-in-phase", "energy-drift"),
            ranges={"amplitude2": _in_mode(+1)},
            regime=_IN_MODE_REGIME,
        ),
        Case(
            "anti-phase",
            "released at opposite angles: the anti-phase mode alone, exact at any amplitude",
            {"amplitude2": lambda p: -p["amplitude1"]},
            ("omega-anti-phase", "shape-anti-phase", "energy-drift"),
            ranges={
                "amplitude1": Bound(
                    "[-a_c, a_c], 2 d sin(a_c) = 0.9 s",
                    lambda p: Range(-pendulums.spring_collapse_limit(p["d"]), pendulums.spring_collapse_limit(p["d"])),
                    ("d",),
                ),
                "amplitude2": _in_mode(-1),
            },
            regime="the attachment points, s = 0.5 m apart, swing towards each other by 2 d sin(a): they stay at least "
            "s/10 apart (at 2 d sin(a) = s they meet and the spring's stretch is no longer 2 d sin th); "
            + _IN_MODE_REGIME,
        ),
        Case(
            "beats",
            "pendulum 1 released, pendulum 2 at rest: beats (k d^2 / m g l = 0.025)",
            {"amplitude2": 0.0},
            _BEATS,
            ranges=_beats_regime(KAPPA_BEATS),
            regime=_BEATS_REGIME,
        ),
        Case(
            "weak-coupling",
            "beats with k = 0.25 N/m (k d^2 / m g l = 0.0064): slow, complete energy transfer",
            {"amplitude2": 0.0, "k": 0.25},
            _BEATS,
            ranges=_beats_regime(KAPPA_BEATS),
            regime=_BEATS_REGIME,
        ),
        Case(
            "strong-coupling",
            "pendulum 1 released with k = 20 N/m (k d^2 / m g l = 0.5): omega_a = 1.42 omega_s",
            {"amplitude2": 0.0, "k": 20.0},
            _STRONG,
            ranges=_beats_regime((KAPPA_MIN, KAPPA_MAX)),
            regime=_STRONG_REGIME,
        ),
    )
    checks = CHECKS
    domains = (
        Domain(
            "double-precision",
            "O3/O4 measured in MuJoCo",
            pendulums.ROUNDOFF_DOMAIN_TEXT,
            lambda p: pendulums.roundoff_outside(
                p, pendulums.PIVOT_SPACING / 2, max(abs(float(p["amplitude1"])), abs(float(p["amplitude2"])))
            ),
        ),
    )

    def validate(self, params: Mapping[str, Any]) -> None:
        if params["amplitude1"] == 0 and params["amplitude2"] == 0:
            raise ValueError("parameters 'amplitude1' and 'amplitude2' are both 0: nothing moves (valid: not both 0)")

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        """The timestep follows the faster mode, omega_a (2 ms at the model's defaults)."""
        return {"timestep": pendulums.timestep_for(_omegas(params)[1], _rate0(type(self)), "omega_a")}

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[:] = [params["amplitude1"], params["amplitude2"]]
        data.qvel[:] = 0.0

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        p1, p2 = pendulums.pendulums(model)
        sp = pendulums.springs(model)
        g = pendulums.gravity(model)
        mgl = p1.mass * g * p1.length
        k = float(sp.stiffness[0])
        modes = osc.coupled_modes(p1.inertia_pivot, mgl, k, sp.height)
        omega_s, omega_a = osc.coupled_frequencies(p1.inertia_pivot, mgl, k, sp.height)
        angles0 = data.qpos.copy()
        beats = osc.Beats(float(angles0[0]), omega_s, omega_a)
        excited = np.abs(modes.coordinates(angles0)) > 1e-9 * np.abs(angles0).max()
        # A symmetric release is a one-degree-of-freedom motion: its exact frequency at any amplitude.
        amplitude = abs(float(angles0[0]))
        if angles0[0] == angles0[1]:  # th1 = th2: a lone pendulum of length I_O / (M h) (O1, O2)
            omega_s = 2 * np.pi / osc.pendulum_period(p1.inertia_pivot * g / mgl, g, amplitude)
        elif angles0[0] == -angles0[1]:  # th1 = -th2: the spring stays level (anti_phase_period)
            omega_a = 2 * np.pi / osc.anti_phase_period(p1.inertia_pivot, mgl, k, sp.height, amplitude)
        periods = 2 * np.pi / np.array([omega_s, omega_a])
        duration = 30.5 * periods[excited].max()
        if excited.all():
            duration = max(duration, 2.5 * beats.transfer_time)
        ratios = modes.shape_ratios()[1]
        rho = pendulums.roundoff(model, float(np.abs(angles0).max()))
        gains = _roundoff_gains(omega_a, omega_a - omega_s, duration)
        tolerance = _roundoff_tolerances(rho, gains)
        if excited.all():  # both modes: the linear theory's cases, whose checks have exact companions
            tolerance.update(_exact_tolerances(omega_a, omega_s, float(model.opt.timestep), duration, rho, gains))
        return {
            "_modes": modes,
            "_excited": excited,
            "_angles0": angles0,
            "_beats": beats,
            "_duration": duration,
            "_scale": float(np.abs(angles0).max()),
            "_energy_scale": float(pendulums.row_energy(model, angles0[None], np.zeros((1, 2)))[0]),
            "_tolerance": tolerance,
            "_roundoff_eps": pendulums.roundoff_per_eps(
                rho, {**gains, **{c.name: gains[c.name.removesuffix("-exact")] for c in EXACT_CHECKS}}
            ),
            "_roundoff_eps_rule": pendulums.ROUNDOFF_EPS_RULE,
            "omega-in-phase": omega_s,
            "omega-anti-phase": omega_a,
            "shape-in-phase": float(ratios[0]),
            "shape-anti-phase": float(ratios[1]),
            "transfer-time": beats.transfer_time,
            "beat-waveform": 0.0,
            "energy-drift": 0.0,
            **{c.name: 0.0 for c in EXACT_CHECKS},
        }

    def check_model(self, model: mujoco.MjModel) -> None:
        p1, p2 = pendulums.pendulums(model)
        if (p1.mass, p1.length, p1.inertia_cm) != (p2.mass, p2.length, p2.inertia_cm):
            raise ValueError(f"the two pendulums differ ({p1} vs {p2}); O3 needs identical pendulums")

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return prediction["_duration"]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        t, theta = traj.time, traj.qpos
        sim = _observe(t, theta, traj.qvel, prediction)
        linear = prediction["_modes"].angles(t, prediction["_angles0"])
        out = {
            **sim,
            "beat-waveform": float(np.abs(theta - linear).max() / prediction["_scale"]),
            "energy-drift": pendulums.energy_drift(
                pendulums.row_energy(model, traj.qpos, traj.qvel), prediction["_energy_scale"]
            ),
        }
        if prediction["_excited"].all():
            out.update(_exact_companions(model, traj, prediction, sim))
        return out


def _observe(t: np.ndarray, theta: np.ndarray, rate: np.ndarray, prediction: Mapping[str, Any]) -> dict[str, float]:
    """The measured frequencies, shapes and transfer time of a motion (angles and rates sampled at `t`)."""
    omegas, shapes = pendulums.two_modes(t, theta, prediction["_modes"], prediction["_excited"])
    return {
        "omega-in-phase": omegas[0],
        "omega-anti-phase": omegas[1],
        "shape-in-phase": shapes.get(0, np.nan),
        "shape-anti-phase": shapes.get(1, np.nan),
        "transfer-time": transfer_time(t, theta[:, 1], rate[:, 1], before=2 * prediction["transfer-time"]),
    }


def _exact_companions(
    model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any], sim: Mapping[str, float]
) -> dict[str, float]:
    """The companions' values: each quantity of `sim` against the same measurement of the exact motion."""
    ref = exact.motion(
        traj.time,
        exact.SpringRow(**pendulums.spring_row(model)).acceleration,
        prediction["_modes"],
        prediction["_angles0"],
    )
    if not ref.bound <= _REF:  # the reference did not converge (beyond the linear regime): the companions fail
        return {c.name: np.nan for c in EXACT_CHECKS}
    ex = _observe(traj.time, ref.angles, ref.rates, prediction)
    out = {
        "omega-in-phase-exact": sim["omega-in-phase"] / ex["omega-in-phase"] - 1,
        "omega-anti-phase-exact": sim["omega-anti-phase"] / ex["omega-anti-phase"] - 1,
        "shape-in-phase-exact": sim["shape-in-phase"] - ex["shape-in-phase"],
        "shape-anti-phase-exact": sim["shape-anti-phase"] - ex["shape-anti-phase"],
        "transfer-time-exact": sim["transfer-time"] / ex["transfer-time"] - 1,
        "beat-waveform-exact": float(np.abs(traj.qpos - ref.angles).max() / prediction["_scale"]),
    }
    return {name: float(value) for name, value in out.items()}


def _exact_tolerances(
    omega_a: float, omega_s: float, timestep: float, duration: float, rho: float, gains: Mapping[str, float]
) -> dict[str, float]:
    """The companions' tolerances (`EXACT_CHECKS`' reasons): RK4's error at the run's step, the reference's budget, or
    the double-precision floor of the check they accompany if larger."""
    eps4 = pendulums.rk4_frequency_error(omega_a, timestep)
    split = omega_a - omega_s
    base = {
        "omega-in-phase-exact": 10 * eps4,
        "omega-anti-phase-exact": 10 * eps4,
        "shape-in-phase-exact": 0.01 * eps4 * omega_a * duration,
        "shape-anti-phase-exact": 0.01 * eps4 * omega_a * duration,
        "transfer-time-exact": 10 * eps4 * omega_a / split if split > 0 else np.inf,
        "beat-waveform-exact": 10 * eps4 * omega_a * duration,
    }
    return {name: max(value + _REF, gains[name.removesuffix("-exact")] * rho) for name, value in base.items()}


@functools.cache
def _rate0(cls: type[CoupledPendulums]) -> float:
    return pendulums.default_rate(cls(), lambda p: _omegas(p)[1])


def _roundoff_gains(omega_a: float, split: float, duration: float) -> dict[str, float]:
    """Each check's double-precision floor over rho (`pendulums.ROUNDOFF_DOMAIN_TEXT`)."""
    return {
        "omega-in-phase": 0.5,
        "omega-anti-phase": 0.5,
        "shape-in-phase": 3.0,
        "shape-anti-phase": 3.0,
        "transfer-time": 0.5 * omega_a / split if split > 0 else np.inf,
        "beat-waveform": 0.5 * omega_a * duration,
        "energy-drift": 50.0,
    }


def _roundoff_tolerances(rho: float, gains: dict[str, float]) -> dict[str, float]:
    """Each linear check's tolerance, or its double-precision floor ``gain x rho`` if larger (the companions':
    `_exact_tolerances`)."""
    return {c.name: max(c.tolerance, gains[c.name] * rho) for c in CHECKS if c.name in gains}


def transfer_time(t: np.ndarray, angle2: np.ndarray, rate2: np.ndarray, *, before: float = np.inf) -> float:
    """First time (s) pendulum 2's swing is largest, from the peaks of |th2| (O4's T_x).

    Only the peaks before `before` (s) count: the envelope peaks again at 3 T_x, 5 T_x, ..., so the caller
    passes a window ending near the envelope's first zero (2 T_x predicted; a window, not a bias).

    The extrema of th2 (zero crossings of its rate, cubic-interpolated) sample its envelope once per half
    carrier period; the vertex of a least-squares parabola through the peaks within 2 % of the largest one,
    contiguous around it, locates the envelope's maximum well below the carrier's half period. NaN with fewer
    than three such peaks (coupling too strong for a resolved envelope).
    """
    from rigidbench import signals

    tc = signals.crossings(t, rate2)
    tc = tc[tc < before]
    if len(tc) < 3:
        return float("nan")
    peaks = np.abs(signals.interpolate(t, angle2, tc))
    i = int(np.argmax(peaks))
    near = peaks >= 0.98 * peaks[i]
    lo, hi = i, i
    while lo > 0 and near[lo - 1]:
        lo -= 1
    while hi < len(peaks) - 1 and near[hi + 1]:
        hi += 1
    if hi - lo < 2:
        return float("nan")
    c = np.polyfit(tc[lo : hi + 1] - tc[i], peaks[lo : hi + 1], 2)
    return float(tc[i] - c[1] / (2 * c[0]))


class CoupledPendulumsEnv(PendulumEnv):
    """``rigidbench/CoupledPendulums-v0``: two spring-coupled pendulums, scored against the normal-mode solution.

    Description
        Two identical point-bob pendulums hinged about the world y axis at x = -0.25 m and +0.25 m, joined by a
        linear spring (stiffness ``k``) attached at ``d`` below the pivots, relaxed at equilibrium. With zero
        action the motion is docs/theory.md O3/O4: a superposition of the in-phase mode (omega_s^2 = M g l / I_O)
        and the anti-phase mode (omega_a^2 = omega_s^2 + 2 k d^2 / I_O); from one pendulum released, beats
        with all the energy in pendulum 2 at T_x = pi / (omega_a - omega_s).

    Observation Space
        Box(-inf, inf, (4,)), float64:

        ==== ===================================== ====== ==================
        idx  quantity                              unit   MuJoCo source
        ==== ===================================== ====== ==================
        0    angle of pendulum 1 from the vertical rad    qpos of ``hinge1``
        1    angle of pendulum 2 from the vertical rad    qpos of ``hinge2``
        2    rate of pendulum 1                    rad/s  qvel of ``hinge1``
        3    rate of pendulum 2                    rad/s  qvel of ``hinge2``
        ==== ===================================== ====== ==================

        A positive angle turns the bob towards -x.

    Action Space
        Box(-1, 1, (1,)), float32, normalised: ``action_scale = 0.1`` N m times it is a torque on pendulum 1
        about its hinge, through ``qfrc_applied``;
        out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -max_i |th_i - th_i,theory(t)| / max_i |th_i(0)|``, the theory being the linear normal-mode
        solution (O4/O7); ``info["measured"]["angles"]`` and ``info["predicted"]["angles"]`` hold both (rad).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        At rest at (``amplitude1``, ``amplitude2``) (rad).

    Episode End
        Truncated after 30.5 periods of the slowest excited mode, or 2.5 T_x if both modes are excited;
        terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (in-phase, anti-phase, beats, weak-coupling, strong-coupling), ``params`` (mass, length, k, d,
        amplitude1, amplitude2, g), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10: ten
        derived steps, 19.6 ms at the defaults), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = CoupledPendulums

    def theory(self, t: np.ndarray) -> np.ndarray:
        return self.prediction["_modes"].angles(t, self.prediction["_angles0"])
