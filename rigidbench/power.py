"""Power: the benchmark's own detection limit (issue 13).

A validation benchmark is only as good as the smallest error in the simulator it can see. Here the simulator is
given a wrong physical quantity on purpose: a copy of the compiled model has one quantity (a body's mass or
inertia, gravity, a spring constant, friction, contact stiffness) scaled by ``1 + delta`` and is simulated, while
the prediction, the controls and the measurement keep the unperturbed model (`Scenario.run(perturb=...)`). The
detection limit of that quantity is the smallest ``delta`` on the decade grid 1e-2 .. 1e-8 at which some check of
some case of the scenario fails; the grid is walked downwards and stops at the first ``delta`` nobody catches.

Quantities are found in the compiled model, not listed by scenarios (DESIGN.md: no scenario code knows about
power):

- ``mass:<body>``, ``inertia:<body>``: every body with degrees of freedom (the first `MAX_BODIES` of them);
  inertia is skipped where it is below 1e-6 of the body's joint-space inertia (a point bob's 1e-9 kg m^2);
- ``length:<body>``: a body turning about one hinge or ball joint, its centre of mass off the joint (a pendulum's
  rod, a top's arm): the centre of mass's distance from the joint (`mj_setConst` after it, as for mass);
- ``g``: gravity, where it is not zero, or the field a model declares fixed in a body's axes
  (`rigidbench.forces.FrameField`, gravity on a turning platform);
- ``spring-k``: every joint and tendon stiffness, where there is one;
- ``joint-damping``: every joint and tendon damping, where there is one;
- ``inverse-square-k``: every strength of the model's declared inverse-square pairs (`rigidbench.forces`), where it
  declares one; named ``coulomb-k`` where every strength is positive (repulsion: Coulomb's q1 q2 / (4 pi eps0));
- ``power-law-k``, ``power-law-n``: the strengths and the exponents of the model's declared power-law terms
  (`rigidbench.forces.power_law`), where it declares them;
- ``friction``: sliding friction of every geom and pair, where contacts are enabled;
- ``contact-stiffness``: every contact's stiffness (direct solref: k; standard solref: the time constant over
  sqrt(1 + delta)), where contacts are enabled;
- ``contact-damping``: every contact's damping (direct solref: b; standard solref: the damping ratio), where
  contacts are enabled and some contact declares one (zero damping, an elastic contact, is no quantity).

Those are edits of the model alone. Two more kinds of quantity are scenario parameters that MuJoCo never reads: a
custom numeric (`rigidbench.params.Numeric`) from which the scenario computes the start state or the controls
(`parameter_quantities`). The simulated copy's numeric is scaled, and its start state and controls are computed from
it (`rigidbench.harness.run` with a perturbation whose ``from_params`` is true); the prediction and the measurement
keep the unperturbed model and start. A scalar numeric parameter is one

- ``rate:<body>``: where it sets the initial velocity of the hinge of a turning frame, in proportion (scaled by
  1 + delta, the hinge's velocity is): a body other moving bodies are carried by, or the frame of a declared field
  (`rigidbench.forces.FrameField`). A turning platform's rate (foucault, eastward-deflection, gyrocompass); a
  rotor's or a top's spin, a release angle, a speed are initial conditions of the motion, not quantities;
- ``load:<param>``: where it changes the controls (the applied loads: a cue's, a stick's or a cushion's impulse,
  the cushion's height and restitution) and not the start state.

Both are found by what the numeric does (`parameter_quantities`), so no scenario declares them.

A scenario's quantities are those of every case's model (cases may differ, e.g. one force law or another); a case
whose model lacks a quantity runs unperturbed (it cannot see it). A parameter quantity is scaled in every case whose
model has its numeric.

Mass and inertia edits are followed by `mujoco.mj_setConst` (MuJoCo 4 caches the joint-space inertia ``dof_M0``;
without it the edit does nothing).

For each quantity the table also gives the theory's own sensitivity: the smallest ``delta`` at which the
*prediction* computed from the perturbed model moves some expected value by more than its check's tolerance. A
quantity the theory does not depend on (a simple pendulum's bob mass) cannot be detected by any benchmark, and
is reported as such, not as a weakness.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from rigidbench import forces, registry
from rigidbench.params import Numeric
from rigidbench.results import PASS
from rigidbench.runner import Job
from rigidbench.scenario import Scenario
from rigidbench.settings import Settings

DELTAS = tuple(10.0**-k for k in range(2, 9))  # 1e-2 .. 1e-8
MAX_BODIES = 3
NEGLIGIBLE_INERTIA = 1e-6


@dataclass(frozen=True)
class Quantity:
    """A physical quantity of a compiled model that can be scaled by ``1 + delta``: of the model itself, or the
    custom numeric `numeric` a scenario computes its start state or controls from (module docstring)."""

    name: str
    scale: Callable[[mujoco.MjModel, float], None]
    numeric: str | None = None

    def perturb(self, delta: float) -> Perturbation:
        return Perturbation(self.name, delta, self.numeric)


@dataclass(frozen=True)
class Perturbation:
    """Scale the quantity `name` of a model by ``1 + delta``: a value (picklable, so a job carrying it can run on a
    cluster), found again in the model it is applied to (`quantities`), or, for a parameter quantity, the custom
    numeric `numeric` (`parameter_quantities`), from which `rigidbench.harness.run` then computes the simulated
    start state and controls (``from_params``)."""

    name: str
    delta: float
    numeric: str | None = None

    @property
    def from_params(self) -> bool:
        """Whether the simulated start state and controls are computed from the perturbed copy (`harness.run`)."""
        return self.numeric is not None

    def __call__(self, model: mujoco.MjModel) -> None:
        if self.numeric is not None:
            _scale_numeric(model, self.numeric, self.delta)
            return
        for q in quantities(model):
            if q.name == self.name:
                q.scale(model, self.delta)
                return
        # Another case's quantity (module docstring): this case's model lacks it and runs unperturbed.


def _scale_numeric(model: mujoco.MjModel, name: str, delta: float) -> None:
    """Scale the custom numeric `name` by ``1 + delta``, where the model has it."""
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, name)
    if i >= 0:
        adr, size = model.numeric_adr[i], model.numeric_size[i]
        model.numeric_data[adr : adr + size] *= 1 + delta


def _moving_bodies(model: mujoco.MjModel) -> list[int]:
    return [b for b in range(1, model.nbody) if model.body_dofnum[b] > 0 and model.body_mass[b] > 0][:MAX_BODIES]


def _arm(model: mujoco.MjModel, b: int) -> np.ndarray | None:
    """For a body turning about one hinge or ball joint whose centre of mass lies off the joint: the joint's
    position in the body's frame (the anchor `length:<body>` scales the centre of mass's offset from); else None."""
    if model.body_jntnum[b] != 1:
        return None
    j = model.body_jntadr[b]
    if int(model.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_BALL)):
        return None
    anchor = np.array(model.jnt_pos[j])
    return anchor if np.linalg.norm(model.body_ipos[b] - anchor) > 0 else None


def quantities(model: mujoco.MjModel) -> list[Quantity]:
    """The quantities of `model` a power run perturbs (module docstring)."""
    out: list[Quantity] = []
    for b in _moving_bodies(model):
        name = model.body(b).name or f"body{b}"

        def mass(m: mujoco.MjModel, delta: float, b: int = b) -> None:
            m.body_mass[b] *= 1 + delta
            mujoco.mj_setConst(m, mujoco.MjData(m))

        out.append(Quantity(f"mass:{name}", mass))
        dofs = range(model.body_dofadr[b], model.body_dofadr[b] + model.body_dofnum[b])
        if model.body_inertia[b].max() >= NEGLIGIBLE_INERTIA * max(model.dof_M0[list(dofs)].max(), 0.0):

            def inertia(m: mujoco.MjModel, delta: float, b: int = b) -> None:
                m.body_inertia[b] *= 1 + delta
                mujoco.mj_setConst(m, mujoco.MjData(m))

            out.append(Quantity(f"inertia:{name}", inertia))
        arm = _arm(model, b)
        if arm is not None:

            def length(m: mujoco.MjModel, delta: float, b: int = b, anchor: np.ndarray = arm) -> None:
                m.body_ipos[b] = anchor + (m.body_ipos[b] - anchor) * (1 + delta)
                mujoco.mj_setConst(m, mujoco.MjData(m))

            out.append(Quantity(f"length:{name}", length))
    if np.any(model.opt.gravity != 0):

        def gravity(m: mujoco.MjModel, delta: float) -> None:
            m.opt.gravity[:] = m.opt.gravity * (1 + delta)

        out.append(Quantity("g", gravity))
    field = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, forces.FRAME_FIELD)
    if field >= 0:  # gravity declared as a field fixed in a body's axes (`rigidbench.forces.FrameField`)

        def frame_field(m: mujoco.MjModel, delta: float, i: int = field) -> None:
            adr, size = m.numeric_adr[i], m.numeric_size[i]
            m.numeric_data[adr : adr + size] *= 1 + delta

        out.append(Quantity("g" if not np.any(model.opt.gravity != 0) else "frame-field", frame_field))
    if np.any(model.jnt_stiffness > 0) or np.any(model.tendon_stiffness > 0):

        def spring(m: mujoco.MjModel, delta: float) -> None:
            m.jnt_stiffness[:] = m.jnt_stiffness * (1 + delta)
            m.tendon_stiffness[:] = m.tendon_stiffness * (1 + delta)

        out.append(Quantity("spring-k", spring))
    if np.any(model.dof_damping > 0) or np.any(model.tendon_damping > 0):

        def damping(m: mujoco.MjModel, delta: float) -> None:
            m.dof_damping[:] = m.dof_damping * (1 + delta)
            m.tendon_damping[:] = m.tendon_damping * (1 + delta)

        out.append(Quantity("joint-damping", damping))
    law = forces.inverse_square(model)
    if law is not None:

        def inverse_square(m: mujoco.MjModel, delta: float) -> None:
            i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, forces.INVERSE_SQUARE)
            if i >= 0:  # the quantity of another case (`plan`): a model without the force is left as it is
                adr, size = m.numeric_adr[i], m.numeric_size[i]
                m.numeric_data[adr : adr + size] *= 1 + delta

        out.append(Quantity("coulomb-k" if np.all(law.k > 0) else "inverse-square-k", inverse_square))
    if forces.power_law(model) is not None:  # every strength of the declared power-law terms, then their exponents
        for label, numeric in (("power-law-k", forces.POWER_LAW), ("power-law-n", forces.POWER_LAW_EXPONENT)):

            def scale(m: mujoco.MjModel, delta: float, numeric: str = numeric) -> None:
                _scale_numeric(m, numeric, delta)  # a case's model without the force is left as it is

            out.append(Quantity(label, scale))
    contact = not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    collidable = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    if contact and (collidable.any() or model.npair):
        if np.any(model.geom_friction[collidable, 0] > 0) or np.any(model.pair_friction[:, 0] > 0):

            def friction(m: mujoco.MjModel, delta: float) -> None:
                m.geom_friction[:, 0] *= 1 + delta
                m.pair_friction[:, :2] *= 1 + delta

            out.append(Quantity("friction", friction))

        def stiffness(m: mujoco.MjModel, delta: float) -> None:
            for solref in (m.geom_solref, m.pair_solref):
                direct = solref[:, 0] < 0
                solref[direct, 0] *= 1 + delta  # k
                solref[~direct, 0] /= math.sqrt(1 + delta)  # k ~ 1 / timeconst^2

        out.append(Quantity("contact-stiffness", stiffness))
        if np.any(model.geom_solref[collidable, 1] != 0) or np.any(model.pair_solref[:, 1] != 0):

            def contact_damping(m: mujoco.MjModel, delta: float) -> None:
                for solref in (m.geom_solref, m.pair_solref):
                    solref[:, 1] *= 1 + delta  # direct: -b; standard: the damping ratio

            out.append(Quantity("contact-damping", contact_damping))
    return out


PROBE = 1e-3  # the relative change of a numeric that tells what it sets (`parameter_quantities`)


def parameter_quantities(scenario: Scenario, model: mujoco.MjModel, nstep: int) -> list[Quantity]:
    """The scenario's scalar numeric parameters that are physical quantities of `model` (module docstring): each
    scaled by 1 + `PROBE` in a copy, the start state and the controls (of a run of `nstep` steps) computed from the
    copy tell a turning frame's rate (``rate:<body>``) and an applied load (``load:<param>``) from an initial
    condition."""
    out: list[Quantity] = []
    base = _started(scenario, model, nstep)
    if base is None:
        return out
    data0, control0 = base
    for p in scenario.params:
        if not isinstance(p.target, Numeric):
            continue
        i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, p.target.name)
        if i < 0 or model.numeric_size[i] != 1 or model.numeric_data[model.numeric_adr[i]] == 0:
            continue
        probe = copy.copy(model)
        _scale_numeric(probe, p.target.name, PROBE)
        moved = _started(scenario, probe, nstep)
        if moved is None:
            continue
        data1, control1 = moved
        same_start = np.array_equal(data0.qpos, data1.qpos) and np.array_equal(data0.qvel, data1.qvel)
        same_control = (control0 is None and control1 is None) or (
            control0 is not None and control1 is not None and np.array_equal(control0, control1)
        )
        name = None
        if same_start and not same_control:
            name = f"load:{p.name}"
        elif not same_start:
            frame = _turned_frame(model, data0.qvel, data1.qvel)
            if frame is not None:
                name = f"rate:{frame}"
        if name is not None:
            out.append(Quantity(name, lambda m, delta, n=p.target.name: _scale_numeric(m, n, delta), p.target.name))
    return out


def _started(scenario: Scenario, model: mujoco.MjModel, nstep: int) -> tuple[mujoco.MjData, np.ndarray | None] | None:
    """The start state and the controls of a run of `nstep` steps the scenario computes from `model` (None where it
    refuses the model's numbers)."""
    try:
        data = scenario.start(model)
        control = scenario.control(model, model.opt.timestep, nstep)
    except Exception:  # noqa: BLE001 - numbers the scenario refuses set nothing a run could use
        return None
    return data, (None if control is None else np.array(control, dtype=float))


def _turned_frame(model: mujoco.MjModel, qvel0: np.ndarray, qvel1: np.ndarray) -> str | None:
    """The name of the turning frame whose hinge velocity went from `qvel0` to ``(1 + PROBE) qvel0`` in `qvel1`
    (module docstring), or None."""
    law = forces.frame_field(model)
    for j in range(model.njnt):
        if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE:
            continue
        dof, body = model.jnt_dofadr[j], model.jnt_bodyid[j]
        v0, v1 = float(qvel0[dof]), float(qvel1[dof])
        if v0 == 0 or not math.isclose(v1, v0 * (1 + PROBE), rel_tol=1e-9):
            continue
        carries = any(
            model.body_dofnum[b] > 0 and _descends(model, b, body) for b in range(1, model.nbody) if b != body
        )
        if carries or (law is not None and law.frame == body):
            return model.body(body).name or f"body{body}"
    return None


def _descends(model: mujoco.MjModel, b: int, ancestor: int) -> bool:
    while b > 0:
        b = int(model.body_parentid[b])
        if b == ancestor:
            return True
    return False


@dataclass
class Limit:
    """The detection limit of one quantity of one scenario."""

    scenario: str
    quantity: str
    detected: float | None = None  # smallest delta on the grid at which a check failed
    caught_by: list[str] = field(default_factory=list)  # "case:check" that failed at that delta
    theory: float | None = None  # smallest delta at which the prediction itself moves beyond a tolerance
    tried: list[float] = field(default_factory=list)

    def record(self) -> dict[str, Any]:
        return {
            "scenario": self.scenario,
            "quantity": self.quantity,
            "detected": self.detected,
            "caught_by": self.caught_by,
            "theory_sensitivity": self.theory,
            "deltas_tried": self.tried,
        }


def theory_sensitivity(scenario: Scenario, quantity: Quantity, settings: Settings | None) -> float | None:
    """The smallest delta on the grid at which the prediction of some case, computed from the perturbed model,
    moves some expected value by more than that check's tolerance (None: not even at the largest delta)."""
    smallest = None
    for delta in DELTAS:
        moved = False
        for case in scenario.cases:
            prep = scenario.prepare(case.name, None, settings)
            model = prep.model
            perturbed = _copy(model)
            # By name in this case's own model (its bodies may differ from the model the quantity was listed from;
            # a case whose model lacks it is left unperturbed, as in `Perturbation`).
            perturbation = quantity.perturb(delta)
            perturbation(perturbed)
            # A parameter quantity: the prediction from the perturbed parameters and the start they give; a model
            # quantity: from the perturbed model and the case's own parameters.
            params = None if perturbation.from_params else prep.params
            try:
                other = scenario.predict(perturbed, scenario.start(perturbed, params))
            except Exception:  # noqa: BLE001 - a prediction the perturbation makes undefined moved, by definition
                moved = True
                break
            for name in case.checks:
                check = scenario._scaled_check(name, prep.prediction)
                e0, e1 = float(prep.prediction[name]), float(other[name])
                if not math.isfinite(e1) or check.error(e1, e0) > check.tolerance:
                    moved = True
                    break
            if moved:
                break
        if not moved:
            break
        smallest = delta
    return smallest


def _copy(model: mujoco.MjModel) -> mujoco.MjModel:
    return copy.copy(model)


def plan(targets: Sequence[str], settings: Settings | None) -> list[tuple[Scenario, Quantity]]:
    """Every (scenario, quantity) pair of the targets' scenarios: the quantities of every case's model.

    Raises
    ------
    ValueError
        For an unknown scenario.
    """
    pairs = []
    for target in targets or list(registry.scenarios()):
        scenario, _ = registry.parse_target(target)
        found: dict[str, Quantity] = {}
        for case in scenario.cases:  # every case's quantities, in the order they first appear
            prep = scenario.prepare(case.name, None, settings)
            for q in quantities(prep.model) + parameter_quantities(scenario, prep.model, prep.nstep):
                found.setdefault(q.name, q)
        pairs += [(scenario, q) for q in found.values()]
    return pairs


def jobs_at(pairs: Sequence[tuple[Scenario, Quantity]], delta: float, cases: Sequence[str] | None = None) -> list[Job]:
    """The perturbed jobs of every pair at one delta: each case of the scenario (or the named ones)."""
    out = []
    for scenario, q in pairs:
        for case in scenario.cases:
            if cases is None or case.name in cases:
                out.append(Job(scenario, case.name, {}, variant=f"{q.name}*(1+{delta:g})", perturb=q.perturb(delta)))
    return out


def failing(rows: Sequence[dict[str, Any]]) -> list[str]:
    """``case:check`` of every row that did not pass."""
    return [f"{r['case']}:{r['check']}" for r in rows if r["status"] != PASS]


def table(limits: Sequence[Limit]) -> str:
    """One row per scenario and quantity: detected at, caught by, the theory's own sensitivity."""
    header = ("scenario", "quantity", "detected at", "caught by", "theory moves at")
    lines = []
    for lim in limits:
        detected = f"{lim.detected:.0e}" if lim.detected is not None else f"> {DELTAS[0]:.0e}"
        theory = f"{lim.theory:.0e}" if lim.theory is not None else f"> {DELTAS[0]:.0e} (independent)"
        caught = ", ".join(lim.caught_by[:2]) + (f" (+{len(lim.caught_by) - 2})" if len(lim.caught_by) > 2 else "")
        lines.append((lim.scenario, lim.quantity, detected, caught or "-", theory))
    widths = [max(len(x) for x in col) for col in zip(header, *lines, strict=True)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    out = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    out += [fmt.format(*line).rstrip() for line in lines]
    return "\n".join(out)


def walk(
    pairs: Sequence[tuple[Scenario, Quantity]],
    settings: Settings | None,
    executor: Any,
    *,
    progress: Callable[[float, int], None] | None = None,
) -> tuple[list[Limit], Any]:
    """Walk the deltas down (module docstring): at each delta run every case of every quantity still caught, on
    `executor` (`rigidbench.runner.run_jobs`), until nothing is caught; then the theory's own sensitivity.

    Returns the limits, and the interrupt that stopped the walk (None if it finished).
    """
    from rigidbench.runner import run_jobs

    limits = {(sc.slug, q.name): Limit(sc.slug, q.name) for sc, q in pairs}
    alive = list(pairs)
    for delta in DELTAS:
        if not alive:
            break
        if progress is not None:
            progress(delta, len(alive))
        jobs = jobs_at(alive, delta)
        result = run_jobs(jobs, settings, executor=executor)
        caught: dict[tuple[str, str], list[str]] = {}
        for job in jobs:
            quantity = job.variant.split("*")[0]
            caught.setdefault((job.scenario.slug, quantity), []).extend(failing(result.rows.get(job.key, [])))
        for sc, q in alive:
            limits[(sc.slug, q.name)].tried.append(delta)
        alive = [(sc, q) for sc, q in alive if caught.get((sc.slug, q.name))]
        for sc, q in alive:
            lim = limits[(sc.slug, q.name)]
            lim.detected, lim.caught_by = delta, caught[(sc.slug, q.name)]
        if result.interrupted is not None:
            return list(limits.values()), result.interrupted
    for sc, q in pairs:
        limits[(sc.slug, q.name)].theory = theory_sensitivity(sc, q, settings)
    return list(limits.values()), None
