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
- ``g``: gravity, where it is not zero, or the field a model declares fixed in a body's axes
  (`rigidbench.forces.FrameField`, gravity on a turning platform);
- ``spring-k``: every joint and tendon stiffness, where there is one;
- ``inverse-square-k``: every strength of the model's declared inverse-square pairs (`rigidbench.forces`), where it
  declares one;
- ``friction``: sliding friction of every geom and pair, where contacts are enabled;
- ``contact-stiffness``: every contact's stiffness (direct solref: k; standard solref: the time constant over
  sqrt(1 + delta)), where contacts are enabled.

A scenario's quantities are those of every case's model (cases may differ, e.g. one force law or another); a case
whose model lacks a quantity runs unperturbed (it cannot see it).

Mass and inertia edits are followed by `mujoco.mj_setConst` (MuJoCo 4 caches the joint-space inertia ``dof_M0``;
without it the edit does nothing).

For each quantity the table also gives the theory's own sensitivity: the smallest ``delta`` at which the
*prediction* computed from the perturbed model moves some expected value by more than its check's tolerance. A
quantity the theory does not depend on (a simple pendulum's bob mass) cannot be detected by any benchmark, and
is reported as such, not as a weakness.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from rigidbench import forces, registry
from rigidbench.results import PASS
from rigidbench.runner import Job
from rigidbench.scenario import Scenario
from rigidbench.settings import Settings

DELTAS = tuple(10.0**-k for k in range(2, 9))  # 1e-2 .. 1e-8
MAX_BODIES = 3
NEGLIGIBLE_INERTIA = 1e-6


@dataclass(frozen=True)
class Quantity:
    """A physical quantity of a compiled model that can be scaled by ``1 + delta``."""

    name: str
    scale: Callable[[mujoco.MjModel, float], None]

    def perturb(self, delta: float) -> Perturbation:
        return Perturbation(self.name, delta)


@dataclass(frozen=True)
class Perturbation:
    """Scale the quantity `name` of a model by ``1 + delta``: a value (picklable, so a job carrying it can run on a
    cluster), found again in the model it is applied to (`quantities`)."""

    name: str
    delta: float

    def __call__(self, model: mujoco.MjModel) -> None:
        for q in quantities(model):
            if q.name == self.name:
                q.scale(model, self.delta)
                return
        # Another case's quantity (module docstring): this case's model lacks it and runs unperturbed.


def _moving_bodies(model: mujoco.MjModel) -> list[int]:
    return [b for b in range(1, model.nbody) if model.body_dofnum[b] > 0 and model.body_mass[b] > 0][:MAX_BODIES]


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
    if forces.inverse_square(model) is not None:

        def inverse_square(m: mujoco.MjModel, delta: float) -> None:
            i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, forces.INVERSE_SQUARE)
            if i >= 0:  # the quantity of another case (`plan`): a model without the force is left as it is
                adr, size = m.numeric_adr[i], m.numeric_size[i]
                m.numeric_data[adr : adr + size] *= 1 + delta

        out.append(Quantity("inverse-square-k", inverse_square))
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
    return out


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
            Perturbation(quantity.name, delta)(perturbed)
            try:
                other = scenario.predict(perturbed, scenario.start(perturbed, prep.params))
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
    import copy

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
            for q in quantities(scenario.prepare(case.name, None, settings).model):
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
