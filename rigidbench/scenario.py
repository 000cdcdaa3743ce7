"""The scenario core (DESIGN.md): model, parameters, cases, observables, predictions, checks.

A scenario is an MJCF file plus a `Scenario` subclass with the same stem, in ``envs/``. The subclass says
which numbers are public parameters, which named cases exist, how to set the initial state, what to measure
from a trajectory and what theory (``analytic/``) predicts for it. Everything else (resolving parameters,
compiling through `MjSpec`, reading values back, running, scoring, recording) lives here once, and the CLI,
the gymnasium env, the dm_env task and the tests are views of it.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import importlib.resources
import json
import math
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import mujoco
import numpy as np

from rigidbench import forces
from rigidbench.engines import use as use_engine
from rigidbench.params import Bound, Param, Range, Value, check_known
from rigidbench.settings import DERIVED_TEXT, Settings, read_settings, skip_idle_stages
from rigidbench.simulate import Timing, Trajectory, check_run_size, simulate, steps_for, time_calls, time_stepping

Params = dict[str, Value]
_BUILD_LOCK = threading.RLock()
# A case value is a number, or a function of the other resolved parameters (e.g. a steady-precession rate).
CaseValue = Value | Callable[[Mapping[str, Value]], Value]


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
        Relative error ``|m - e| / |e|`` or absolute error ``|m - e|``.
    reason : str
        Where the tolerance comes from (integrator order and step, contact stiffness, statistics, ...).
    theory : str
        THEORY.md entry and seed location of the prediction.
    """

    name: str
    unit: str
    tolerance: float
    kind: str
    reason: str
    theory: str

    def __post_init__(self) -> None:
        if self.kind not in ("rel", "abs"):
            raise ValueError(f"check {self.name}: kind must be 'rel' or 'abs', not {self.kind!r}")

    def error(self, measured: float, expected: float) -> float:
        diff = abs(measured - expected)
        if self.kind == "abs":
            return diff
        return diff / abs(expected) if expected != 0 else math.inf


# A check whose float32 round-off floor reaches this fraction of the quantity itself says nothing about the physics
# at that precision (`Scenario._roundoff_check`): it is reported as unresolved instead of passing on a tolerance
# that could not fail.
UNRESOLVED_FRACTION = 0.1

# The prediction's entries keyed by check name (`Scenario.check_prediction_keys`): a tolerance that depends on the
# run (`Scenario._scaled_check`), and a float32 engine's round-off scale, secular quantities and derived floors
# (`Scenario.roundoff_scale`, `Scenario._roundoff_check`).
PER_CHECK = ("_tolerance", "_roundoff_scale", "_roundoff_secular", "_roundoff_eps")


@dataclass(frozen=True)
class Outcome:
    """One scored check: a result row without the run's context."""

    check: Check
    measured: float
    expected: float
    # The engine's float precision alone could move the quantity by `UNRESOLVED_FRACTION` of itself or more
    # (`Scenario._roundoff_check`): reported, never scored.
    unresolved: bool = False

    @property
    def error(self) -> float:
        return self.check.error(self.measured, self.expected)

    @property
    def passed(self) -> bool:
        return bool(np.isfinite(self.error) and self.error <= self.check.tolerance)


@dataclass
class CaseRun:
    """Everything one simulated case produced."""

    scenario: str
    case: str
    params: Params
    settings: dict
    outcomes: list[Outcome]
    diverged_at: float | None
    duration: float
    nstep: int
    wall_time: float
    trajectory: Trajectory | None = field(default=None, repr=False)
    prediction: Mapping[str, Any] | None = field(default=None, repr=False)
    timing: Timing | None = None


@dataclass
class Prepared:
    """A case ready to simulate: resolved, compiled, started and predicted, with its run length checked."""

    case: Case
    params: Params
    model: mujoco.MjModel = field(repr=False)
    data: mujoco.MjData = field(repr=False)
    prediction: Mapping[str, Any] = field(repr=False)
    duration: float
    nstep: int


