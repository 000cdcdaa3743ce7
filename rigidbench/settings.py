"""Simulation settings and profiles.

Settings are part of what is measured (DESIGN.md). The scenario's MJCF file holds its *reference* settings
(integrator, timestep, contact softness), each commented with the reason; a profile overrides some of them.
Whatever the profile, the settings recorded with a result are read back from the compiled model.

Profiles
--------
reference
    The model file as written: settings under which MuJoCo should reproduce the theory closely.
mujoco-default
    What a user gets by writing the model naively: MuJoCo's default integrator (Euler), 2 ms step, default
    solref/solimp on every geom and equality constraint, pyramidal friction cone. Failures here are the
    benchmark's findings.
thorough
    The reference settings with at least `THOROUGH_SAMPLES` Monte Carlo samples in statistical scenarios.

Monte Carlo sample counts: a scenario that draws samples keeps its count in ``<numeric name="samples">``
(its public parameter, e.g. ``n``, targets that entry); `Settings.samples` raises it to at least that many.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace

import mujoco
import numpy as np

INTEGRATORS = {
    "Euler": mujoco.mjtIntegrator.mjINT_EULER,
    "RK4": mujoco.mjtIntegrator.mjINT_RK4,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
}
CONES = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}

# MuJoCo's own defaults (MJCF reference, <geom solref solimp>, <option>).
MUJOCO_DEFAULT_SOLREF = (0.02, 1.0)
MUJOCO_DEFAULT_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)
MUJOCO_DEFAULT_TIMESTEP = 0.002

# Samples in the thorough profile: a goodness-of-fit test with ~20 bins then resolves bin probabilities to ~1 %.
THOROUGH_SAMPLES = 100_000

# Largest timestep accepted (s): beyond this no scenario here is meaningful, and MuJoCo accepts anything.
MAX_TIMESTEP = 0.1

# Name of the model's custom text holding the settings that followed the parameters (`Scenario.reference_settings`),
# as JSON: {"timestep": {"value": ..., "rule": ...}, ...}; read back into every result's settings as "derived".
DERIVED_TEXT = "rigidbench:derived"


@dataclass(frozen=True)
class Settings:
    """Overrides of the model's simulation options; ``None`` keeps what the model file says.

    Attributes
    ----------
    integrator : {"Euler", "RK4", "implicit", "implicitfast"} or None
    timestep : float or None
        Seconds, in (0, 0.1].
    cone : {"pyramidal", "elliptic"} or None
    solref, solimp : tuple of float or None
        Applied to every geom, explicit contact pair and equality constraint (MuJoCo's constraint softness;
        MuJoCo's defaults are the same for all three).
    samples : int or None
        Least number of Monte Carlo samples (raises the model's ``<numeric name="samples">``, if it has one).
    """

    integrator: str | None = None
    timestep: float | None = None
    cone: str | None = None
    solref: tuple[float, ...] | None = None
    solimp: tuple[float, ...] | None = None
    samples: int | None = None

    def __post_init__(self) -> None:
        if self.integrator is not None and self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator {self.integrator!r} is not one of {', '.join(INTEGRATORS)}")
        if self.timestep is not None and not 0.0 < self.timestep <= MAX_TIMESTEP:
            raise ValueError(f"timestep = {self.timestep!r} s is outside the valid range (0, {MAX_TIMESTEP}] s")
        if self.cone is not None and self.cone not in CONES:
            raise ValueError(f"cone {self.cone!r} is not one of {', '.join(CONES)}")
        if self.samples is not None and not (isinstance(self.samples, int) and self.samples >= 1):
            raise ValueError(f"samples = {self.samples!r} must be an integer >= 1")

    def merged(self, other: Settings) -> Settings:
        """These settings with every field `other` sets replaced by `other`'s value."""
        changes = {k: v for k, v in vars(other).items() if v is not None}
        return replace(self, **changes)

    def apply(self, spec: mujoco.MjSpec) -> None:
        """Write the overrides into `spec` (before compiling)."""
        if self.integrator is not None:
            spec.option.integrator = INTEGRATORS[self.integrator]
        if self.timestep is not None:
            spec.option.timestep = self.timestep
        if self.cone is not None:
            spec.option.cone = CONES[self.cone]
        for element in (*spec.geoms, *spec.pairs, *spec.equalities):
            if self.solref is not None:
                element.solref = list(self.solref)
            if self.solimp is not None:
                element.solimp = list(self.solimp)
        samples = spec.numeric("samples")
        if self.samples is not None and samples is not None:
            samples.data = [max(float(samples.data[0]), float(self.samples))]


PROFILES: dict[str, Settings] = {
    "reference": Settings(),
    "mujoco-default": Settings(
        integrator="Euler",
        timestep=MUJOCO_DEFAULT_TIMESTEP,
        cone="pyramidal",
        solref=MUJOCO_DEFAULT_SOLREF,
        solimp=MUJOCO_DEFAULT_SOLIMP,
    ),
    "thorough": Settings(samples=THOROUGH_SAMPLES),
}


def profile(name: str) -> Settings:
    """The settings of a named profile.

    Raises
    ------
    ValueError
        If `name` is not a known profile.
    """
    if name not in PROFILES:
        raise ValueError(f"profile {name!r} is not one of {', '.join(PROFILES)}")
    return PROFILES[name]


# Pipeline stages a model can switch off (MuJoCo's disable flags), by the name recorded with results.
STAGES = {"contact": mujoco.mjtDisableBit.mjDSBL_CONTACT, "constraint": mujoco.mjtDisableBit.mjDSBL_CONSTRAINT}


def idle_stages(model: mujoco.MjModel) -> tuple[str, ...]:
    """The pipeline stages that can do nothing in `model`, so that skipping them changes no result.

    ``contact``: no two geoms of different bodies have matching contype/conaffinity bits, and there is no
    explicit ``<pair>`` and no flex (conservative: MuJoCo's parent-child and static-body filters are ignored).
    ``constraint``: besides no contact, no equality, no joint or tendon limit and no friction loss.

    Measured (mujoco 4.0, RK4): collision detection over geoms that cannot collide still costs ~0.3 us per
    force evaluation, and the empty constraint stage ~0.1 us: 20-30 % of a pendulum's or a top's step.
    Skipping both leaves every state bit for bit the same (tests/test_settings.py checks every scenario).
    """
    contype, conaffinity, body = model.geom_contype, model.geom_conaffinity, model.geom_bodyid
    pairs = (np.bitwise_and.outer(contype, conaffinity) | np.bitwise_and.outer(conaffinity, contype)) != 0
    collides = bool(model.npair or model.nflex or (pairs & (body[:, None] != body[None, :])).any())
    constrained = collides or bool(
        model.neq
        or model.jnt_limited.any()
        or model.tendon_limited.any()
        or (model.dof_frictionloss > 0).any()
        or (model.tendon_frictionloss > 0).any()
    )
    return (() if collides else ("contact",)) + (() if constrained else ("constraint",))


def skip_idle_stages(model: mujoco.MjModel) -> None:
    """Switch off the stages `idle_stages` finds (in place). Call it again after editing the model's contacts,
    limits, equalities or friction loss: a stage once skipped stays skipped."""
    for stage in idle_stages(model):
        model.opt.disableflags |= STAGES[stage]


def read_settings(model: mujoco.MjModel) -> dict:
    """The settings a compiled model actually uses, for the results record (values immutable)."""
    names = {v: k for k, v in INTEGRATORS.items()}
    cones = {v: k for k, v in CONES.items()}
    out = {
        "integrator": names.get(mujoco.mjtIntegrator(model.opt.integrator), str(model.opt.integrator)),
        "timestep": float(model.opt.timestep),
        "cone": cones[mujoco.mjtCone(model.opt.cone)],
        "mujoco": mujoco.__version__,
        # Pipeline stages switched off (by the model file, or by `skip_idle_stages` where they can do nothing).
        "disabled": tuple(name for name, bit in STAGES.items() if model.opt.disableflags & bit),
    }
    derived = _custom_text(model, DERIVED_TEXT)
    if derived is not None:
        out["derived"] = json.loads(derived)
    contact = [i for i in range(model.ngeom) if model.geom_contype[i] or model.geom_conaffinity[i]]
    if contact:
        out["solref"] = tuple(sorted({tuple(float(x) for x in model.geom_solref[i]) for i in contact}))
        out["solimp"] = tuple(sorted({tuple(float(x) for x in model.geom_solimp[i]) for i in contact}))
    return out


def _custom_text(model: mujoco.MjModel, name: str) -> str | None:
    """The data of the model's custom text `name`, or None if it has none."""
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXT, name)
    if i < 0:
        return None
    start, size = int(model.text_adr[i]), int(model.text_size[i])
    return bytes(model.text_data[start : start + size]).rstrip(b"\0").decode()
