"""Two identical pendulums coupled by a spring: the MuJoCo side, and its gymnasium env.

Theory: THEORY.md O3 (normal modes, Wilcox Part II sections 12.1-12.3, eqs 12.10-12.24), O4 (beats and energy
transfer, section 12.4) and O7 (the eigenproblem, eqs 12.15-12.26), implemented in
`rigidbench.analytic.oscillations`. Model: ``models/coupled_pendulums.xml``.

Amplitude: the theory is linear. 1 mrad keeps the nonlinear frequency shifts well inside the tolerances: the
in-phase mode never stretches the spring and is exactly a lone pendulum, shifted by -a^2/16 = -6e-8 (O1); the
anti-phase mode (th1 = -th2 = th) stretches the spring by 2 d sin(th), so its potential is ``(m g l + 2 k d^2)
th^2 - (m g l / 12 + 2 k d^2 / 3) th^4``, and Lindstedt's method gives ``d(omega_a)/omega_a = -(3/8) a^2 (m g l/6
+ 4 k d^2/3) / (m g l + 2 k d^2)``: -2.8e-7 at a = 1 mrad in the strong-coupling case (k = 20 N/m), smaller in
the others. The spring is not exactly linear in the angles: its length is
``L^2 = (s + d (sin th1 - sin th2))^2 + d^2 (cos th1 - cos th2)^2`` (s = 0.5 m, the pivot spacing). The sine
terms are the th^3 corrections above; the second term, the spring's tilt off the horizontal, changes L only at
O(d^2 a^4 / s) and the spring energy at O(k d^3 a^5 / s), a frequency shift of order a^3 d / s ~ 1e-9: negligible.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench.analytic import oscillations as osc
from rigidbench.envs import pendulums
from rigidbench.envs.pendulums import BobMass, PendulumEnv, RodLength, SpringHeight, SpringStiffness
from rigidbench.params import Gravity, Numeric, Param, Range, positive
from rigidbench.scenario import Case, Check, Scenario
from rigidbench.simulate import Trajectory

_FREQ = (
    "RK4 at dt = 2 ms: relative frequency error (omega dt)^4/120 <~ 5e-11; normal coordinates from the O7 mode "
    "vectors, crossings cubic-interpolated over >= 30 periods; nonlinear shift <= (3/8) a^2 (m g l/6 + 4 k d^2/3)/"
    "(m g l + 2 k d^2) = 2.8e-7 at a = 1 mrad (module docstring)"
)
_SHAPE = (
    "least-squares fit of th1, th2 at the two measured frequencies over the record; nonlinear terms O(a^2) ~ 1e-6 "
    "of the amplitude leak into the fit, 1e-5 leaves a decade"
)
_WAVE = (
    "the linear solution's phase error grows as the nonlinear shift (<~ 1e-7 at 1 mrad, module docstring) times "
    "omega t (<~ 1.3e3 rad over 2.5 T_x in the weak case): <~ 1.3e-4 of the amplitude; RK4 adds ~1e-9"
)
CHECKS = (
    Check("omega-in-phase", "rad/s", 1e-6, "rel", _FREQ, "O3: omega_s^2 = M g l / I_O (= g/l for a point bob)"),
    Check(
        "omega-anti-phase",
        "rad/s",
        1e-6,
        "rel",
        _FREQ,
        "O3: omega_a^2 = omega_s^2 + 2 k d^2 / I_O (Wilcox eqs 12.10-12.24)",
    ),
    Check("shape-in-phase", "1", 1e-5, "abs", _SHAPE, "O3/O7: th2/th1 = +1 in the in-phase mode"),
    Check("shape-anti-phase", "1", 1e-5, "abs", _SHAPE, "O3/O7: th2/th1 = -1 in the anti-phase mode"),
    Check(
        "transfer-time",
        "s",
        1e-4,
        "rel",
        "vertex of a parabola through the peaks of |th2| within 2 % of the envelope maximum: applied to the exact "
        "O4 signal it errs by <= 7e-6 for omega_b/omega0 <= 0.03 (tests); the nonlinear shift moves omega_a - "
        "omega_s by <~ 1e-5 of itself",
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
        pendulums.SPRING_CHAIN_ENERGY_REASON,
        "O3: " + pendulums.SPRING_CHAIN_ENERGY,
    ),
)
_BEATS = (
    "omega-in-phase",
    "omega-anti-phase",
    "shape-in-phase",
    "shape-anti-phase",
    "transfer-time",
    "beat-waveform",
    "energy-drift",
)
_STRONG = tuple(c for c in _BEATS if c != "transfer-time")  # too few carrier peaks per beat to locate T_x
_MODES = ("in-phase", "anti-phase")


class CoupledPendulums(Scenario):
    """Two identical pendulums and a spring at d below the pivots: normal modes, beats, energy transfer
    (THEORY.md O3, O4, O7)."""

    slug = "coupled-pendulums"
    title = "Two identical pendulums coupled by a spring (normal modes and beats)"
    env_id = "rigidbench/CoupledPendulums-v0"
    params = (
        Param("mass", "kg", "mass m of each point bob", positive(1e3), BobMass()),
        Param("length", "m", "distance l from each pivot to its bob", positive(100.0), RodLength()),
        Param(
            "k",
            "N/m",
            "stiffness of the coupling spring (linear, relaxed at equilibrium)",
            positive(1e4),
            SpringStiffness(),
        ),
        Param(
            "d",
            "m",
            "distance below the pivots at which the spring is attached, 0 < d <= length",
            positive(100.0),
            SpringHeight(),
        ),
        Param("amplitude1", "rad", "release angle of pendulum 1 (at rest)", Range(-1.0, 1.0), Numeric("amplitude1")),
        Param("amplitude2", "rad", "release angle of pendulum 2 (at rest)", Range(-1.0, 1.0), Numeric("amplitude2")),
        Param("g", "m/s^2", "gravitational acceleration (along -z)", positive(1e3), Gravity()),
    )
    cases = (
        Case(
            "in-phase",
            "both released at the same angle: the in-phase mode alone",
            {"amplitude2": lambda p: p["amplitude1"]},
            ("omega-in-phase", "shape-in-phase", "energy-drift"),
        ),
        Case(
            "anti-phase",
            "released at opposite angles: the anti-phase mode alone",
            {"amplitude2": lambda p: -p["amplitude1"]},
            ("omega-anti-phase", "shape-anti-phase", "energy-drift"),
        ),
        Case(
            "beats",
            "pendulum 1 released, pendulum 2 at rest: beats (k d^2 / m g l = 0.025)",
            {"amplitude2": 0.0},
            _BEATS,
        ),
        Case(
            "weak-coupling",
            "beats with k = 0.25 N/m (k d^2 / m g l = 0.0064): slow, complete energy transfer",
            {"amplitude2": 0.0, "k": 0.25},
            _BEATS,
        ),
        Case(
            "strong-coupling",
            "pendulum 1 released with k = 20 N/m (k d^2 / m g l = 0.5): omega_a = 1.42 omega_s",
            {"amplitude2": 0.0, "k": 20.0},
            _STRONG,
        ),
    )
    checks = CHECKS

    def validate(self, params: Mapping[str, Any]) -> None:
        if params["d"] > params["length"]:
            raise ValueError(
                f"parameter 'd' = {params['d']:g} m is outside the valid range (0, length = {params['length']:g}] m: "
                "the spring is attached to the rod, between the pivot and the bob"
            )
        if params["amplitude1"] == 0 and params["amplitude2"] == 0:
            raise ValueError("parameters 'amplitude1' and 'amplitude2' are both 0: nothing moves (valid: not both 0)")

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        data.qpos[:] = [params["amplitude1"], params["amplitude2"]]
        data.qvel[:] = 0.0

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        p1, p2 = pendulums.pendulums(model)
        sp = pendulums.springs(model)
        g = pendulums.gravity(model)
        mgl = p1.mass * g * p1.length
        k = float(sp.stiffness[0])
        modes = osc.normal_modes(*osc.spring_chain_matrices(2, p1.inertia_pivot, mgl, k, sp.height))
        omega_s, omega_a = osc.coupled_frequencies(p1.inertia_pivot, mgl, k, sp.height)
        angles0 = data.qpos.copy()
        beats = osc.Beats(float(angles0[0]), omega_s, omega_a)
        excited = np.abs(modes.coordinates(angles0)) > 1e-9 * np.abs(angles0).max()
        periods = 2 * np.pi / np.array([omega_s, omega_a])
        duration = 30.5 * periods[excited].max()
        if excited.all():
            duration = max(duration, 2.5 * beats.transfer_time)
        ratios = modes.shape_ratios()[1]
        return {
            "_modes": modes,
            "_excited": excited,
            "_angles0": angles0,
            "_beats": beats,
            "_duration": duration,
            "_scale": float(np.abs(angles0).max()),
            "_energy_scale": float(pendulums.row_energy(model, angles0[None], np.zeros((1, 2)))[0]),
            "omega-in-phase": omega_s,
            "omega-anti-phase": omega_a,
            "shape-in-phase": float(ratios[0]),
            "shape-anti-phase": float(ratios[1]),
            "transfer-time": beats.transfer_time,
            "beat-waveform": 0.0,
            "energy-drift": 0.0,
        }

    def check_model(self, model: mujoco.MjModel) -> None:
        p1, p2 = pendulums.pendulums(model)
        if (p1.mass, p1.length, p1.inertia_cm) != (p2.mass, p2.length, p2.inertia_cm):
            raise ValueError(f"the two pendulums differ ({p1} vs {p2}); O3 needs identical pendulums")

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return prediction["_duration"]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        t, theta = traj.time, traj.qpos
        modes: osc.NormalModes = prediction["_modes"]
        excited = prediction["_excited"]
        q = modes.coordinates(theta)
        omegas = np.array([pendulums.frequency(t, q[:, r]) if excited[r] else np.nan for r in range(2)])
        fitted = [r for r in range(2) if excited[r]]
        z = pendulums.modal_amplitudes(t, theta, omegas[fitted])
        shapes = {r: pendulums.mode_shape(z[:, i])[1] for i, r in enumerate(fitted)}
        linear = modes.angles(t, prediction["_angles0"])
        return {
            "omega-in-phase": omegas[0],
            "omega-anti-phase": omegas[1],
            "shape-in-phase": shapes.get(0, np.nan),
            "shape-anti-phase": shapes.get(1, np.nan),
            "transfer-time": transfer_time(t, theta[:, 1], traj.qvel[:, 1], before=2 * prediction["transfer-time"]),
            "beat-waveform": float(np.abs(theta - linear).max() / prediction["_scale"]),
            "energy-drift": pendulums.energy_drift(
                pendulums.row_energy(model, traj.qpos, traj.qvel), prediction["_energy_scale"]
            ),
        }


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
        action the motion is THEORY.md O3/O4: a superposition of the in-phase mode (omega_s^2 = M g l / I_O)
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
        Box(-0.1, 0.1, (1,)), float64: torque on pendulum 1 about its hinge (N m), through ``qfrc_applied``;
        out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -max_i |th_i - th_i,theory(t)| / max_i |th_i(0)|``, the theory being the linear normal-mode
        solution (O4/O7); ``info["measured"]["angles"]`` and ``info["predicted"]["angles"]`` hold both (rad).

    Starting State
        At rest at (``amplitude1``, ``amplitude2``) (rad).

    Episode End
        Truncated after 30.5 periods of the slowest excited mode, or 2.5 T_x if both modes are excited;
        terminated on divergence.

    Arguments
        ``case`` (in-phase, anti-phase, beats, weak-coupling, strong-coupling), ``params`` (mass, length, k, d,
        amplitude1, amplitude2, g), ``profile``, ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e.
        10 ms), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = CoupledPendulums

    def _theory(self, t: np.ndarray) -> np.ndarray:
        return self.prediction["_modes"].angles(t, self.prediction["_angles0"])
