"""Chain of N identical pendulums with nearest-neighbour springs: the MuJoCo side, and its gymnasium env.

Theory: THEORY.md O5 (``omega_r^2 = g/l + 4 kappa sin^2(r pi / 2N)``, ``kappa = k d^2 / (m l^2)``, shapes
``cos(r pi (j + 1/2) / N)``) and O7 (``det(V - omega^2 T) = 0``, Wilcox Part II section 12.2, eqs 12.15-12.26),
implemented in `rigidbench.analytic.oscillations`. Model: ``models/pendulum_chain.xml``, a one-pendulum template
from which `rigidbench.envs.pendulums.ChainSize` builds the chain through `mujoco.MjSpec`.

The number of modes depends on ``n``: the lowest and highest modes get a row each with their frequencies, and
every mode is covered by rows holding the largest relative error over all of them (NaN, a failure, if any mode's
frequency could not be measured). The prediction holds every mode (``prediction["_omega_O7"]``, ``["_omega_O5"]``).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from rigidbench.analytic import oscillations as osc
from rigidbench.envs import pendulums
from rigidbench.envs.pendulums import BobMass, ChainSize, PendulumEnv, RodLength, SpringHeight, SpringStiffness
from rigidbench.params import Gravity, Numeric, Param, Range, positive
from rigidbench.scenario import Case, Check, Params, Scenario
from rigidbench.simulate import Trajectory

MAX_PENDULUMS = 40

_FREQ = (
    "RK4 at dt = 2 ms: relative frequency error (omega dt)^4/120 <~ 5e-11; normal coordinates from the O7 mode "
    "vectors (modal filter), crossings cubic-interpolated over >= 30 periods; one pendulum released at 1 mrad: "
    "nonlinear shifts <~ 1e-7 (O1's a^2/16 and the spring geometry, see coupled_pendulums)"
)
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
        "other modes' amplitudes",
        "O5: th_j proportional to cos(r pi (j + 1/2) / N); O7: normal coordinates oscillate alone (Wilcox eq. 12.26)",
    ),
    Check(
        "energy-drift",
        "1",
        1e-8,
        "abs",
        pendulums.SPRING_CHAIN_ENERGY_REASON,
        "O5: " + pendulums.SPRING_CHAIN_ENERGY,
    ),
)
_ALL = (
    "omega-lowest",
    "omega-highest",
    "mode-frequencies",
    "mode-frequencies-closed-form",
    "mode-purity",
    "energy-drift",
)


class PendulumChain(Scenario):
    """N identical pendulums in a row, neighbours coupled by springs, free ends: every normal mode (THEORY.md
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
        Param("mass", "kg", "mass m of each point bob", positive(1e3), BobMass()),
        Param("length", "m", "distance l from each pivot to its bob", positive(100.0), RodLength()),
        Param(
            "k",
            "N/m",
            "stiffness of each coupling spring (linear, relaxed at equilibrium)",
            positive(1e4),
            SpringStiffness(),
        ),
        Param(
            "d",
            "m",
            "distance below the pivots at which the springs are attached, 0 < d <= length",
            positive(100.0),
            SpringHeight(),
        ),
        Param(
            "amplitude",
            "rad",
            "release angle of pendulum 1 (the others hang at rest)",
            Range(-1.0, 1.0),
            Numeric("amplitude"),
        ),
        Param("g", "m/s^2", "gravitational acceleration (along -z)", positive(1e3), Gravity()),
    )
    cases = (
        Case("end-released", "pendulum 1 released, the others at rest: every mode excited", {}, _ALL),
        Case(
            "strong-coupling",
            "k = 10 N/m (k d^2 / m g l = 0.25): the mode frequencies spread over a factor 1.7",
            {"k": 10.0},
            _ALL,
        ),
    )
    checks = CHECKS

    def defaults(self) -> Params:
        """Defaults from the model file, with the chain built at its default size (the raw file is the template)."""
        return _chain_defaults(type(self))

    def validate(self, params: Mapping[str, Any]) -> None:
        if params["d"] > params["length"]:
            raise ValueError(
                f"parameter 'd' = {params['d']:g} m is outside the valid range (0, length = {params['length']:g}] m: "
                "the springs are attached to the rods, between the pivots and the bobs"
            )
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
        modes = osc.normal_modes(*osc.spring_chain_matrices(n, p.inertia_pivot, mgl, k, sp.height))
        closed = osc.chain_frequencies(n, p.inertia_pivot, mgl, k, sp.height)
        angles0 = data.qpos.copy()
        return {
            "_modes": modes,
            "_omega_O7": modes.frequencies,
            "_omega_O5": closed,
            "_angles0": angles0,
            "_scale": float(np.abs(angles0).max()),
            "_energy_scale": float(pendulums.row_energy(model, angles0[None], np.zeros((1, n)))[0]),
            "omega-lowest": float(closed[0]),
            "omega-highest": float(closed[-1]),
            "mode-frequencies": 0.0,
            "mode-frequencies-closed-form": 0.0,
            "mode-purity": 0.0,
            "energy-drift": 0.0,
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return 30.5 * 2 * np.pi / prediction["_omega_O7"][0]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        t, theta = traj.time, traj.qpos
        modes: osc.NormalModes = prediction["_modes"]
        q = modes.coordinates(theta)
        omegas = np.array([pendulums.frequency(t, q[:, r]) for r in range(q.shape[1])])
        purity = max(pendulums.sinusoid_residual(t, q[:, r], omegas[r]) for r in range(q.shape[1]))
        return {
            "omega-lowest": omegas[0],
            "omega-highest": omegas[-1],
            "mode-frequencies": float(np.abs(omegas / prediction["_omega_O7"] - 1).max()),
            "mode-frequencies-closed-form": float(np.abs(omegas / prediction["_omega_O5"] - 1).max()),
            "mode-purity": purity,
            "energy-drift": pendulums.energy_drift(
                pendulums.row_energy(model, traj.qpos, traj.qvel), prediction["_energy_scale"]
            ),
        }


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
        normal modes of THEORY.md O5/O7: ``omega_r^2 = M g l / I_O + 4 k d^2 sin^2(r pi / 2N) / I_O``, shapes
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
        Box(-0.1, 0.1, (1,)), float64: torque on pendulum 1 about its hinge (N m), through ``qfrc_applied``;
        out-of-range actions are clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -max_i |th_i - th_i,theory(t)| / |amplitude|``, the theory being the linear normal-mode solution
        (O7); ``info["measured"]["angles"]`` and ``info["predicted"]["angles"]`` hold both (rad).

    Starting State
        Pendulum 1 at rest at ``amplitude`` (rad), the others hanging at rest: every mode is excited.

    Episode End
        Truncated after 30.5 periods of the lowest mode; terminated on divergence.

    Arguments
        ``case`` (end-released, strong-coupling), ``params`` (n, mass, length, k, d, amplitude, g), ``profile``,
        ``integrator``, ``timestep``, ``frame_skip`` (default 10, i.e. 20 ms), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = PendulumChain

    def _theory(self, t: np.ndarray) -> np.ndarray:
        return self.prediction["_modes"].angles(t, self.prediction["_angles0"])

    def _load(self, case: str, params: Mapping[str, Any]) -> None:
        if hasattr(self, "model"):  # the observation space is fixed at construction: so is n
            n = self.scenario.resolve(self.scenario.case(case), params)["n"]
            if n != self.model.njnt:
                raise ValueError(
                    f"parameter 'n' = {n:g} cannot differ from the env's {self.model.njnt} pendulums (the "
                    "observation space depends on it); make a new env instead"
                )
        super()._load(case, params)
