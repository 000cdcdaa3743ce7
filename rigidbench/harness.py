"""The harness: what is done with a scenario (resolve, build, start, predict, run, score), written once.

A scenario (`rigidbench.contract.Scenario`) says what its parameters, cases, checks and theory are; this module
does everything else, the same way for all of them: resolving parameters (defaults, case values, the user's
``--set``, ranges, regimes and domains), compiling the model through MjSpec with the settings and the settings that
follow the parameters, starting and predicting, refusing what an engine's precision cannot resolve, simulating on
the engine in use, and scoring every check (with a float32 engine's round-off floor where one applies).

It imports the contract and the scenarios' hooks run from here, never the reverse: every scenario's ``run``,
``prepare``, ``resolve``, ``build``, ... methods hand the call to the functions below (`rigidbench.contract`).
The CLI, the gymnasium envs, census, power, sweeps and the tests are views of these functions.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import time as _time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from rigidbench import forces, pulse
from rigidbench.contract import BUILD_LOCK, PER_CHECK, UNRESOLVED_FRACTION, Case, Check, OutsideDomain, Params, Scenario
from rigidbench.engines.base import Engine, EngineRefused
from rigidbench.engines.base import use as use_engine
from rigidbench.engines.precision import advance_error, roundoff_floor, stored, stored_model, stored_state
from rigidbench.params import Bound, Value, check_known
from rigidbench.settings import DERIVED_TEXT, Settings, read_settings, skip_idle_stages
from rigidbench.simulate import Timing, Trajectory, check_run_size, simulate, steps_for, time_calls, time_stepping

__all__ = [
    "PER_CHECK",
    "UNRESOLVED_FRACTION",
    "CaseRun",
    "Outcome",
    "Prepared",
    "build",
    "check_domain",
    "check_precision",
    "check_prediction_keys",
    "prepare",
    "resolve",
    "roundoff_check",
    "roundoff_scale",
    "run",
    "scaled_check",
    "settings_record",
    "simulate",
    "start",
]


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


def scaled_check(scenario: Scenario, name: str, prediction: Mapping[str, Any]) -> Check:
    """The check, with its tolerance replaced by ``prediction["_tolerance"][name]`` when the prediction
    gives one: a bound that depends on the run (a Monte Carlo error ~ n^-1/2, a contact-stiffness bound
    ~ k^-1/2), and its relative floor by ``prediction["_floor"][name]`` (`Check.floor`). The check's `reason`
    must state the formula."""
    check = scenario.check(name)
    tolerance = prediction.get("_tolerance", {}).get(name)
    floor = prediction.get("_floor", {}).get(name)
    if tolerance is not None:
        check = dataclasses.replace(check, tolerance=float(tolerance))
    if floor is not None:
        check = dataclasses.replace(check, floor=float(floor))
    return check


def roundoff_scale(scenario: Scenario, name: str, prediction: Mapping[str, Any]) -> float:
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
    check = scenario.check(name)
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


def roundoff_check(
    scenario: Scenario, check: Check, prediction: Mapping[str, Any], precision: str, nstep: int
) -> tuple[Check, bool]:
    """The check as scored on an engine of `precision`, and whether that precision resolves it at all.

    On float64 the check is unchanged. On float32 its tolerance gains the round-off floor of float32 over the
    run (`rigidbench.engines.roundoff_floor`), stated in its reason; where that floor reaches
    `UNRESOLVED_FRACTION` of the quantity itself (1 for a relative or dimensionless check, else the expected
    value's size), float32 alone could move it that much: the check is reported as unresolved, not scored.
    """

    secular = check.name in prediction.get("_roundoff_secular", ())
    floor, rule = roundoff_floor(precision, nstep, roundoff_scale(scenario, check.name, prediction), secular=secular)
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


def check_prediction_keys(scenario: Scenario, prediction: Mapping[str, Any]) -> None:
    """Refuse a prediction whose per-check entries (`PER_CHECK`: tolerances, round-off scales and floors) name a
    check this scenario does not have: a misspelt or renamed key would silently drop what it carries (a
    subclass renaming a check must rename it in each of them).

    Raises
    ------
    TypeError
        Naming the entry and the unknown check.
    """
    names = {c.name for c in scenario.checks}
    for entry in PER_CHECK:
        unknown = sorted(set(prediction.get(entry, ())) - names)
        if unknown:
            raise TypeError(
                f"scenario '{scenario.slug}': prediction[{entry!r}] names {unknown}, not checks of this scenario "
                f"({sorted(names)})"
            )


def resolve(
    scenario: Scenario, case: Case, overrides: Mapping[str, object] | None = None, *, regime: bool = True
) -> Params:
    """Parameters for `case`: model defaults, then the case's values, then the user's overrides;
    derived case values are computed last from the others, unless the user set them. With ``regime=False`` the
    case's regime (`Case.ranges`: where its checks' closed forms hold) is not applied, the parameters' ranges and the
    theory's domains are: for a control task that moves a parameter over its whole range and scores its own
    measurement, not the case's checks (`rigidbench.envs.base.ScenarioEnv.case_regime`).

    Raises
    ------
    ValueError
        For an unknown parameter, or one of the wrong shape, not finite, or out of its range.
    """
    overrides = dict(overrides or {})
    check_known(scenario.params, overrides, scenario.slug)
    values: dict[str, Value] = dict(scenario.defaults())
    derived = {}
    for name, v in case.values.items():
        if callable(v):
            derived[name] = v
        else:
            values[name] = v
    for name, v in overrides.items():
        values[name] = scenario.param(name).check(v)
    for p in scenario.params:
        if p.name not in derived or p.name in overrides:
            values[p.name] = p.check(values[p.name])
    for name, fn in derived.items():
        if name not in overrides:
            values[name] = scenario.param(name).check(fn(values))
    for p in scenario.params:
        p.check_within(values[p.name], values)
    scenario.validate(values)
    check_domain(scenario, case, values, regime=regime)
    return values


def check_domain(scenario: Scenario, case: Case, values: Mapping[str, Value], *, regime: bool = True) -> None:
    """Refuse parameters outside the case's regime (unless ``regime=False``) or a domain of the theory
    (`OutsideDomain`).

    Raises
    ------
    OutsideDomain
        Naming the parameter(s), their values, the theory and its condition.
    """
    for name, bound in case.ranges.items() if regime else ():
        p = scenario.param(name)
        interval = bound.range(values) if isinstance(bound, Bound) else bound
        if any(float(x) not in interval for x in np.ravel(values[name])):
            unit = "" if p.unit == "1" else f" {p.unit}"
            where = f"{bound.text} = {interval}" if isinstance(bound, Bound) else str(interval)
            raise OutsideDomain(
                f"parameter '{name}' = {_fmt(values[name])}{unit} is outside the regime of case '{case.name}', "
                f"{where}{unit}: {case.regime}",
                f"case {case.name}: {name}",
            )
    for domain in scenario.domains:
        if not domain.applies(case.name):
            continue
        outside = domain.test(values)
        if outside:
            raise OutsideDomain(
                f"{outside} is outside the domain of {domain.theory} ({domain.name}): {domain.text}", domain.name
            )


def build(scenario: Scenario, params: Mapping[str, Value], settings: Settings | None = None) -> mujoco.MjModel:
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
    with BUILD_LOCK:
        spec = scenario.spec()
        for p in scenario.params:
            p.target.apply(spec, params[p.name])
        apply_derived(scenario, spec, params, settings)
        if settings is not None:
            settings.apply(spec)
        try:
            model = spec.compile()
        except ValueError as exc:  # MuJoCo's compiler errors
            raise ValueError(f"scenario '{scenario.slug}': MuJoCo refused the model: {exc}") from None
    scenario.check_model(model)
    forces.attach(model)  # the forces MuJoCo has no element for (rigidbench.forces), if the model declares any
    skip_idle_stages(model)
    engine = settings.engine_object() if settings is not None else None
    if engine is not None:
        try:
            engine.check(model)  # refuse what the engine lacks, before anything is simulated
        except ValueError as exc:
            raise type(exc)(f"scenario '{scenario.slug}': {exc}") from None
    return model


def check_precision(
    scenario: Scenario,
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

    if precision == "float64":
        return
    error, where = advance_error(model, data, precision)
    if error >= UNRESOLVED_FRACTION:  # the rounding is that share of each step, as a check's floor of itself
        raise EngineRefused(
            f"scenario '{scenario.slug}': engine {engine} ({precision}) cannot resolve this motion: {where} "
            f"(resolvable: below {UNRESOLVED_FRACTION:g}, i.e. |v| dt >= {0.5 / UNRESOLVED_FRACTION:g} eps |x|)"
        )
    reason = scenario.precision_domain(model, data, prediction, precision)
    if reason is not None:
        raise EngineRefused(
            f"scenario '{scenario.slug}': engine {engine} ({precision}) cannot resolve this case: {reason}"
        )


def settings_record(model: mujoco.MjModel, settings: Settings | None) -> dict:
    """The settings a compiled model runs with, read back in full (`read_settings`), and the engine's
    record (name, version, device, precision) that every result row carries."""

    engine = (settings.engine_object() if settings is not None else None) or Engine()
    return {**read_settings(model), **engine.record()}


def apply_derived(
    scenario: Scenario, spec: mujoco.MjSpec, params: Mapping[str, Value], settings: Settings | None
) -> None:
    """Write the settings that follow the parameters into `spec`, and their rules as the model's custom text
    `settings.DERIVED_TEXT` (read back with the settings of every result)."""

    derived = scenario.reference_settings(params)
    applied = {}
    for name, d in derived.items():
        if not (math.isfinite(d.value) and d.value > 0):
            raise ValueError(f"scenario '{scenario.slug}': derived {name} = {d.value!r} ({d.rule}) is not positive")
        if name == "timestep":
            if settings is not None and settings.timestep is not None:
                continue  # the profile or the user fixed it
            spec.option.timestep = d.value
        elif name == "pulse_duration":
            spec.numeric(pulse.PULSE_DURATION).data = [d.value]
        elif name == "solver_tolerance":
            spec.option.tolerance = d.value  # a profile's or the user's tolerance (applied after) still wins
        else:
            scenario.apply_derived(spec, name, d.value)
        applied[name] = {"value": d.value, "rule": d.rule}
    if applied:
        spec.add_text(name=DERIVED_TEXT, data=json.dumps(applied, sort_keys=True))


def start(scenario: Scenario, model: mujoco.MjModel, params: Mapping[str, Value] | None = None) -> mujoco.MjData:
    """A new MjData at the case's initial state, with derived quantities computed (mj_forward)."""
    data = mujoco.MjData(model)
    scenario.initial_state(model, data, scenario.read_params(model) if params is None else params)
    mujoco.mj_forward(model, data)
    return data


