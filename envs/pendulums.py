"""The physics layer shared by the pendulum family: where the numbers live in the MJCF, what is measured.

Model conventions (``models/pendulum.xml``, ``coupled_pendulums.xml``, ``pendulum_chain.xml``,
``double_pendulum.xml``): pendulum i is the body ``pendulum<i>`` (``pendulum`` for a lone one), hinged about
the world y axis at its body origin by the joint ``hinge<i>``; its bob is a point mass (explicit ``<inertial>``)
at ``(0, 0, -l)``, marked by the site ``bob<i>``; a spring attachment is the site ``spring<i>`` at ``(0, 0, -d)``.
A positive angle turns the bob towards -x. Springs are spatial tendons of the default class ``spring``, with
``springlength="-1"``: MuJoCo takes the rest length from the reference configuration, so every spring is
relaxed at equilibrium (docs/theory.md O3). Visual geoms carry no mass (house rule 7).

MuJoCo refuses a moving body with zero inertia, so each bob carries ``diaginertia`` 1e-9 kg m^2, a part in 1e9
of ``m l^2`` at the defaults. It is not neglected: every prediction takes the pivot moment ``I_O = I_yy + m
l^2`` read back from the compiled model (docs/theory.md O2).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import signals
from rigidbench.contract import Derived
from rigidbench.envs.base import ScenarioEnv
from rigidbench.params import Value

# The energy check shared by the spring-coupled pendulums (coupled pair and chain): RK4 at their 2 ms step.
SPRING_CHAIN_ENERGY_REASON = (
    "RK4 is not symplectic: relative drift ~ T (omega dt)^6 / (72 dt) <~ 2e-10 over the run; 1e-8 leaves 1.5 decades"
)
# Pivot spacing s (m) of the spring-coupled models (``coupled_pendulums.xml``: pivots at x = -+0.25 m;
# ``pendulum_chain.xml``: its ``spacing``): the springs' rest length.
PIVOT_SPACING = 0.5
# Double precision. MuJoCo computes gravity's torque and the springs' lengths from world positions: a lever arm
# l sin th, or a stretch d sin th, measured against pivots up to X from the origin carries an absolute error ~ eps X,
# so the restoring torque has a relative error rho = eps X (M g + k d) / ((M g l + k d^2) |a|) (a = the largest
# release angle). Measured (census draws at amplitudes 1e-14 .. 1e-7 rad): energy drift 4 .. 5.4 rho, frequencies
# 1e-3 .. 0.04 rho, mode purity 0.01 .. 0.14 rho. At the defaults rho ~ 1e-13 and no check feels it; each check's
# tolerance is its own, or this floor times a factor ~10 above the measured ratio if larger.
ROUNDOFF = (
    "; floor {factor} rho if larger, rho = eps X (M g + k d) / ((M g l + k d^2) |a|): the restoring torque's relative "
    "double-precision error, MuJoCo's lever arms and spring lengths being differences of world positions up to X from "
    "the origin (measured {measured}; rho ~ 1e-13 at the defaults)"
)


ROUNDOFF_MAX = 1e-2
ROUNDOFF_DOMAIN_TEXT = (
    "rho = eps X (M g + k d) / ((M g l + k d^2) |a|) <= 1e-2: the restoring torque, computed by MuJoCo from world "
    "positions up to X from the origin, is resolved in double precision (at rho ~ 1 the release is below the "
    "rounding of the model's coordinates and no oscillation can be measured; below 1e-2 the checks' tolerances "
    "include a floor ~ rho, their reasons say how)"
)


def roundoff_outside(params: Mapping[str, Any], extent: float, amplitude: float, gain: float = 1.0) -> str | None:
    """The double-precision domain's test (`ROUNDOFF_DOMAIN_TEXT`) from requested parameters: None inside, else a
    phrase naming the parameters. `gain` (>= 1) multiplies rho where a check amplifies the round-off (the chain's
    nearly degenerate modes)."""
    m, g, length, k, d = (float(params[x]) for x in ("mass", "g", "length", "k", "d"))
    rho = np.finfo(float).eps * extent * (m * g + k * d) / ((m * g * length + k * d * d) * abs(amplitude))
    if rho * gain <= ROUNDOFF_MAX:
        return None
    amplified = f" x {gain:.3g}" if gain > 1 else ""
    return (
        f"amplitude {amplitude:g} rad with length = {length:g} m, d = {d:g} m, pivots up to {extent:g} m out "
        f"(rho = {rho:.2g}{amplified})"
    )


def roundoff(model: mujoco.MjModel, amplitude: float) -> float:
    """rho (see `ROUNDOFF`): the relative double-precision error of the restoring torque of side-by-side pendulums,
    released at `amplitude` (rad, the largest angle)."""
    pend = pendulums(model)
    p, g = pend[0], gravity(model)
    sp = springs(model)
    k = float(sp.stiffness.max()) if len(sp.stiffness) else 0.0
    d = sp.height if len(sp.stiffness) else 0.0
    extent = max(abs(q.pivot_x) for q in pend)
    eps = np.finfo(float).eps
    return float(eps * extent * (p.mass * g + k * d) / ((p.mass * g * p.length + k * d * d) * abs(amplitude)))


ROUNDOFF_EPS_RULE = (
    "floor = gain x rho, rho = eps X (M g + k d) / ((M g l + k d^2) |a|) the restoring torque's relative round-off "
    "from world positions up to X out, proportional to the precision's eps; the gains are the float64 floors'"
)


def roundoff_per_eps(rho: float, gains: Mapping[str, float]) -> dict[str, float]:
    """The floors ``gain x rho`` (`ROUNDOFF_DOMAIN_TEXT`) in units of the precision's eps.

    rho is eps times the torque's amplification X (M g + k d) / ((M g l + k d^2) |a|), the same mechanism in any
    precision: a float32 engine's floor is this times float32's eps (`Scenario._roundoff_check`), 5.4e8 times the
    float64 floor the tolerances carry. Infinite gains (a check that does not apply) are left out.
    """
    eps = float(np.finfo(float).eps)
    return {name: g * rho / eps for name, g in gains.items() if math.isfinite(g * rho)}


def spring_collapse_limit(height: float) -> float:
    """Largest release angle (rad) at which two neighbouring attachment points, d below pivots s apart, stay at
    least s/10 apart when the pendulums swing against each other (2 d sin a <= 0.9 s)."""
    return float(np.arcsin(min(1.0, 0.45 * PIVOT_SPACING / height)))


SPRING_CHAIN_ENERGY = (
    "E = sum 1/2 I_O th'^2 + m g l (1 - cos th) + 1/2 k (L - L0)^2 conserved (relative to its initial value)"
)

# The reference step of the model files (s): the derived timestep equals it at each model's defaults.
REFERENCE_TIMESTEP = 2e-3


def timestep_for(omega_max: float, omega_default: float, what: str) -> Derived:
    """The reference timestep for a fastest angular rate `omega_max` (rad/s): ``dt = c / omega_max`` with ``c =
    2 ms x omega_default``, `omega_default` being the smallest fastest rate of the scenario's default cases
    (`default_rate`): every default case is integrated at a step no longer than the model file's 2 ms, the slowest
    at exactly 2 ms, and every other set of parameters at the same ``omega dt``.

    RK4's relative frequency error is (omega dt)^4 / 120 and its relative energy drift per period ~ 2 pi (omega
    dt)^5 / 72: both then stay what they are in the default cases, whatever the time scales. `what` names
    omega_max.
    """
    c = REFERENCE_TIMESTEP * omega_default
    return Derived(
        REFERENCE_TIMESTEP * (omega_default / omega_max),
        f"dt = {c:.4g} / omega_max (omega_max dt = {c:.3g}, as in the default cases, where dt <= 2 ms: RK4 frequency "
        f"error (omega dt)^4/120 = {c**4 / 120:.1e}); omega_max = {what} = {omega_max:.6g} rad/s",
    )


def default_rate(scenario, rate) -> float:
    """The smallest of `rate(params)` (rad/s) over the scenario's cases at their default parameters."""
    return min(rate(scenario.resolve(case)) for case in scenario.cases)


