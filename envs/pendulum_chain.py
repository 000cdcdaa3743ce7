"""Chain of N identical pendulums with nearest-neighbour springs: the MuJoCo side, and its gymnasium env.

Theory: docs/theory.md O5 (``omega_r^2 = g/l + 4 kappa sin^2(r pi / 2N)``, ``kappa = k d^2 / (m l^2)``, shapes
``cos(r pi (j + 1/2) / N)``) and O7 (``det(V - omega^2 T) = 0``, Wilcox Part II section 12.2, eqs 12.15-12.26),
implemented in `rigidbench.analytic.oscillations`. Model: ``models/pendulum_chain.xml``, a one-pendulum template
from which `rigidbench.envs.pendulums.ChainSize` builds the chain through `mujoco.MjSpec`.

The number of modes depends on ``n``: the lowest and highest modes get a row each with their frequencies, and
every mode is covered by rows holding the largest relative error over all of them (NaN, a failure, if any mode's
frequency could not be measured). The prediction holds every mode (``prediction["_omega_O7"]``, ``["_omega_O5"]``).

Amplitude: the theory is linear, and one pendulum released excites every mode. The quartic terms of the
Lagrangian (`rigidbench.analytic.oscillations.spring_chain_quartic`: gravity's th^4/24 and the springs' sin th)
shift each mode's frequency by ``delta_r a^2`` (`rigidbench.analytic.oscillations.amplitude_shifts`, the averaged
Lagrangian) and, near the modes' 1:1 resonances, exchange energy between neighbouring modes, which leaks a relative
``~ delta omega / (omega_{r+1} - omega_r)`` of one mode into the next: the mode-purity residual (measured 2.5e-6 at
the defaults, as this estimates). The case regimes bound |amplitude| so that both stay below a quarter of their
tolerances, and the attachment points of neighbours stay s/10 apart (`pendulums.spring_collapse_limit`).

Time scales: the timestep follows the highest mode (2 ms at the defaults), and a run lasts 30.5 periods of the
lowest; kappa = k d^2 / (m g l) <= 24.75 (a range of k that depends on m, g, l and d: omega_highest / omega_lowest
<= 10) keeps runs below 3e5 steps.

Exact companions (issue 35): the linear checks' tolerances are sized by the neglected amplitude^2 terms, so each has a
companion ``<check>-exact`` that applies the same measurement to the exact nonlinear motion of the same model (every
number read back from the compiled model; `rigidbench.analytic.oscillations_exact`), sampled at the simulation's
times, and reports the difference: RK4's error at the run's step is what is left (every mode's frequency, and the
mode purity).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench.analytic import oscillations as osc
from rigidbench.analytic import oscillations_exact as exact
from rigidbench.contract import Case, Check, Derived, Domain, Params, Scenario, Trajectory
from rigidbench.envs import pendulums
from rigidbench.envs.pendulums import BobMass, ChainSize, PendulumEnv, RodLength, SpringHeight, SpringStiffness
from rigidbench.params import Bound, Gravity, Numeric, Param, Range

MAX_PENDULUMS = 40

_FREQ = (
    "RK4 at dt = 6.55e-3 / omega_highest (2 ms at the defaults): relative frequency error (omega dt)^4/120 <~ 2e-11; "
    "normal coordinates from the O5 mode vectors (modal filter), crossings cubic-interpolated over >= 30 periods; "
    "first-order amplitude shifts <= 2.5e-7 in the case regime (1e-7 at the default 1 mrad; module docstring)"
) + pendulums.ROUNDOFF.format(factor="0.5", measured="1e-3 .. 0.04 rho")
CHECKS = (
    Check(
        "omega-lowest",
        "rad/s",
        1e-6,
        "rel",
        _FREQ,
        "O5/O7: r = 0, all in phase, springs unstretched: omega_0^2 = M g l / I_O",
    ),
    Check(
        "omega-highest",
        "rad/s",
        1e-6,
        "rel",
        _FREQ,
        "O5/O7: r = N-1: omega^2 = M g l / I_O + 4 k d^2 sin^2((N-1) pi / 2N) / I_O",
    ),
    Check(
        "mode-frequencies",
        "1",
        1e-6,
        "abs",
        _FREQ + "; the row is max over all N modes of |omega_measured / omega_O7 - 1|",
        "O7: roots of det(V - omega^2 T) = 0, T = I_O 1, V = M g l 1 + k d^2 (path Laplacian) (Wilcox eq. 12.17)",
    ),
    Check(
        "mode-frequencies-closed-form",
        "1",
        1e-6,
        "abs",
        _FREQ + "; the row is max over all N modes of |omega_measured / omega_O5 - 1|",
        "O5: omega_r^2 = M g l / I_O + 4 k d^2 sin^2(r pi / 2N) / I_O, r = 0 ... N-1",
    ),
    Check(
        "mode-purity",
        "1",
        1e-4,
        "abs",
        "the O5 shapes are the chain's modes iff each modal-filter output is a single sinusoid: max over modes of "
        "max |q_r - (best sinusoid at the measured omega_r)| / its amplitude. Nonlinear mode coupling leaks O(a^2) "
        "~ 1e-6 of the amplitude into every q_r, divided by the weakest mode's share sin(pi/2N) of the release "
        "(0.31 at N = 5, 0.13 at N = 12); 1e-4 leaves a decade. A shape error delta shows up as ~delta times the "
        "other modes' amplitudes"
        + pendulums.ROUNDOFF.format(
            factor="max(3, 0.5 min(omega_N / min mode spacing, omega_N T)) x",
            measured="0.01 .. 0.9 rho at N <= 4, <= 0.16 rho min(omega/spacing, omega T) up to N = 40",
        ),
        "O5: th_j proportional to cos(r pi (j + 1/2) / N); O7: normal coordinates oscillate alone (Wilcox eq. 12.26)",
    ),
    Check(
        "energy-drift",
        "1",
        1e-8,
        "abs",
        pendulums.SPRING_CHAIN_ENERGY_REASON + pendulums.ROUNDOFF.format(factor="50", measured="4 .. 5.4 rho"),
        "O5: " + pendulums.SPRING_CHAIN_ENERGY,
    ),
)
# Exact companions (issue 35): the frequencies and the mode purity measured the same way on the exact nonlinear motion
# of the same model (`rigidbench.analytic.oscillations_exact`), sampled at the simulation's times.
# The reference's error budget, relative to the amplitude: its a-posteriori bound (`ExactMotion.bound`) is <= 2 eps
# w_max t_run (its phases' rounding) + ~1e-15 (iteration and quadrature), <= 1.7e-12 over the cases' ranges.
_REF = 1e-11
_EXACT_THEORY = (
    "{ids} exact: the nonlinear equations of motion of the chain as compiled (I_O th_i'' = -M g h sin th_i - sum k (L "
    "- L0) dL/dth_i over its springs, L a spring's length between its attachment points), solved by Picard's "
    "iteration of Duhamel's formula to <= 1e-11 of the amplitude; {what}"
)
_RK4 = (
    "RK4 at the run's step: relative frequency error eps4 = (omega_highest dt)^4 / 120 (1.5e-11 at the defaults); "
    "the same measurement applied to both, so only the integrator's error (and the reference's 1e-11) is left; "
)
EXACT_CHECKS = (
    Check(
        "mode-frequencies-exact",
        "1",
        1.6e-10,
        "abs",
        _RK4 + "tolerance 10 eps4 + 1e-11" + pendulums.ROUNDOFF.format(factor="0.5", measured="as mode-frequencies"),
        _EXACT_THEORY.format(
            ids="O5/O7",
            what="the companion of omega-lowest, omega-highest, mode-frequencies and mode-frequencies-closed-form: "
            "the largest |omega_r measured / omega_r of the exact motion - 1| over the N modes (signed)",
        ),
    ),
    Check(
        "mode-purity-exact",
        "1",
        1.1e-10,
        "abs",
        _RK4
        + "the residual moves with the modes' phase drifts: measured <= 8.5e-4 eps4 omega_highest t_run / sin(pi / "
        "2N) (the weakest mode's share of the release) in the default cases; tolerance 0.01 of that + 1e-11"
        + pendulums.ROUNDOFF.format(factor="as mode-purity:", measured="as mode-purity"),
        _EXACT_THEORY.format(ids="O5/O7", what="the mode-purity residual measured minus that of the exact motion"),
    ),
)
CHECKS = CHECKS + EXACT_CHECKS
_ALL = (
    "omega-lowest",
    "omega-highest",
    "mode-frequencies",
    "mode-frequencies-closed-form",
    "mode-purity",
    "energy-drift",
    *(c.name for c in EXACT_CHECKS),
)


# kappa = k d^2 / (m g l) <= 24.75: omega_highest / omega_lowest <= sqrt(1 + 4 kappa) = 10.
KAPPA_MAX = (10.0**2 - 1) / 4
# The neglected first-order amplitude effects may take this fraction of a check's tolerance.
SHIFT_SHARE = 0.25


def _amplitude_range(a_max: float) -> Range:
    """[-a_max, a_max]; empty, (-0, 0), where no amplitude is linear (a census then draws the other parameters
    again)."""
    return Range(-a_max, a_max, low_open=a_max == 0, high_open=a_max == 0)


_REGIME = {
    "amplitude": Bound(
        "[-a_max, a_max], a_max(n, mass, length, k, d, g) from the first-order amplitude shift (case regime)",
        lambda p: _amplitude_range(amplitude_limit(p)),
        ("n", "mass", "length", "k", "d", "g"),
    )
}
_REGIME_TEXT = (
    "the linear theory's amplitudes (O5/O7): |amplitude| <= a_max, where the first-order amplitude shift of the modes "
    "(averaged quartic Lagrangian) stays below a quarter of the frequency tolerance (1e-6), the energy it moves "
    "between neighbouring modes near their 1:1 resonance (shift x omega / mode spacing) below a quarter of the "
    "mode-purity tolerance (1e-4), and the springs' attachment points s/10 apart"
)


class PendulumChain(Scenario):
    """N identical pendulums in a row, neighbours coupled by springs, free ends: every normal mode (docs/theory.md
    O5, O7)."""

    slug = "pendulum-chain"
    title = "Chain of N spring-coupled pendulums (normal modes)"
    env_id = "rigidbench/PendulumChain-v0"
    params = (
        # n first: ChainSize builds the bodies the other targets then set.
        Param(
            "n",
            "1",
            "number of pendulums in the chain",
            Range(2, MAX_PENDULUMS),
            ChainSize(),
            integer=True,
        ),
        # Bounds: 1 g to 1 t, 1 mm to 100 m, microgravity to 100 g. The springs matter through kappa = k d^2 /
        # (m g l): k's own range is wide and its dependent range bounds kappa (run length, module docstring).
        Param("mass", "kg", "mass m of each point bob", Range(1e-3, 1e3), BobMass()),
        Param("length", "m", "distance l from each pivot to its bob", Range(1e-3, 100.0), RodLength()),
        Param(
            "k",
            "N/m",
            "stiffness of each coupling spring (linear, relaxed at equilibrium)",
            Range(1e-15, 1e15),
            SpringStiffness(),
            within=Bound(
                f"(0, {KAPPA_MAX:g}] m g l / d^2 (omega_highest / omega_lowest <= 10: 30 slow periods stay below "
                "3e5 steps)",
                lambda p: Range(0.0, KAPPA_MAX * p["mass"] * p["g"] * p["length"] / p["d"] ** 2, low_open=True),
                ("mass", "length", "d", "g"),
            ),
        ),
        Param(
            "d",
            "m",
            "distance below the pivots at which the springs are attached, on the rods between pivots and bobs",
            Range(1e-6, 100.0),
            SpringHeight(),
            within=Bound("[1e-3 length, length]", lambda p: Range(1e-3 * p["length"], p["length"]), ("length",)),
        ),
        Param(
            "amplitude",
            "rad",
            "release angle of pendulum 1 (the others hang at rest)",
            Range(-1.0, 1.0),
            Numeric("amplitude"),
        ),
        Param("g", "m/s^2", "gravitational acceleration (along -z)", Range(1e-6, 1e3), Gravity()),
    )
    cases = (
        Case(
            "end-released",
            "pendulum 1 released, the others at rest: every mode excited",
            {},
            _ALL,
            ranges=_REGIME,
            regime=_REGIME_TEXT,
        ),
        Case(
            "strong-coupling",
            "k = 10 N/m (k d^2 / m g l = 0.25): the mode frequencies spread over a factor 1.7",
            {"k": 10.0},
            _ALL,
            ranges=_REGIME,
            regime=_REGIME_TEXT,
        ),
    )
    checks = CHECKS
    domains = (
        Domain(
            "double-precision",
            "O5/O7 measured in MuJoCo",
            pendulums.ROUNDOFF_DOMAIN_TEXT
            + "; for the chain rho x max(1, g_p / 10), g_p = max(3, 0.5 min(omega_N / min mode spacing, omega_N T)) "
            "the mode purity's round-off gain (nearly degenerate modes exchange the round-off's energy; "
            "`purity_gain`), so that its tolerance stays <= 0.1",
            lambda p: pendulums.roundoff_outside(
                p, (round(p["n"]) - 1) / 2 * pendulums.PIVOT_SPACING, float(p["amplitude"]), _purity_gain(p)
            ),
        ),
    )

    def defaults(self) -> Params:
        """Defaults from the model file, with the chain built at its default size (the raw file is the template)."""
        return _chain_defaults(type(self))

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        """The timestep follows the highest mode (2 ms at the model's defaults)."""
        return {"timestep": pendulums.timestep_for(_highest(params), _rate0(type(self)), "omega_highest")}

    def validate(self, params: Mapping[str, Any]) -> None:
        if params["amplitude"] == 0:
            raise ValueError("parameter 'amplitude' = 0 rad: nothing moves (valid: [-1, 1] rad, not 0)")

    def check_model(self, model: mujoco.MjModel) -> None:
        pend = pendulums.pendulums(model)
        if len({(p.mass, p.length, p.inertia_cm) for p in pend}) != 1:
            raise ValueError("the chain's pendulums differ; O5 needs identical pendulums")
        sp = pendulums.springs(model)
        if sp.pairs != [(i, i + 1) for i in range(len(pend) - 1)] or len(set(sp.stiffness)) != 1:
            raise ValueError(f"the springs {sp.pairs} do not join neighbours 1-2, 2-3, ... with one stiffness")

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[:] = 0.0
        data.qpos[0] = params["amplitude"]
        data.qvel[:] = 0.0

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        pend = pendulums.pendulums(model)
        sp = pendulums.springs(model)
        n, p = len(pend), pend[0]
        mgl = p.mass * pendulums.gravity(model) * p.length
        k = float(sp.stiffness[0])
        # The modal filter uses the O5 shapes (exact however weak the coupling); O7's eigenvalues are the theory of
        # the mode-frequencies row.
        modes = osc.chain_modes(n, p.inertia_pivot, mgl, k, sp.height)
        closed = modes.frequencies
        omega_o7 = osc.normal_modes(*osc.spring_chain_matrices(n, p.inertia_pivot, mgl, k, sp.height)).frequencies
        angles0 = data.qpos.copy()
        rho = pendulums.roundoff(model, float(np.abs(angles0).max()))
        gains = _roundoff_gains(omega_o7)
        tolerance = _roundoff_tolerances(rho, gains)
        eps4 = pendulums.rk4_frequency_error(float(omega_o7[-1]), float(model.opt.timestep))
        run = RUN_PERIODS * 2 * np.pi / float(omega_o7[0])
        tolerance["mode-frequencies-exact"] = max(10 * eps4 + _REF, gains["mode-frequencies"] * rho)
        tolerance["mode-purity-exact"] = max(
            PURITY_FACTOR * eps4 * float(omega_o7[-1]) * run / np.sin(np.pi / (2 * n)) + _REF,
            gains["mode-purity"] * rho,
        )
        return {
            "_modes": modes,
            "_omega_O7": omega_o7,
            "_omega_O5": closed,
            "_angles0": angles0,
            "_scale": float(np.abs(angles0).max()),
            "_energy_scale": float(pendulums.row_energy(model, angles0[None], np.zeros((1, n)))[0]),
            "_tolerance": tolerance,
            "_roundoff_eps": pendulums.roundoff_per_eps(
                rho, {**gains, **{c.name: gains[c.name.removesuffix("-exact")] for c in EXACT_CHECKS}}
            ),
            "_roundoff_eps_rule": pendulums.ROUNDOFF_EPS_RULE,
            "omega-lowest": float(closed[0]),
            "omega-highest": float(closed[-1]),
            "mode-frequencies": 0.0,
            "mode-frequencies-closed-form": 0.0,
            "mode-purity": 0.0,
            "energy-drift": 0.0,
            **{c.name: 0.0 for c in EXACT_CHECKS},
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return 30.5 * 2 * np.pi / prediction["_omega_O7"][0]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        t, theta = traj.time, traj.qpos
        omegas, purity = _observe(t, theta, prediction["_modes"])
        ref = exact.motion(
            t, exact.SpringRow(**pendulums.spring_row(model)).acceleration, prediction["_modes"], prediction["_angles0"]
        )
        valid = ref.bound <= _REF  # else the reference did not converge (beyond the linear regime): the companions fail
        omegas_ref, purity_ref = _observe(t, ref.angles, prediction["_modes"]) if valid else (omegas, purity)
        ratio = omegas / omegas_ref - 1
        return {
            "omega-lowest": omegas[0],
            "omega-highest": omegas[-1],
            "mode-frequencies": float(np.abs(omegas / prediction["_omega_O7"] - 1).max()),
            "mode-frequencies-closed-form": float(np.abs(omegas / prediction["_omega_O5"] - 1).max()),
            "mode-purity": purity,
            "energy-drift": pendulums.energy_drift(
                pendulums.row_energy(model, traj.qpos, traj.qvel), prediction["_energy_scale"]
            ),
            "mode-frequencies-exact": float(ratio[np.argmax(np.abs(ratio))]) if valid else np.nan,
            "mode-purity-exact": purity - purity_ref if valid else np.nan,
        }


def _observe(t: np.ndarray, theta: np.ndarray, modes: osc.NormalModes) -> tuple[np.ndarray, float]:
    """Each mode's measured frequency (modal filter, zero crossings) and the mode-purity residual of a motion."""
    q = modes.coordinates(theta)
    omegas = np.array([pendulums.frequency(t, q[:, r]) for r in range(q.shape[1])])
    purity = max(pendulums.sinusoid_residual(t, q[:, r], omegas[r]) for r in range(q.shape[1]))
    return omegas, purity


@functools.cache
def _rate0(cls: type[PendulumChain]) -> float:
    return pendulums.default_rate(cls(), _highest)


def _roundoff_gains(omega: np.ndarray) -> dict[str, float]:
    """Each check's double-precision floor over rho (`pendulums.ROUNDOFF_DOMAIN_TEXT`): 0.5, the mode purity's
    `purity_gain`, the energy drift's 50."""
    factor = {"mode-purity": purity_gain(omega), "energy-drift": 50.0}
    return {c.name: factor.get(c.name, 0.5) for c in CHECKS if c not in EXACT_CHECKS}


def _roundoff_tolerances(rho: float, gains: dict[str, float]) -> dict[str, float]:
    """Each linear check's tolerance, or its double-precision floor ``gain x rho`` if larger (the companions' are set in
    `PendulumChain.predict`)."""
    return {c.name: max(c.tolerance, gains[c.name] * rho) for c in CHECKS if c.name in gains}


# Run length in periods of the lowest mode (`PendulumChain.duration`).
RUN_PERIODS = 30.5
# mode-purity-exact's tolerance over eps4 omega_highest t_run / sin(pi / 2N) (its reason).
PURITY_FACTOR = 0.01


def purity_gain(omega: np.ndarray) -> float:
    """The mode purity's round-off floor over rho: ``max(3, 0.5 min(omega_N / min(omega_{r+1} - omega_r),
    omega_N T))``, T the run's length.

    Round-off forces that are not a mode's own move energy between nearly degenerate neighbours, as the
    nonlinearity does (module docstring), by ~rho omega / spacing, and no more than the phase rho omega T the run
    gives them. Measured (census seed 3's draw, n = 2 .. 40, rho = 7e-7 .. 2e-3): purity = 0.5 .. 0.9 rho at n <=
    4, then 14 rho at n = 12 and 36 rho at n = 24 and 40 (omega T = 224 there): <= 0.16 rho min(omega/spacing,
    omega T); the factor 0.5 leaves 3x.
    """
    omega = np.asarray(omega, dtype=float)
    spacing = float(np.diff(omega).min())
    phase = float(omega[-1] / omega[0]) * 2 * np.pi * RUN_PERIODS
    ratio = min(float(omega[-1]) / spacing, phase) if spacing > 0 else phase
    return max(3.0, 0.5 * ratio)


def _purity_gain(p: Mapping[str, Any]) -> float:
    """The domain's gain from the requested parameters: the mode purity's round-off floor `purity_gain` over 10
    (its tolerance stays <= 0.1 inside the double-precision domain, rho x gain <= 1e-2), at least 1."""
    inertia = p["mass"] * p["length"] ** 2 + 1e-9
    w = osc.chain_frequencies(round(p["n"]), inertia, p["mass"] * p["g"] * p["length"], p["k"], p["d"])
    return max(1.0, purity_gain(w) / 10.0)


def _highest(p: Mapping[str, Any]) -> float:
    """The chain's highest mode frequency (rad/s) from the requested parameters (point bobs, O5)."""
    inertia = p["mass"] * p["length"] ** 2 + 1e-9
    mgl = p["mass"] * p["g"] * p["length"]
    return float(osc.chain_frequencies(round(p["n"]), inertia, mgl, p["k"], p["d"])[-1])


@functools.cache
def _amplitude_limit(n: int, mass: float, length: float, k: float, d: float, g: float) -> float:
    inertia = mass * length**2 + 1e-9
    mgl = mass * g * length
    modes = osc.chain_modes(n, inertia, mgl, k, d)
    a = 1e-3
    release = np.zeros(n)
    release[0] = a
    shift = np.abs(osc.amplitude_shifts(modes, osc.spring_chain_quartic(mgl, k, d), modes.coordinates(release)))
    per_a2 = shift / a**2
    w = modes.frequencies
    spacing = np.diff(w).min()
    tol = {c.name: c.tolerance for c in CHECKS}
    limits = [
        pendulums.spring_collapse_limit(d) ** 2,
        SHIFT_SHARE * tol["omega-lowest"] / per_a2.max(),
        # Modes that double precision cannot tell apart (kappa ~ 1e-16) exchange energy freely: no linear regime.
        SHIFT_SHARE * tol["mode-purity"] * spacing / (per_a2 * w).max() if spacing > 0 else 0.0,
    ]
    return float(np.sqrt(min(limits)))


def amplitude_limit(p: Mapping[str, Any]) -> float:
    """Largest |amplitude| (rad) of the linear theory's regime (module docstring): the first-order amplitude shift
    below `SHIFT_SHARE` of the frequency tolerance, the resonant leak shift x omega / (mode spacing) below that of
    the mode-purity tolerance, the attachment points s/10 apart."""
    return _amplitude_limit(round(p["n"]), *(float(p[x]) for x in ("mass", "length", "k", "d", "g")))


@functools.cache
def _chain_defaults(cls: type[PendulumChain]) -> Params:
    scenario = cls()
    spec = scenario.spec()
    scenario.param("n").target.apply(spec, spec.numeric("n").data[0])
    return scenario.read_params(spec.compile())


class PendulumChainEnv(PendulumEnv):
    """``rigidbench/PendulumChain-v0``: N spring-coupled pendulums, scored against the normal-mode solution.

    Description
        ``n`` identical point-bob pendulums hinged about the world y axis in a row along x (pivots 0.5 m apart),
        each neighbouring pair joined by a linear spring (stiffness ``k``) attached at ``d`` below the pivots,
        relaxed at equilibrium; the ends are free. With zero action the motion is a superposition of the N
        normal modes of docs/theory.md O5/O7: ``omega_r^2 = M g l / I_O + 4 k d^2 sin^2(r pi / 2N) / I_O``, shapes
        ``cos(r pi (j + 1/2) / N)``.

    Observation Space
        Box(-inf, inf, (2 n,)), float64:

        ============ ========================================= ====== ==================
        idx          quantity                                  unit   MuJoCo source
        ============ ========================================= ====== ==================
        0 ... n-1    angle of pendulum i from the vertical     rad    qpos of ``hinge<i>``
        n ... 2n-1   rate of pendulum i                        rad/s  qvel of ``hinge<i>``
        ============ ========================================= ====== ==================

        Pendulum 1 is at the -x end. A positive angle turns a bob towards -x. ``n`` is fixed for the env's
        lifetime (the observation space depends on it); ``reset`` refuses a different ``n``.

    Action Space
        Box(-1, 1, (1,)), float32, normalised: ``action_scale = 0.1`` N m times it is a torque on pendulum 1
        about its hinge, through ``qfrc_applied``;
        out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -max_i |th_i - th_i,theory(t)| / |amplitude|``, the theory being the linear normal-mode solution
        (O7); ``info["measured"]["angles"]`` and ``info["predicted"]["angles"]`` hold both (rad).
        Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        Pendulum 1 at rest at ``amplitude`` (rad), the others hanging at rest: every mode is excited.

    Episode End
        Truncated after 30.5 periods of the lowest mode; terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (end-released, strong-coupling), ``params`` (n, mass, length, k, d, amplitude, g), ``profile``,
        ``integrator``, ``timestep``, ``frame_skip`` (default 10: ten derived
        steps, 20 ms at the defaults), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = PendulumChain

    def theory(self, t: np.ndarray) -> np.ndarray:
        return self.prediction["_modes"].angles(t, self.prediction["_angles0"])

    def load(self, case: str, params: Mapping[str, Any]) -> None:
        if hasattr(self, "model"):  # the observation space is fixed at construction: so is n
            n = self.scenario.resolve(self.scenario.case(case), params)["n"]
            if n != self.model.njnt:
                raise ValueError(
                    f"parameter 'n' = {n:g} cannot differ from the env's {self.model.njnt} pendulums (the "
                    "observation space depends on it); make a new env instead"
                )
        super().load(case, params)
