r"""The scenario contract: everything a scenario author writes, and nothing that runs it.

A scenario is an MJCF file in ``models/`` and a `Scenario` subclass with the same stem in ``envs/`` (house rule 1).
The subclass declares its public parameters (`Param`, with units and ranges), its named `Case`\ s, its `Check`\ s
(each with a tolerance, the reason for it and the theory it tests), the `Domain`\ s its closed forms need, and
implements a few hooks: `initial_state`, `predict` (from ``analytic/``), `duration` and `measure`, and where the
physics asks for them `reference_settings`, `validate`, `control`, `simulate`. Start from the template,
``docs/templates/vertical_throw.py`` (docs/scenarios.md, "Adding a scenario"). A first scenario can skip the float32
hook (`precision_domain`) and the per-check prediction entries other than ``"_tolerance"``.

What is done with a scenario (resolving parameters, compiling through MjSpec, starting, predicting, running,
scoring, float32 round-off floors) is the harness's (`rigidbench.harness`), which imports scenarios and never the
reverse. Every scenario still answers ``scenario.run(...)``, ``scenario.prepare(...)``, ``scenario.resolve(...)``
and the like: those methods, at the end of `Scenario`, hand the call to the harness.
"""

from __future__ import annotations

import functools
import importlib
import importlib.resources
import math
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import mujoco
import numpy as np

from rigidbench.params import Bound, Param, Range, Value, check_known
from rigidbench.trajectory import Trajectory

__all__ = [
    "MAX_ACCELERATION",
    "PER_CHECK",
    "UNRESOLVED_FRACTION",
    "Bound",
    "Case",
    "Check",
    "Derived",
    "Domain",
    "OutsideDomain",
    "Param",
    "Params",
    "Range",
    "Scenario",
    "Trajectory",
    "Value",
    "round_step",
]

Params = dict[str, Value]
# MuJoCo parses and compiles without the GIL and does not document its compiler as thread-safe; the runner builds
# cases from several threads, so one compile at a time (a few ms each): `Scenario.defaults` and the harness's build.
BUILD_LOCK = threading.RLock()
# A case value is a number, or a function of the other resolved parameters (e.g. a steady-precession rate).
CaseValue = Value | Callable[[Mapping[str, Value]], Value]

# MuJoCo flags a joint acceleration (qacc) above mjMAXVAL = 1e10 as a divergence and resets the state ("Nan, Inf or
# huge value in QACC"): an engine limit, not the theory's. Scenarios keep every acceleration of their motion (a blow's
# pulse, a contact's peak deceleration, a top's gyroscopic acceleration) below a tenth of it.
MAX_ACCELERATION = 1e9


# A check whose float32 round-off floor reaches this fraction of the quantity itself says nothing about the physics
# at that precision (`Scenario._roundoff_check`): it is reported as unresolved instead of passing on a tolerance
# that could not fail.
UNRESOLVED_FRACTION = 0.1

# The prediction's entries keyed by check name (`Scenario.check_prediction_keys`): a tolerance and a relative check's
# floor that depend on the run (`Scenario._scaled_check`, `Check.floor`), and a float32 engine's round-off scale,
# secular quantities and derived floors (`rigidbench.harness.roundoff_scale`, `rigidbench.harness.roundoff_check`).
PER_CHECK = ("_tolerance", "_floor", "_roundoff_scale", "_roundoff_secular", "_roundoff_eps")


def round_step(h: float) -> float:
    """A derived timestep rounded down to one significant digit (1, 2, ..., 9 times a power of ten, s).

    Never larger than the rule's value, so its error bounds hold, and at most a factor 2 smaller. A step that stays
    the same over a range of parameters is readable, reproducible from its printed value, and equal to the model
    file's step at every default case (each rule is calibrated a hair above it there).
    """
    e = math.floor(math.log10(h))
    return float(f"{math.floor(h / 10.0**e * (1 + 1e-12))}e{e}")


class OutsideDomain(ValueError):
    """A parameter set the theory does not cover to the checks' tolerances: refused before simulating.

    Attributes
    ----------
    domain : str
        Short name of the violated condition (a census groups refusals by it), e.g. ``"small-oscillation"``.
    """

    def __init__(self, message: str, domain: str) -> None:
        super().__init__(message)
        self.domain = domain