BODY, HINGE, BOB_SITE, SPRING_SITE, ROD, BALL = "pendulum", "hinge", "bob", "spring", "rod", "ball"
_QPOS_QVEL = mujoco.mjtState.mjSTATE_QPOS | mujoco.mjtState.mjSTATE_QVEL


def _suffix(body_name: str) -> str:
    return body_name[len(BODY) :]


def _pendulum_bodies(spec: mujoco.MjSpec, bodies: tuple[str, ...] | None) -> list[mujoco.MjsBody]:
    if bodies is not None:
        return [spec.body(b) for b in bodies]
    return [b for b in spec.bodies if b.name.startswith(BODY)]


# ---- parameter targets ---------------------------------------------------------------------------------
# Each writes a number into every element it concerns (all pendulums unless `bodies` names some) and reads it
# back from the first, so that what the prediction uses is what MuJoCo compiled (house rule 3).


@dataclass(frozen=True)
class BobMass:
    """Mass (kg) of the point bob(s)."""

    bodies: tuple[str, ...] | None = None

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        for body in _pendulum_bodies(spec, self.bodies):
            body.mass = float(value)

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.body(self.bodies[0] if self.bodies else _first_pendulum(model)).mass[0])


@dataclass(frozen=True)
class RodLength:
    """Pivot-to-bob distance l (m): moves the bob's mass, its site and visual geoms, and any child pendulum."""

    bodies: tuple[str, ...] | None = None

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        length = float(value)
        for body in _pendulum_bodies(spec, self.bodies):
            s = _suffix(body.name)
            body.ipos = [0.0, 0.0, -length]
            for site in body.sites:
                if site.name == BOB_SITE + s:
                    site.pos = [0.0, 0.0, -length]
            for geom in body.geoms:
                if geom.name == ROD + s:
                    geom.fromto = [0.0, 0.0, 0.0, 0.0, 0.0, -length]
                elif geom.name == BALL + s:
                    geom.pos = [0.0, 0.0, -length]
            for child in body.bodies:
                child.pos = [0.0, 0.0, -length]

    def read(self, model: mujoco.MjModel) -> Value:
        return float(-model.body(self.bodies[0] if self.bodies else _first_pendulum(model)).ipos[2])