class Scenario:
    """Base class of every scenario. Subclasses set the class attributes and implement the hooks.

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

    # ---- hooks -------------------------------------------------------------------------------------------

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
        return simulate(model, data, duration, control=control)

    def _scaled_check(self, name: str, prediction: Mapping[str, Any]) -> Check:
        """The check, with its tolerance replaced by ``prediction["_tolerance"][name]`` when the prediction
        gives one: a bound that depends on the run (a Monte Carlo error ~ n^-1/2, a contact-stiffness bound
        ~ k^-1/2). The check's `reason` must state the formula."""
        check = self.check(name)
        tolerance = prediction.get("_tolerance", {}).get(name)
        return check if tolerance is None else dataclasses.replace(check, tolerance=float(tolerance))

    def roundoff_scale(self, name: str, prediction: Mapping[str, Any]) -> float:
        """The size of check `name`'s quantity, in its unit, that a float32 engine's round-off is relative to
        (`rigidbench.engines.roundoff_floor`): 1 for a relative error or a dimensionless ratio, else the expected
        value's size (at least 1 rad for an angle, whose rounding is absolute: a relative check of an angle theta
        has scale max(theta, 1 rad) / theta).

        A scenario gives the scale as ``prediction["_roundoff_scale"][name]`` where the quantity is expected to be 0
        in a unit (e.g. the ball's speed for a slip that should vanish), where its motion amplifies round-off (a
        spin near the separatrix), or where its measurement subtracts large numbers (a spacing between positions far
        from the origin), in units of the quantity. A quantity read from a coordinate that a steady motion advances
        every step is named in ``prediction["_roundoff_secular"]`` (its floor grows like the step count). A floor the
        scenario derives itself, proportional to the precision's eps, is ``prediction["_roundoff_eps"][name]`` in
        units of eps (or, where it is not proportional, a function of eps giving the floor), with
        ``prediction["_roundoff_eps_rule"]`` saying where it comes from (`_roundoff_check`).
        """
        check = self.check(name)
        given = prediction.get("_roundoff_scale", {}).get(name)
        if given is not None:
            return float(given)
        if check.unit == "rad":
            # An angle is read from an orientation whose numbers are O(1): float32 rounds it to an absolute
            # ~eps rad, however small the angle, so a relative check of a small angle theta sees 1 rad / theta.
            size = abs(float(prediction[name]))
            if check.kind == "rel":
                return max(size, 1.0) / size if size > 0 else 1.0
            return max(size, 1.0)
        if check.kind == "rel" or check.unit == "1":
            return 1.0
        return abs(float(prediction[name]))

    def _roundoff_check(
        self, check: Check, prediction: Mapping[str, Any], precision: str, nstep: int
    ) -> tuple[Check, bool]:
        """The check as scored on an engine of `precision`, and whether that precision resolves it at all.

        On float64 the check is unchanged. On float32 its tolerance gains the round-off floor of float32 over the
        run (`rigidbench.engines.roundoff_floor`), stated in its reason; where that floor reaches
        `UNRESOLVED_FRACTION` of the quantity itself (1 for a relative or dimensionless check, else the expected
        value's size), float32 alone could move it that much: the check is reported as unresolved, not scored.
        """
        from rigidbench.engines import roundoff_floor

        secular = check.name in prediction.get("_roundoff_secular", ())
        floor, rule = roundoff_floor(precision, nstep, self.roundoff_scale(check.name, prediction), secular=secular)
        if floor == 0:
            return check, False
        # A scenario that derives its own round-off floor as a multiple of the precision's eps (the float64 floor
        # its tolerance already carries, e.g. a torque computed from rounded world positions) has it scaled to the
        # engine's eps; the larger of the two floors counts.
        # A floor that is not proportional to eps is given as a function of eps (absolute, in the check's units).
        per_eps = prediction.get("_roundoff_eps", {}).get(check.name)
        if per_eps is not None:
            eps = float(np.finfo(np.dtype(precision)).eps)
            derived = float(per_eps(eps)) if callable(per_eps) else float(per_eps) * eps
            if derived > floor:
                floor = derived
                rule = f"the scenario's floor {derived / eps:.3g} eps ({prediction['_roundoff_eps_rule']})"
        size = 1.0 if check.kind == "rel" or check.unit == "1" else abs(float(prediction[check.name]))
        unresolved = size > 0 and floor >= UNRESOLVED_FRACTION * size
        reason = f"{check.reason}; + {precision} round-off {rule} = {floor:.3g} (float64 tolerance {check.tolerance:g})"
        if unresolved:
            reason += f": at least {UNRESOLVED_FRACTION:g} of the quantity, so {precision} cannot resolve it"
        return dataclasses.replace(check, tolerance=check.tolerance + floor, reason=reason), unresolved

    # ---- the core ---------------------------------------------------------------------------------------

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

    def check_prediction_keys(self, prediction: Mapping[str, Any]) -> None:
        """Refuse a prediction whose per-check entries (`PER_CHECK`: tolerances, round-off scales and floors) name a
        check this scenario does not have: a misspelt or renamed key would silently drop what it carries (a
        subclass renaming a check must rename it in each of them).

        Raises
        ------
        TypeError
            Naming the entry and the unknown check.
        """
        names = {c.name for c in self.checks}
        for entry in PER_CHECK:
            unknown = sorted(set(prediction.get(entry, ())) - names)
            if unknown:
                raise TypeError(
                    f"scenario '{self.slug}': prediction[{entry!r}] names {unknown}, not checks of this scenario "
                    f"({sorted(names)})"
                )

    def check(self, name: str) -> Check:
        return next(c for c in self.checks if c.name == name)

    def defaults(self) -> Params:
        """Parameter defaults, read from the compiled model file."""
        return _defaults(type(self))

    def resolve(self, case: Case, overrides: Mapping[str, object] | None = None) -> Params:
        """Parameters for `case`: model defaults, then the case's values, then the user's overrides;
        derived case values are computed last from the others, unless the user set them.

        Raises
        ------
        ValueError
            For an unknown parameter, or one of the wrong shape, not finite, or out of its range.
        """
        overrides = dict(overrides or {})
        check_known(self.params, overrides, self.slug)
        values: dict[str, Value] = dict(self.defaults())
        derived = {}
        for name, v in case.values.items():
            if callable(v):
                derived[name] = v
            else:
                values[name] = v
        for name, v in overrides.items():
            values[name] = self.param(name).check(v)
        for p in self.params:
            if p.name not in derived or p.name in overrides:
                values[p.name] = p.check(values[p.name])
        for name, fn in derived.items():
            if name not in overrides:
                values[name] = self.param(name).check(fn(values))
        for p in self.params:
            p.check_within(values[p.name], values)
        self.validate(values)
        self.check_domain(case, values)
        return values

    def check_domain(self, case: Case, values: Mapping[str, Value]) -> None:
        """Refuse parameters outside the case's regime or a domain of the theory (`OutsideDomain`).

        Raises
        ------
        OutsideDomain
            Naming the parameter(s), their values, the theory and its condition.
        """
        for name, bound in case.ranges.items():
            p = self.param(name)
            interval = bound.range(values) if isinstance(bound, Bound) else bound
            if any(float(x) not in interval for x in np.ravel(values[name])):
                unit = "" if p.unit == "1" else f" {p.unit}"
                where = f"{bound.text} = {interval}" if isinstance(bound, Bound) else str(interval)
                raise OutsideDomain(
                    f"parameter '{name}' = {_fmt(values[name])}{unit} is outside the regime of case '{case.name}', "
                    f"{where}{unit}: {case.regime}",
                    f"case {case.name}: {name}",
                )
        for domain in self.domains:
            if not domain.applies(case.name):
                continue
            outside = domain.test(values)
            if outside:
                raise OutsideDomain(
                    f"{outside} is outside the domain of {domain.theory} ({domain.name}): {domain.text}", domain.name
                )

    def build(self, params: Mapping[str, Value], settings: Settings | None = None) -> mujoco.MjModel:
        """Compile the model with `params` applied through MjSpec and `settings` on top, with the pipeline stages
        that can do nothing in it switched off (`rigidbench.settings.skip_idle_stages`: results bit for bit the
        same, steps 20-30 % cheaper where nothing collides).

        Raises
        ------
        ValueError
            If MuJoCo refuses the model (the message is MuJoCo's, prefixed with the scenario), or
            `check_model` does.
        """
        # MuJoCo parses and compiles without the GIL and does not document its compiler as thread-safe; the
        # runner builds cases from several threads, so one build at a time (a few ms each).
        with _BUILD_LOCK:
            spec = self.spec()
            for p in self.params:
                p.target.apply(spec, params[p.name])
            self._apply_derived(spec, params, settings)
            if settings is not None:
                settings.apply(spec)
            try:
                model = spec.compile()
            except ValueError as exc:  # MuJoCo's compiler errors
                raise ValueError(f"scenario '{self.slug}': MuJoCo refused the model: {exc}") from None
        self.check_model(model)
        forces.attach(model)  # the forces MuJoCo has no element for (rigidbench.forces), if the model declares any
        skip_idle_stages(model)
        engine = settings.engine_object() if settings is not None else None
        if engine is not None:
            try:
                engine.check(model)  # refuse what the engine lacks, before anything is simulated
            except ValueError as exc:
                raise type(exc)(f"scenario '{self.slug}': {exc}") from None
        return model

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

    def check_precision(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        prediction: Mapping[str, Any],
        engine: str,
        precision: str,
    ) -> None:
        """Refuse a start that `engine`'s `precision` cannot resolve: a moving body whose step the positions'
        rounding swamps (`rigidbench.engines.advance_error`), or the scenario's own `precision_domain`. Every check,
        and an env's every reward, would measure the rounding, not the physics. Nothing on float64.

        Raises
        ------
        rigidbench.engines.EngineRefused
            Naming the scenario, the engine and its precision, and the numbers.
        """
        from rigidbench.engines import EngineRefused, advance_error

        if precision == "float64":
            return
        error, where = advance_error(model, data, precision)
        if error >= UNRESOLVED_FRACTION:  # the rounding is that share of each step, as a check's floor of itself
            raise EngineRefused(
                f"scenario '{self.slug}': engine {engine} ({precision}) cannot resolve this motion: {where} "
                f"(resolvable: below {UNRESOLVED_FRACTION:g}, i.e. |v| dt >= {0.5 / UNRESOLVED_FRACTION:g} eps |x|)"
            )
        reason = self.precision_domain(model, data, prediction, precision)
        if reason is not None:
            raise EngineRefused(
                f"scenario '{self.slug}': engine {engine} ({precision}) cannot resolve this case: {reason}"
            )

    def settings_record(self, model: mujoco.MjModel, settings: Settings | None) -> dict:
        """The settings a compiled model runs with, read back in full (`read_settings`), and the engine's
        record (name, version, device, precision) that every result row carries."""
        from rigidbench.engines import Engine

        engine = (settings.engine_object() if settings is not None else None) or Engine()
        return {**read_settings(model), **engine.record()}

    def _apply_derived(self, spec: mujoco.MjSpec, params: Mapping[str, Value], settings: Settings | None) -> None:
        """Write the settings that follow the parameters into `spec`, and their rules as the model's custom text
        `settings.DERIVED_TEXT` (read back with the settings of every result)."""
        from rigidbench import pulse

        derived = self.reference_settings(params)
        applied = {}
        for name, d in derived.items():
            if not (math.isfinite(d.value) and d.value > 0):
                raise ValueError(f"scenario '{self.slug}': derived {name} = {d.value!r} ({d.rule}) is not positive")
            if name == "timestep":
                if settings is not None and settings.timestep is not None:
                    continue  # the profile or the user fixed it
                spec.option.timestep = d.value
            elif name == "pulse_duration":
                spec.numeric(pulse.PULSE_DURATION).data = [d.value]
            elif name == "solver_tolerance":
                spec.option.tolerance = d.value  # a profile's or the user's tolerance (applied after) still wins
            else:
                self.apply_derived(spec, name, d.value)
            applied[name] = {"value": d.value, "rule": d.rule}
        if applied:
            spec.add_text(name=DERIVED_TEXT, data=json.dumps(applied, sort_keys=True))

    def read_params(self, model: mujoco.MjModel) -> Params:
        """The parameters as compiled (what is actually simulated)."""
        return {p.name: p.target.read(model) for p in self.params}

    def start(self, model: mujoco.MjModel, params: Mapping[str, Value] | None = None) -> mujoco.MjData:
        """A new MjData at the case's initial state, with derived quantities computed (mj_forward)."""
        data = mujoco.MjData(model)
        self.initial_state(model, data, self.read_params(model) if params is None else params)
        mujoco.mj_forward(model, data)
        return data

    def prepare(
        self, case: str | None = None, overrides: Mapping[str, object] | None = None, settings: Settings | None = None
    ) -> Prepared:
        """Resolve, compile, start and predict one case, and check its run length, without simulating.

        Raises
        ------
        ValueError
            For invalid parameters or settings, a set outside the theory's domain (`OutsideDomain`), or a run
            longer than the step or memory limits (`rigidbench.simulate.check_run_size`).
        """
        c = self.case(case)
        params = self.resolve(c, overrides)
        model = self.build(params, settings)
        actual = self.read_params(model)
        data = self.start(model, actual)
        engine = settings.engine_object() if settings is not None and settings.engine is not None else None
        if engine is not None and engine.precision != "float64":
            # Predict from what the engine simulates: the model and initial state rounded to its precision
            # (`rigidbench.engines.stored`); the parameters reported are read back from it.
            from rigidbench.engines import stored

            model, data = stored(model, data, engine.precision)
            actual = self.read_params(model)
        prediction = self.predict(model, data)
        self.check_prediction_keys(prediction)
        if engine is not None:
            self.check_precision(model, data, prediction, engine.name, engine.precision)
        duration = float(self.duration(prediction))
        if not (math.isfinite(duration) and duration > 0):
            raise ValueError(
                f"scenario '{self.slug}:{c.name}': the predicted run length {duration!r} s is not positive"
            )
        nstep = steps_for(duration, model.opt.timestep)
        check_run_size(model, nstep)
        return Prepared(c, actual, model, data, prediction, duration, nstep)

    def run(
        self,
        case: str | None = None,
        overrides: Mapping[str, object] | None = None,
        settings: Settings | None = None,
        *,
        keep_trajectory: bool = False,
        perturb: Callable[[mujoco.MjModel], None] | None = None,
        timed: bool = False,
    ) -> CaseRun:
        """Simulate one case and score every check it names.

        Parameters
        ----------
        timed : bool
            Also measure what the stepping costs (`rigidbench.simulate.time_stepping`: only the stepping, never
            the prediction or the measurement; a scenario with its own `simulate` is timed by whole calls).
        perturb : callable, optional
            Edits a copy of the compiled model in place before it is simulated (`rigidbench.power`): the
            prediction, the controls and the measurement keep the unperturbed model, so a check that fails shows
            the benchmark can see the edit.

        Raises
        ------
        ValueError
            For invalid parameters or settings (before anything is simulated); see `prepare`.
        """
        import time as _time

        prep = self.prepare(case, overrides, settings)
        model, data, prediction = prep.model, prep.data, prep.prediction
        control = self.control(model, model.opt.timestep, prep.nstep)
        simulated = model
        if perturb is not None:
            simulated = copy.copy(model)
            perturb(simulated)
        engine = settings.engine_object() if settings is not None else None
        with use_engine(engine):  # `rigidbench.simulate` steps with it; scenario code never branches on it
            c0, t0 = _time.process_time(), _time.perf_counter()
            traj = self.simulate(simulated, data, prep.duration, control=control)
            wall = _time.perf_counter() - t0
            cpu = _time.process_time() - c0
            timing = None
            if timed and traj.diverged_at is None:
                if type(self).simulate is Scenario.simulate and engine is None:
                    timing = time_stepping(simulated, traj, control, first=(cpu, wall))
                else:  # a scenario's own simulate, or a batched engine: whole calls (per-world cost of a batch)
                    timing = time_calls(
                        lambda: self.simulate(simulated, data, prep.duration, control=control), steps=prep.nstep
                    )
        outcomes = []
        if traj.diverged_at is None:
            measured = self.measure(model, traj, prediction)
            precision = engine.precision if engine is not None else "float64"
            for name in prep.case.checks:
                check, unresolved = self._roundoff_check(
                    self._scaled_check(name, prediction), prediction, precision, len(traj.time) - 1
                )
                outcomes.append(Outcome(check, float(measured[name]), float(prediction[name]), unresolved))
        return CaseRun(
            scenario=self.slug,
            case=prep.case.name,
            params=prep.params,
            settings=self.settings_record(model, settings),
            outcomes=outcomes,
            diverged_at=traj.diverged_at,
            duration=prep.duration,
            nstep=len(traj.time) - 1,
            wall_time=wall,
            trajectory=traj if keep_trajectory else None,
            prediction=prediction if keep_trajectory else None,
            timing=timing,
        )


def _fmt(value: object) -> str:
    if isinstance(value, (list, tuple, np.ndarray)):
        return ",".join(f"{float(x):g}" for x in np.ravel(value))
    return f"{float(value):g}"


@functools.cache
def _model_xml(stem: str) -> str:
    return importlib.resources.files("rigidbench.models").joinpath(f"{stem}.xml").read_text()


@functools.cache
def _defaults(cls: type[Scenario]) -> Params:
    scenario = cls()
    with _BUILD_LOCK:
        model = scenario.spec().compile()
    return scenario.read_params(model)