@dataclass(frozen=True)
class Domain:
    """A condition the theory of some checks needs, stated in words and tested on the resolved parameters.

    Outside it the closed form does not hold to the checks' tolerances (a linearisation, an asymptotic
    exponent, an impulsive blow), so a parameter set there is refused before anything is simulated, with a
    message naming the parameters and the theory (`OutsideDomain`). `rigidbench list` prints every domain.

    Attributes
    ----------
    name : str
        Short name, e.g. ``"small-oscillation"``.
    theory : str
        THEORY.md entry (and seed) whose domain this is.
    text : str
        The condition and why, e.g. ``"|amplitude| <= 4e-3 rad: the period's amplitude shift a^2/16 stays
        below the 1e-6 tolerance"``.
    test : callable
        Resolved parameters -> None inside the domain, or a phrase naming the parameters and their values
        outside it (``"amplitude1 = 0.5 rad"``).
    cases : tuple of str
        The cases it applies to; empty for every case.
    """

    name: str
    theory: str
    text: str
    test: Callable[[Mapping[str, Value]], str | None]
    cases: tuple[str, ...] = ()

    def applies(self, case: str) -> bool:
        return not self.cases or case in self.cases


@dataclass(frozen=True)
class Case:
    """A named initial condition / parameter set that exercises distinct physics.

    Attributes
    ----------
    name : str
    doc : str
    values : mapping of parameter name to a value or to a function of the resolved parameters
        Values given as functions are derived (e.g. the steady-precession rate from the spin and tilt); a
        user's explicit ``--set`` of that parameter wins over the derivation.
    checks : tuple of str
        Names of the scenario's checks that apply to this case.
    ranges : mapping of parameter name to `Range` or `Bound`
        The case's regime: where its checks' theory holds (e.g. a small tilt for the linearised sleeping top).
        Narrower than the parameter's own range; a value outside it is refused (`OutsideDomain`), and a census
        draws inside it.
    regime : str
        Why the ranges are what they are (the theory and the tolerance that set them).
    """

    name: str
    doc: str
    values: Mapping[str, CaseValue]
    checks: tuple[str, ...]
    ranges: Mapping[str, Range | Bound] = field(default_factory=dict)
    regime: str = ""


@dataclass(frozen=True)
class Derived:
    """A simulation setting that follows the parameters (`Scenario.reference_settings`).

    Attributes
    ----------
    value : float
        In SI units (a timestep or a pulse duration in s).
    rule : str
        How it follows from the parameters, with the numbers, e.g. ``"T0 / 3200, T0 = 2 pi sqrt(l/g) = 2.006 s"``.
    """

    value: float
    rule: str