@dataclass(frozen=True)
class SpringHeight:
    """Distance d (m) below the pivots at which the springs are attached (every ``spring*`` site)."""

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        for site in spec.sites:
            if site.name.startswith(SPRING_SITE):
                site.pos = [0.0, 0.0, -float(value)]

    def read(self, model: mujoco.MjModel) -> Value:
        names = [model.site(i).name for i in range(model.nsite)]
        return float(-model.site_pos[next(i for i, n in enumerate(names) if n.startswith(SPRING_SITE)), 2])


@dataclass(frozen=True)
class SpringStiffness:
    """Spring constant k (N/m) of every tendon and of the ``spring`` default class (for tendons added later)."""

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        default = spec.find_default("spring").tendon
        # MuJoCo 4 stores a polynomial stiffness (k, k2, k3): a linear spring keeps the higher orders at 0.
        k = [float(value)] + [0.0] * (np.size(default.stiffness) - 1) if np.ndim(default.stiffness) else float(value)
        default.stiffness = k
        for tendon in spec.tendons:
            tendon.stiffness = k

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.tendon_stiffness[0])


@dataclass(frozen=True)
class ChainSize:
    """Number n of pendulums in a row: builds the chain through `MjSpec` from the one-pendulum template.

    The model file holds a single pendulum body ``pendulum`` (joint ``hinge``, sites ``bob`` and ``spring``) and
    the default class ``spring``. `apply` attaches n copies of it, ``pendulum1`` ... ``pendulum<n>``, spaced
    ``spacing`` (a ``<numeric>``, m) apart along x and centred on the origin, deletes the template, and joins each
    neighbouring pair's ``spring`` sites by a spatial tendon ``coupling<i>`` of class ``spring``. It must be
    applied before the other targets of the family (first in ``params``), which then set every copy.
    """

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        n = round(float(value))
        template = spec.body(BODY)
        spacing = float(spec.numeric("spacing").data[0])
        spec.copy_during_attach = True  # attach copies of the template, not the template itself (write-only flag)
        for i in range(1, n + 1):
            frame = spec.worldbody.add_frame(pos=[(i - 1 - (n - 1) / 2) * spacing, 0.0, 0.0])
            frame.attach_body(template, "", str(i))
        spec.delete(template)
        for i in range(1, n):
            tendon = spec.add_tendon(default=spec.find_default("spring"), name=f"coupling{i}")
            tendon.wrap_site(f"{SPRING_SITE}{i}")
            tendon.wrap_site(f"{SPRING_SITE}{i + 1}")
        width = n * spacing + 0.5  # the view (fovy 45 deg, square) is 0.83 x the camera's distance wide
        spec.camera("side").pos = [0.0, -max(2.8, 1.3 * width), spec.camera("side").pos[2]]
        spec.geom("backdrop").size = [max(4.0, width), max(2.0, 0.6 * width), 0.01]

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.njnt)