def prepare(
    scenario: Scenario,
    case: str | None = None,
    overrides: Mapping[str, object] | None = None,
    settings: Settings | None = None,
) -> Prepared:
    """Resolve, compile, start and predict one case, and check its run length, without simulating.

    Raises
    ------
    ValueError
        For invalid parameters or settings, a set outside the theory's domain (`OutsideDomain`), or a run
        longer than the step or memory limits (`rigidbench.simulate.check_run_size`).
    """
    c = scenario.case(case)
    params = resolve(scenario, c, overrides)
    model = build(scenario, params, settings)
    actual = scenario.read_params(model)
    data = start(scenario, model, actual)
    engine = settings.engine_object() if settings is not None and settings.engine is not None else None
    if engine is not None and engine.precision != "float64":
        # Predict from what the engine simulates: the model and initial state rounded to its precision
        # (`rigidbench.engines.stored`); the parameters reported are read back from it.

        model, data = stored(model, data, engine.precision)
        actual = scenario.read_params(model)
    prediction = scenario.predict(model, data)
    check_prediction_keys(scenario, prediction)
    if engine is not None:
        check_precision(scenario, model, data, prediction, engine.name, engine.precision)
    duration = float(scenario.duration(prediction))
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(
            f"scenario '{scenario.slug}:{c.name}': the predicted run length {duration!r} s is not positive"
        )
    nstep = steps_for(duration, model.opt.timestep)
    check_run_size(model, nstep)
    return Prepared(c, actual, model, data, prediction, duration, nstep)