@dataclass(frozen=True)
class Check:
    """An observable, its tolerance and the reason for that tolerance.

    Attributes
    ----------
    name : str
        Public name of the check, e.g. ``"nutation-period"``.
    unit : str
        Unit of `measured` and `expected`.
    tolerance : float
        Largest accepted error, in the unit for ``kind="abs"``, a fraction for ``kind="rel"``. A bound that
        depends on the run (n^-1/2, k^-1/2) is given at the model's defaults here and replaced by the run's
        prediction (``prediction["_tolerance"][name]``, see `Scenario._scaled_check`).
    kind : {"rel", "abs"}
        Relative error ``|m - e| / max(|e|, floor)`` or absolute error ``|m - e|``.
    reason : str
        Where the tolerance comes from (integrator order and step, contact stiffness, statistics, ...).
    theory : str
        The docs/theory.md ID(s) of the prediction first (``"T4: ..."``, `rigidbench.theory`), then the formula and
        its seed location.
    floor : float
        For a relative check whose expected value can come near 0 over the ranges (a marble the stick never
        reaches, a ball a plastic cushion stops): the size, in the check's unit, below which the error is no longer
        relative to the expected value but to this floor, because the simulation's errors keep that size (they
        scale with the motion that sets it, e.g. the stick's speed). 0 (the default) for a pure relative error.
        A floor that depends on the run is given as ``prediction["_floor"][name]``; the reason states the rule.
    identity : bool
        The check measures a relation that holds exactly by symmetry or by construction (a quantity zero by symmetry,
        a conservation law the engine's equal and opposite forces build in), not the accuracy of an approximation:
        its error is round-off, and a failure means a broken model or engine, not an inaccurate one. Reported as
        ``claim: "identity"`` in result rows, `rigidbench list` and the report, apart from the accuracy checks.
    false_alarm : float
        For a statistical test (a Monte Carlo sample's goodness of fit), the probability that a correct simulation
        fails it: the test's level. Reported as ``claim: "statistical"``; a census re-runs a set that failed only
        such checks on an independent sample (`rigidbench.census`), since a correct simulation fails one in 1 /
        false_alarm sets. 0 (the default) for a deterministic check.
    """

    name: str
    unit: str
    tolerance: float
    kind: str
    reason: str
    theory: str
    floor: float = 0.0
    identity: bool = False
    false_alarm: float = 0.0

    @property
    def claim(self) -> str:
        """``"identity"`` for a check of an exact relation (`identity`), ``"statistical"`` for a statistical test
        (`false_alarm`), else ``"accuracy"``."""
        return "identity" if self.identity else "statistical" if self.false_alarm > 0 else "accuracy"

    def __post_init__(self) -> None:
        if self.kind not in ("rel", "abs"):
            raise ValueError(f"check {self.name}: kind must be 'rel' or 'abs', not {self.kind!r}")
        if not 0 <= self.false_alarm < 1:
            raise ValueError(f"check {self.name}: false_alarm must be in [0, 1), not {self.false_alarm!r}")

    def error(self, measured: float, expected: float) -> float:
        diff = abs(measured - expected)
        if self.kind == "abs":
            return diff
        scale = max(abs(expected), self.floor)
        return diff / scale if scale != 0 else math.inf