def _first_pendulum(model: mujoco.MjModel) -> str:
    return next(model.body(i).name for i in range(model.nbody) if model.body(i).name.startswith(BODY))


# ---- the physics layer -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Pendulum:
    """One compiled pendulum: the numbers a prediction needs, read back from the model."""

    mass: float
    length: float
    inertia_cm: float  # about the bob's own y axis (kg m^2)
    pivot_x: float  # world x of the hinge (m), top-level pendulums

    @property
    def inertia_pivot(self) -> float:
        """I_O = I_cm + m l^2 (kg m^2), docs/theory.md O2 / R4."""
        return self.inertia_cm + self.mass * self.length**2


def pendulums(model: mujoco.MjModel) -> list[Pendulum]:
    """Every hinged body of `model`, in joint order."""
    out = []
    for j in range(model.njnt):
        b = model.body(model.jnt_bodyid[j])
        out.append(Pendulum(float(b.mass[0]), float(-b.ipos[2]), float(b.inertia[1]), float(b.pos[0])))
    return out


def gravity(model: mujoco.MjModel) -> float:
    return float(-model.opt.gravity[2])


@dataclass(frozen=True)
class Springs:
    """The spring tendons: stiffness k (N/m), rest length (m), and which pendulums (joint indices) each joins."""

    stiffness: np.ndarray
    rest_length: np.ndarray
    pairs: list[tuple[int, int]]
    height: float  # attachment distance d below the pivots (m)


def springs(model: mujoco.MjModel) -> Springs:
    """Read the spring tendons back: each wraps the ``spring`` sites of two pendulums."""
    pairs = []
    for t in range(model.ntendon):
        adr = model.tendon_adr[t]
        sites = model.wrap_objid[adr : adr + 2]
        pairs.append(tuple(int(model.body_dofadr[model.site_bodyid[s]]) for s in sites))
    heights = {float(-model.site_pos[model.wrap_objid[model.tendon_adr[t]], 2]) for t in range(model.ntendon)}
    return Springs(
        stiffness=model.tendon_stiffness.copy(),
        rest_length=model.tendon_lengthspring[:, 0].copy(),
        pairs=pairs,
        height=heights.pop() if heights else float("nan"),
    )


def spring_row(model: mujoco.MjModel) -> dict[str, Any]:
    """The side-by-side pendulums and springs of `model` as the exact equations of motion take them: the keyword
    arguments of `rigidbench.analytic.oscillations_exact.SpringRow` (not imported here: the simple pendulum's reading
    stays short), every number read back from the compiled model.

    Raises
    ------
    ValueError
        If the model has a force the exact equations leave out: joint or tendon damping, armature, friction loss, or
        a nonlinear spring (MuJoCo's polynomial stiffness).
    """
    extra = {
        "joint damping": model.dof_damping,
        "joint armature": model.dof_armature,
        "joint friction loss": model.dof_frictionloss,
        "tendon damping": model.tendon_damping,
        "tendon armature": model.tendon_armature,
        "tendon stiffness polynomial": model.tendon_stiffnesspoly,
    }
    present = [name for name, value in extra.items() if np.any(np.asarray(value) != 0)]
    if present:
        raise ValueError(f"the exact equations of motion have no {', '.join(present)}; the model has some")
    pend = pendulums(model)
    g = gravity(model)
    sp = springs(model)
    return {
        "inertia_pivot": np.array([p.inertia_pivot for p in pend]),
        "mgl": np.array([p.mass * g * p.length for p in pend]),
        "pivot_x": np.array([p.pivot_x for p in pend]),
        "height": sp.height,
        "pairs": sp.pairs,
        "stiffness": sp.stiffness,
        "rest_length": sp.rest_length,
    }


def rk4_frequency_error(omega: float, timestep: float) -> float:
    """RK4's relative frequency error (omega dt)^4 / 120 for a mode of `omega` (rad/s) at `timestep` (s): the phase
    of RK4's amplification factor over a step, omega dt - (omega dt)^5 / 120 + ... (Hairer, Norsett & Wanner,
    *Solving ODEs I*, section II.2, stability function of RK4)."""
    return float((omega * timestep) ** 4 / 120)