def run(
    scenario: Scenario,
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
        the benchmark can see the edit. Where its ``from_params`` attribute is true (a parameter the scenario
        computes the start state or the controls from: a platform's rate, a cushion's height), the simulated start
        state and controls are computed from the edited copy instead; the prediction and the measurement still
        keep the unperturbed model and start.

    Raises
    ------
    ValueError
        For invalid parameters or settings (before anything is simulated); see `prepare`.
    """

    prep = prepare(scenario, case, overrides, settings)
    model, data, prediction = prep.model, prep.data, prep.prediction
    control = scenario.control(model, model.opt.timestep, prep.nstep)
    simulated = model
    engine = settings.engine_object() if settings is not None else None
    if perturb is not None:
        simulated = copy.copy(model)
        perturb(simulated)
        if getattr(perturb, "from_params", False):
            forces.attach(simulated)
            data = start(scenario, simulated)  # the parameters read back from the edited copy
            if engine is not None and engine.precision != "float64":
                data = stored_state(simulated, data, engine.precision)
            control = scenario.control(simulated, simulated.opt.timestep, prep.nstep)
    with use_engine(engine):  # `rigidbench.simulate` steps with it; scenario code never branches on it
        c0, t0 = _time.process_time(), _time.perf_counter()
        traj = scenario.simulate(simulated, data, prep.duration, control=control)
        wall = _time.perf_counter() - t0
        cpu = _time.process_time() - c0
        timing = None
        if timed and traj.diverged_at is None:
            if type(scenario).simulate is Scenario.simulate and engine is None:
                timing = time_stepping(simulated, traj, control, first=(cpu, wall))
            else:  # a scenario's own simulate, or a batched engine: whole calls (per-world cost of a batch)
                timing = time_calls(
                    lambda: scenario.simulate(simulated, data, prep.duration, control=control), steps=prep.nstep
                )
    outcomes = []
    if traj.diverged_at is None:
        measured = scenario.measure(model, traj, prediction)
        precision = engine.precision if engine is not None else "float64"
        for name in prep.case.checks:
            check, unresolved = roundoff_check(
                scenario, scaled_check(scenario, name, prediction), prediction, precision, len(traj.time) - 1
            )
            outcomes.append(Outcome(check, float(measured[name]), float(prediction[name]), unresolved))
    return CaseRun(
        scenario=scenario.slug,
        case=prep.case.name,
        params=prep.params,
        settings=settings_record(model, settings),
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


# ---- the gymnasium envs' side (`rigidbench.envs.base.ScenarioEnv` calls these through `contract.harness()`) ------


def settings_for(profile_name: str, *, integrator: str | None = None, timestep: float | None = None) -> Settings:
    """The settings of an env: the named profile with the env's own integrator and timestep on top.

    Raises
    ------
    ValueError
        For an unknown profile, integrator, or a timestep outside (0, `rigidbench.settings.MAX_TIMESTEP`] s.
    """
    from rigidbench.settings import profile

    return profile(profile_name).merged(Settings(integrator=integrator, timestep=timestep))


def env_model(scenario: Scenario, params: Mapping[str, Value], settings: Settings, precision: str) -> mujoco.MjModel:
    """The model an env steps: built (`build`) and stored in `precision` (`rigidbench.engines.stored_model`)."""

    return stored_model(build(scenario, params, settings), precision)


def env_start(scenario: Scenario, model: mujoco.MjModel, precision: str, engine: str) -> tuple:
    """An env's episode start for a compiled `model`: (parameters read back, the initial MjData, the prediction, the
    episode's duration in s, the settings record), the state stored in `precision` and checked resolvable by it.

    Raises
    ------
    rigidbench.engines.EngineRefused
        If `engine`'s `precision` cannot resolve the start (`check_precision`).
    """

    actual = scenario.read_params(model)
    data = start(scenario, model, actual)
    if precision != "float64":
        data = stored_state(model, data, precision)
    prediction = scenario.predict(model, data)
    check_precision(scenario, model, data, prediction, engine, precision)
    return (actual, data, prediction, float(scenario.duration(prediction)), read_settings(model))


def attach_forces(model: mujoco.MjModel) -> None:
    """Attach the forces MuJoCo has no element for (`rigidbench.forces.attach`): cheap and idempotent."""
    forces.attach(model)