class Scenario:
    """Base class of every scenario: set the class attributes, implement the hooks.

    Hooks a scenario must implement: `initial_state`, `predict`, `duration`, `measure`. Hooks it may override:
    `validate`, `reference_settings`, `apply_derived`, `check_model`, `control`, `simulate`, `precision_domain`.
    Everything below "what the harness does" is not for overriding.

    Class attributes
    ----------------
    slug : str
        Public name, e.g. ``"heavy-top"``; the MJCF file is ``models/<slug with underscores>.xml``.
    title, doc : str
        One line, and a paragraph with the theory references.
    params : tuple of Param
    cases : tuple of Case
        The first case is the default.
    checks : tuple of Check
    domains : tuple of Domain
        Conditions the theory needs beyond the parameter ranges (refused before simulating).
    env_id : str or None
        Gymnasium id, e.g. ``"rigidbench/HeavyTop-v0"``; None for a scenario with no stepping env.
    sharded : bool
        True where `simulate` maps independent shards through `rigidbench.shards.map` (a Monte Carlo batch): under
        ``--cluster`` the runner runs such a case here and its shards on the workers.
    """

    slug: ClassVar[str]
    title: ClassVar[str]
    params: ClassVar[tuple[Param, ...]]
    cases: ClassVar[tuple[Case, ...]]
    checks: ClassVar[tuple[Check, ...]]
    domains: ClassVar[tuple[Domain, ...]] = ()
    env_id: ClassVar[str | None]
    sharded: ClassVar[bool] = False

    # ---- hooks: what a scenario says -----------------------------------------------------------------

    def validate(self, params: Mapping[str, Value]) -> None:
        """Cross-parameter validity (e.g. the inertia triangle inequality). Raise ValueError naming them."""

    def reference_settings(self, params: Mapping[str, Value]) -> dict[str, Derived]:
        """Settings that follow the parameters: ``"timestep"`` (s) from the fastest time scale and the integrator's
        error bound for the checks' tolerances, ``"pulse_duration"`` (s) from an omega tau bound,
        ``"solver_tolerance"`` (MuJoCo's ``opt.tolerance``) from the accelerations the constraint solver must resolve
        (it stops when its scaled gradient is below the tolerance: a fixed 1e-8 leaves slow motions unconverged);
        other names are scenario-specific (`apply_derived`).

        A derived timestep is used unless the settings give one (a profile such as ``mujoco-default``, the
        user's ``--timestep``, a sweep point); a derived pulse duration is always used (it is part of the blow,
        not of the integrator); a derived solver tolerance gives way to a profile's or the user's (applied after).
        All are recorded with every result (``settings["derived"]``). Empty by default: the model file's values.
        """
        return {}

    def apply_derived(self, spec: mujoco.MjSpec, name: str, value: float) -> None:
        """Write a scenario-specific derived setting (a name `reference_settings` returns besides ``"timestep"``
        and ``"pulse_duration"``, e.g. a constraint's time constant) into `spec`; always applied, like the pulse
        (it is part of the model, not of the integrator)."""
        raise ValueError(f"scenario '{self.slug}': no derived setting '{name}'")

    def check_model(self, model: mujoco.MjModel) -> None:
        """Validity of the compiled model under its settings (e.g. contact stiffness against the timestep).

        Called by `build`; raise ValueError naming the parameter or setting and its valid range.
        """

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Value]) -> None:
        """Set qpos/qvel (and anything else) of `data` from the parameters."""
        raise NotImplementedError

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        """Closed-form predictions from the compiled model and the initial state in `data` (after mj_forward).

        Returns a mapping with one entry per check name (the expected value), plus any extra quantities
        `measure`, `duration` and the envs need (prefixed with an underscore by convention).
        """
        raise NotImplementedError

    def duration(self, prediction: Mapping[str, Any]) -> float:
        """Simulated time (s) the case needs, from the predicted time scales."""
        raise NotImplementedError

    def control(self, model: mujoco.MjModel, timestep: float, nstep: int) -> np.ndarray | None:
        """Open-loop actuator controls for the run, shape (nstep, model.nu), or None (no actuators driven).

        Row i holds the controls applied during step i, i.e. over [i dt, (i + 1) dt).
        """
        return None

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        """The measured value of each check, from the trajectory."""
        raise NotImplementedError

    def simulate(
        self, model: mujoco.MjModel, data: mujoco.MjData, duration: float, *, control: np.ndarray | None = None
    ) -> Trajectory:
        """Run the case from the state in `data`: one rollout by default. Batch scenarios (Monte Carlo over
        initial states, extra runs at other settings) override it and return any object with the attributes
        `measure` needs plus ``time`` (the sample times of one run) and ``diverged_at``."""
        return harness().simulate(model, data, duration, control=control)

    def precision_domain(
        self, model: mujoco.MjModel, data: mujoco.MjData, prediction: Mapping[str, Any], precision: str
    ) -> str | None:
        """Where an engine of `precision` cannot resolve the case at all, a phrase naming the numbers; else None.

        The floors of `_roundoff_check` are linear in eps and hold while the round-off is a small share of what it
        disturbs; a scenario overrides this where a quantity every check hangs on (a restoring torque against its
        own round-off, a contact's penetration against the positions' rounding) would be off by
        `UNRESOLVED_FRACTION` of itself or more. Called on float32 engines only (`check_precision`); by default
        nothing beyond the moving bodies' advance (`rigidbench.engines.advance_error`).
        """
        return None

    # ---- lookups ------------------------------------------------------------------------------------

    @property
    def file_stem(self) -> str:
        return self.slug.replace("-", "_")

    def spec(self) -> mujoco.MjSpec:
        """A fresh MjSpec of the scenario's model file."""
        return mujoco.MjSpec.from_string(_model_xml(self.file_stem))

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        check_known(self.params, [name], self.slug)
        raise AssertionError  # unreachable

    def case(self, name: str | None) -> Case:
        """The named case (the first one if `name` is None).

        Raises
        ------
        ValueError
            If the scenario has no case of that name.
        """
        if name is None:
            return self.cases[0]
        for c in self.cases:
            if c.name == name:
                return c
        raise ValueError(
            f"unknown case '{name}' for scenario '{self.slug}'; valid: {', '.join(c.name for c in self.cases)}"
        )

    def check(self, name: str) -> Check:
        return next(c for c in self.checks if c.name == name)

    def defaults(self) -> Params:
        """Parameter defaults, read from the compiled model file."""
        return _defaults(type(self))

    def read_params(self, model: mujoco.MjModel) -> Params:
        """The parameters as compiled (what is actually simulated)."""
        return {p.name: p.target.read(model) for p in self.params}

    # ---- what the harness does with a scenario (`rigidbench.harness`; not for overriding) ----------------

    def resolve(self, case: Case, overrides: Mapping[str, object] | None = None, *, regime: bool = True) -> Params:
        """Parameters for `case`: defaults, the case's values, the user's overrides; checked, domains included
        (`rigidbench.harness.resolve`)."""
        return harness().resolve(self, case, overrides, regime=regime)

    def check_domain(self, case: Case, values: Mapping[str, Value], *, regime: bool = True) -> None:
        """Refuse parameters outside the case's regime or a domain of the theory (`rigidbench.harness.check_domain`)."""
        harness().check_domain(self, case, values, regime=regime)

    def build(self, params: Mapping[str, Value], settings: Any = None) -> mujoco.MjModel:
        """The compiled model with `params` and `settings` applied (`rigidbench.harness.build`)."""
        return harness().build(self, params, settings)

    def start(self, model: mujoco.MjModel, params: Mapping[str, Value] | None = None) -> mujoco.MjData:
        """A new MjData at the case's initial state, after mj_forward (`rigidbench.harness.start`)."""
        return harness().start(self, model, params)

    def prepare(
        self, case: str | None = None, overrides: Mapping[str, object] | None = None, settings: Any = None
    ) -> Any:
        """Resolve, compile, start and predict one case without simulating: a `rigidbench.harness.Prepared`
        (`rigidbench.harness.prepare`). `settings` is a `rigidbench.settings.Settings` or None (the reference)."""
        return harness().prepare(self, case, overrides, settings)

    def run(
        self,
        case: str | None = None,
        overrides: Mapping[str, object] | None = None,
        settings: Any = None,
        **options: Any,
    ) -> Any:
        """Simulate one case and score every check it names: a `rigidbench.harness.CaseRun`
        (`rigidbench.harness.run`, whose options are ``keep_trajectory``, ``perturb`` and ``timed``)."""
        return harness().run(self, case, overrides, settings, **options)

    def settings_record(self, model: mujoco.MjModel, settings: Any) -> dict:
        """The settings a compiled model runs with, read back in full (`rigidbench.harness.settings_record`)."""
        return harness().settings_record(model, settings)

    def check_precision(
        self, model: mujoco.MjModel, data: mujoco.MjData, prediction: Mapping[str, Any], engine: str, precision: str
    ) -> None:
        """Refuse a start that `engine`'s `precision` cannot resolve (`rigidbench.harness.check_precision`)."""
        harness().check_precision(self, model, data, prediction, engine, precision)

    def check_prediction_keys(self, prediction: Mapping[str, Any]) -> None:
        """Refuse per-check prediction entries naming no check (`rigidbench.harness.check_prediction_keys`)."""
        harness().check_prediction_keys(self, prediction)

    def roundoff_scale(self, name: str, prediction: Mapping[str, Any]) -> float:
        """The size a float32 engine's round-off of check `name` is relative to (`rigidbench.harness.roundoff_scale`;
        a scenario sets it through ``prediction["_roundoff_scale"]``, not by overriding this)."""
        return harness().roundoff_scale(self, name, prediction)

    def _scaled_check(self, name: str, prediction: Mapping[str, Any]) -> Check:
        return harness().scaled_check(self, name, prediction)

    def _roundoff_check(self, check: Check, prediction: Mapping[str, Any], precision: str, nstep: int):
        return harness().roundoff_check(self, check, prediction, precision, nstep)


def harness():
    """The harness module (`rigidbench.harness`), which runs scenarios.

    The contract never imports it by name: the dependency goes from the harness to the scenarios. Importing
    `rigidbench` (or any command that runs a scenario) has loaded it already; if nothing has, it is loaded here.
    """
    global _HARNESS
    if _HARNESS is None:
        _HARNESS = importlib.import_module("rigidbench.harness")
    return _HARNESS


_HARNESS = None


@functools.cache
def _model_xml(stem: str) -> str:
    return importlib.resources.files("rigidbench.models").joinpath(f"{stem}.xml").read_text()


@functools.cache
def _defaults(cls: type[Scenario]) -> Params:
    scenario = cls()
    with BUILD_LOCK:
        model = scenario.spec().compile()
    return scenario.read_params(model)