def row_energy(model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
    """Total energy (J) of side-by-side pendulums with springs, from the full nonlinear geometry.

    ``sum 1/2 I_O th'^2 + sum m g l (1 - cos th) + sum 1/2 k (L - L0)^2`` (1 - cos th written 2 sin^2(th/2):
    no cancellation at milliradian amplitudes), with L the distance between the
    attachment points ``(x_i - d sin th_i, -d cos th_i)`` (not MuJoCo's energy: computed independently).
    """
    pend = pendulums(model)
    g = gravity(model)
    energy = sum(
        0.5 * p.inertia_pivot * qvel[:, i] ** 2 + 2 * p.mass * g * p.length * np.sin(0.5 * qpos[:, i]) ** 2
        for i, p in enumerate(pend)
    )
    sp = springs(model)
    for (i, j), k, rest in zip(sp.pairs, sp.stiffness, sp.rest_length, strict=True):
        d = sp.height
        dx = (pend[j].pivot_x - d * np.sin(qpos[:, j])) - (pend[i].pivot_x - d * np.sin(qpos[:, i]))
        dz = -d * np.cos(qpos[:, j]) + d * np.cos(qpos[:, i])
        energy = energy + 0.5 * k * (np.hypot(dx, dz) - rest) ** 2
    return energy


def energy_drift(energy: np.ndarray, scale: float) -> float:
    """max |E(t) - E(0)| / scale, with scale the oscillation energy (J) (not the arbitrary zero of E)."""
    return float(np.abs(energy - energy[0]).max() / scale)


# ---- measurement -----------------------------------------------------------------------------------------


def frequency(t: np.ndarray, q: np.ndarray) -> float:
    """Angular frequency (rad/s) of an oscillating signal from its zero crossings.

    Crossing times are cubic-interpolated (`rigidbench.signals.crossings`, error O(h^4)); a least-squares line
    through crossing time versus crossing number gives the half period, so the resolution improves as
    1/(number of crossings)^(3/2) rather than being an FFT bin. NaN with fewer than four crossings.
    """
    tc = signals.crossings(t, q)
    if len(tc) < 4:
        return float("nan")
    half_period = np.polyfit(np.arange(len(tc)), tc, 1)[0]
    return float(np.pi / half_period)


def modal_amplitudes(t: np.ndarray, angles: np.ndarray, omegas: Iterable[float], stride: int = 10) -> np.ndarray:
    """Complex amplitude of each pendulum in each mode: least-squares fit of the whole record.

    Fits ``th_j(t) = sum_r Re(z_jr e^{i omega_r t})`` (linear in z, omegas given, e.g. measured) to every
    `stride`-th sample. Returns z, shape (n_pendulums, n_modes). A pure normal mode r has z_jr = a_jr c_r: all
    pendulums in phase or in anti-phase (docs/theory.md O7).
    """
    omegas = np.asarray(list(omegas), dtype=float)
    ts = t[::stride, None]
    basis = np.hstack([np.cos(omegas * ts), -np.sin(omegas * ts)])
    coef, *_ = np.linalg.lstsq(basis, angles[::stride], rcond=None)
    m = len(omegas)
    return (coef[:m] + 1j * coef[m:]).T


def sinusoid_residual(t: np.ndarray, q: np.ndarray, omega: float, stride: int = 10) -> float:
    """max |q - (A cos(omega t) + B sin(omega t))| / sqrt(A^2 + B^2) for the least-squares A, B (NaN if omega is)."""
    if not np.isfinite(omega):
        return float("nan")
    ts, qs = t[::stride], q[::stride]
    basis = np.stack([np.cos(omega * ts), np.sin(omega * ts)], axis=-1)
    coef, *_ = np.linalg.lstsq(basis, qs, rcond=None)
    return float(np.abs(qs - basis @ coef).max() / np.hypot(*coef))


def mode_shape(z: np.ndarray) -> np.ndarray:
    """A real mode vector from one column of `modal_amplitudes`: rotated to the phase of its largest entry and
    divided by the first entry (ratios th_j / th_1)."""
    z = z * np.exp(-1j * np.angle(z[np.argmax(np.abs(z))]))
    return z.real / z.real[0]


def worst(measured: np.ndarray, expected: np.ndarray, relative: bool = True) -> tuple[float, float]:
    """(measured, expected) of the entry with the largest error, for one result row over many modes."""
    measured, expected = np.asarray(measured, float), np.asarray(expected, float)
    err = np.abs(measured - expected) / (np.abs(expected) if relative else 1.0)
    err = np.where(np.isfinite(err), err, np.inf)
    i = int(np.argmax(err))
    return float(measured[i]), float(expected[i])


# ---- the gymnasium view ----------------------------------------------------------------------------------


class PendulumEnv(ScenarioEnv):
    """Env plumbing for hinged pendulums: observation = hinge angles and rates, action = a torque (N m) on the
    first pendulum's hinge through ``qfrc_applied``, clipped to +-`max_torque`. The observables compared with
    theory are the hinge angles (named after their joints); the reward is minus the largest deviation of a hinge
    angle from the closed-form motion, divided by the largest initial angle ``prediction["_scale"]``. Subclasses
    implement `theory`.

    Observation (float64, shape (2 n,), n hinges)

    ======= ================================================== ====== ==========================
    idx     quantity                                           unit   MuJoCo source
    ======= ================================================== ====== ==========================
    0..n-1  hinge angle of pendulum i (relative to its parent) rad    qpos of ``hinge<i>``
    n..2n-1 hinge rate of pendulum i                           rad/s  qvel of ``hinge<i>``
    ======= ================================================== ====== ==========================
    """

    max_torque: ClassVar[float] = 0.1

    @property
    def observables(self) -> tuple[str, ...]:  # one per hinge: the number depends on the model (the chain's n)
        return tuple(self.model.joint(i).name for i in range(self.model.njnt))

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(2 * self.model.nq,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_torque, self.max_torque, shape=(1,), dtype=np.float64)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        # Read per step: cached here (a MuJoCo attribute or a mapping look-up costs ~0.1 us each).
        self._nq = self.model.nq
        self._nobs = 2 * self._nq
        self._scale = float(self.prediction["_scale"])
        self.start_views()

    def bind_views(self) -> None:
        """The generalised forces the action writes into (`ScenarioEnv.bind_views`)."""
        self._qfrc = self._data.qfrc_applied

    def observe(self) -> np.ndarray:
        # qpos then qvel, in one C call: the state components (QPOS | QVEL) in MuJoCo's order. `_data`, not the
        # `data` property: ~40 ns less a read, every step.
        obs = np.empty(self._nobs)
        mujoco.mj_getState(self.model, self._data, obs, _QPOS_QVEL)
        return obs

    def apply_action(self, action: np.ndarray) -> None:
        self._qfrc[0] = action.item()  # a Python float: cheaper to read and to store than action[0]

    def observe_batch(self, worlds) -> np.ndarray:
        return np.concatenate([worlds.qpos, worlds.qvel], axis=1)

    def apply_actions(self, actions: np.ndarray, worlds) -> None:
        worlds.qfrc_applied[:, 0] = actions[:, 0]

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        return obs[:, : self._nq]

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        return np.abs(measured - predicted).max(axis=1) / self._scale  # NaN propagates, as in `deviation`

    def measured(self, obs: np.ndarray) -> list[float]:
        return obs.tolist()[: self._nq]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        # max |measured - predicted| over Python floats: numpy's number (NaN included) without three temporaries
        # and a reduction per step.
        if self._nq == 1:  # a lone pendulum: no loop (NaN propagates through abs and the division)
            return abs(measured[0] - predicted[0]) / self._scale
        worst = -1.0
        for m, p in zip(measured, predicted):  # noqa: B905 (lengths checked by _score)
            d = abs(m - p)
            if d > worst or d != d:
                worst = d
                if d != d:
                    break
        return worst / self._scale


def two_modes(t: np.ndarray, theta: np.ndarray, modes: Any, excited: Any) -> tuple[np.ndarray, dict[int, float]]:
    """The measured frequencies (rad/s; NaN for a mode not excited) and shapes (second pendulum over the first, by
    mode index) of a two-pendulum motion: each excited mode's frequency from its normal coordinate
    (`modes.coordinates`, `frequency`), then the shapes from one least-squares fit of both angles at those
    frequencies (`modal_amplitudes`, `mode_shape`)."""
    q = modes.coordinates(theta)
    omegas = np.array([frequency(t, q[:, r]) if excited[r] else np.nan for r in range(2)])
    fitted = [r for r in range(2) if excited[r]]
    z = modal_amplitudes(t, theta, omegas[fitted])
    return omegas, {r: mode_shape(z[:, i])[1] for i, r in enumerate(fitted)}
