"""Fidelity sweeps: every check's error over a grid of integrators x timesteps (x any numeric parameter), and the
observed order of convergence next to the integrator's nominal order.

A sweep point is one case simulated under one `Settings` (integrator, timestep) and, optionally, one value of a
swept parameter (e.g. a contact ``stiffness``). Each point yields the ordinary result rows (`results.rows_of`:
measured, expected, error, the settings read back from the compiled model, the parameters as compiled, the
MuJoCo version) plus a ``point`` record naming where in the grid it sits. Points run in worker processes
(`concurrent.futures.ProcessPoolExecutor`); results are kept in grid order whatever order they finish in.

The observed order is fitted by `observed_order`; its rule is stated there.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from rigidbench import registry
from rigidbench.results import DIVERGED, FAIL, PASS, _jsonable, atomic_write, rows_of
from rigidbench.settings import INTEGRATORS, MAX_TIMESTEP, Settings

# Nominal global order of accuracy of MuJoCo's integrators. Euler is semi-implicit (symplectic) Euler: first
# order; `implicit` and `implicitfast` are first-order implicit-in-velocity Euler variants; RK4 is the classic
# fourth-order Runge-Kutta; MuJoCo 4.0's `discrete` merges the constraint solve into the implicit velocity update
# (first order).
NOMINAL_ORDER = {"Euler": 1, "implicit": 1, "implicitfast": 1, "RK4": 4, "discrete": 1}

# The default timestep ladder: dt_ref * 2^k, k = k_min .. LADDER_TOP, dt_ref the case's reference timestep
# (`reference`).
# Going *up* from the reference step lifts the error of a high-order method off round-off (RK4 at dt_ref is
# often at 1e-11 for the tops); nine doublings span a factor 512, i.e. 10 decades of error for a 4th-order method,
# and cost less than one more run at dt_ref (each doubling halves the steps). Going *down* brings a first-order
# method into its asymptotic regime (Euler on the heavy top errs by 5e-3..5e-2 at dt_ref): k_min is as low as
# LADDER_BOTTOM while a run stays within STEP_BUDGET steps, so short cases get finer steps and long ones none.
LADDER_TOP = 9
LADDER_BOTTOM = -3
STEP_BUDGET = 100_000

# Refused points: the model's own checks (e.g. contact stiffness too high for the timestep) rejected them.
REFUSED = "refused"

EPS = float(np.finfo(float).eps)
# Round-off: an error within ROUNDOFF_EPS machine epsilons (times the square root of the number of steps, the
# random walk of per-step rounding) of the scale of the value is noise, not truncation error.
ROUNDOFF_EPS = 100.0
# An error this large (relative, or normalised to an O(1) scale) is not in any asymptotic regime.
CEILING = 0.1
# Local slopes inside a straight range may differ from the range's fitted slope by at most this much.
STRAIGHT = 0.3
# A range whose error falls slower than this with the timestep is a plateau (round-off, or a measurement floor):
# every consistent integrator has order >= 1.
PLATEAU = 0.5


@dataclass(frozen=True)
class Point:
    """One grid point: a case under one integrator and timestep, and optionally one swept parameter value."""

    scenario: str
    case: str
    integrator: str
    timestep: float
    param: tuple[tuple[str, float], ...] = ()
    base: Settings = Settings()  # the user's settings the grid varies on (profile, --option, --settings-from)
    reference_timestep: float | None = None  # the case's reference timestep (s): the grid's dt is a multiple of it

    @property
    def scale(self) -> float | None:
        """dt / dt_ref: where the point sits on the case's ladder (1 = the reference timestep)."""
        return None if not self.reference_timestep else self.timestep / self.reference_timestep

    def settings(self) -> Settings:
        return self.base.merged(Settings(integrator=self.integrator, timestep=self.timestep))

    def record(self) -> dict[str, Any]:
        out = {
            "scenario": self.scenario,
            "case": self.case,
            "integrator": self.integrator,
            "timestep": self.timestep,
            "param": dict(self.param),
        }
        if self.base != Settings():
            out["base"] = self.base.record()
        if self.reference_timestep:
            out["reference_timestep"] = self.reference_timestep
        return out


@dataclass(frozen=True)
class Order:
    """The observed order of convergence of one check under one integrator (and one swept parameter value).

    Attributes
    ----------
    observed : float or None
        Least-squares slope of log(error) against log(timestep) over the straight range; None if fewer than two
        points are usable (`reason` says why).
    used : tuple of float
        The timesteps (s) of the points the fit used.
    reason : str
        Empty when fitted from three or more points; otherwise what limited the fit.
    """

    scenario: str
    case: str
    check: str
    integrator: str
    param: tuple[tuple[str, float], ...]
    nominal: int
    observed: float | None
    used: tuple[float, ...]
    reason: str = ""

    def record(self) -> dict[str, Any]:
        return {
            "scenario": self.scenario,
            "case": self.case,
            "check": self.check,
            "integrator": self.integrator,
            "param": dict(self.param),
            "nominal": self.nominal,
            "observed": self.observed,
            "npoints": len(self.used),
            "used": list(self.used),
            "reason": self.reason,
        }


@dataclass
class Sweep:
    """A sweep's grid, its result rows (one per check per point) and the fitted orders."""

    points: list[Point]
    rows: list[dict[str, Any]] = field(default_factory=list)
    orders: list[Order] = field(default_factory=list)

    def document(self) -> dict[str, Any]:
        from rigidbench import __version__

        return {
            "rigidbench": __version__,
            "mujoco": mujoco.__version__,
            "kind": "sweep",
            "nominal_order": NOMINAL_ORDER,
            "fit_rule": observed_order.__doc__.split("Parameters")[0].strip(),
            "results": self.rows,
            "orders": [o.record() for o in self.orders],
        }


# ---- the order of convergence --------------------------------------------------------------------------------


def observed_order(
    timesteps: Sequence[float],
    errors: Sequence[float],
    *,
    floors: Sequence[float] | float = 0.0,
    ceiling: float = CEILING,
    straight: float = STRAIGHT,
) -> tuple[float | None, tuple[float, ...], str]:
    """Observed order of convergence: the least-squares slope of log(error) against log(timestep) over the range
    where that curve is straight.

    The rule, in order:

    1. Drop points whose error is not finite (diverged, not measurable) and points **at round-off**: error at or
       below its floor, ``floor = 100 eps sqrt(nstep) * scale`` (scale: 1 for relative errors and for absolute
       errors of quantities normalised to O(1); ``|expected|`` otherwise), i.e. within ~100 eps of the value,
       allowing for the random walk of rounding over the run's steps.
    2. Drop points **before the asymptotic regime**: error above `ceiling` (0.1 of the scale: a 10 % error is not
       a small truncation error), and every larger timestep after the first such point.
    3. Among the remaining points (in timestep order), take the longest contiguous run whose consecutive
       two-point slopes all lie within `straight` (0.3) of the run's own least-squares slope, and whose slope is
       at least 0.5 (a flatter run is a plateau of round-off or of the measurement, not convergence: every
       consistent integrator has order >= 1); ties go to the run at smaller timesteps (closer to the asymptotic
       limit). The order is that run's least-squares slope.

    An order needs three points; with two, the order is None and the reason gives their two-point slope.

    Parameters
    ----------
    timesteps : sequence of float, shape (n,)
        Timesteps (s), any order, all positive.
    errors : sequence of float, shape (n,)
        The check's error at each timestep (NaN for a point that diverged).
    floors : float or sequence of float, shape (n,)
        Round-off floor of each point (see rule 1).

    Returns
    -------
    order : float or None
    used : tuple of float
        Timesteps of the points fitted, ascending.
    reason : str
        Empty for a fit through three or more points; otherwise why the fit is weak or absent.

    Raises
    ------
    ValueError
        If `timesteps` and `errors` differ in length or a timestep is not positive.
    """
    h = np.asarray(timesteps, dtype=float)
    e = np.asarray(errors, dtype=float)
    if h.shape != e.shape or h.ndim != 1:
        raise ValueError(f"timesteps and errors must be 1-d of one length, got shapes {h.shape} and {e.shape}")
    if np.any(~(h > 0)):
        raise ValueError(f"timesteps must be positive, got {h.tolist()}")
    floor = np.broadcast_to(np.asarray(floors, dtype=float), h.shape)
    order = np.argsort(h)
    h, e, floor = h[order], e[order], floor[order]

    finite = np.isfinite(e)
    if not finite.any():
        return None, (), "diverged or not measured"
    above = finite & (e > floor)
    if not above.any():
        return None, (), "at round-off"
    saturated = finite & (e > ceiling)
    if saturated.any():  # everything from the first saturated point up is outside the asymptotic regime
        above &= np.arange(len(h)) < np.argmax(saturated)
    keep = np.nonzero(above)[0]
    if keep.size == 0:
        return None, (), f"saturated: error above {ceiling:g} wherever it is above round-off"
    x, y = np.log(h[keep]), np.log(e[keep])
    if keep.size == 1:
        return None, (float(h[keep[0]]),), "one point between round-off and saturation"

    best: tuple[int, int] | None = None  # [start, stop) of the chosen run
    n = len(x)
    for length in range(n, 1, -1):
        for start in range(0, n - length + 1):  # smaller timesteps first: they win ties
            xs, ys = x[start : start + length], y[start : start + length]
            slope = np.polyfit(xs, ys, 1)[0]
            local = np.diff(ys) / np.diff(xs)
            if slope >= PLATEAU and np.all(np.abs(local - slope) <= straight):
                best = (start, start + length)
                break
        if best is not None:
            break
    if best is None:
        return None, (), "plateau: the error does not fall with the timestep"
    start, stop = best
    xs, ys = x[start:stop], y[start:stop]
    slope = float(np.polyfit(xs, ys, 1)[0])
    used = tuple(float(v) for v in h[keep[start:stop]])
    if stop - start < 3:
        return None, used, f"two points only (slope {slope:.2f})"
    return slope, used, ""


def roundoff_floor(row: Mapping[str, Any]) -> float:
    """The round-off floor of a result row's error (rule 1 of `observed_order`)."""
    expected = row.get("expected")
    scale = 1.0
    if row.get("tolerance_kind") == "abs" and expected not in (None, 0, 0.0):
        scale = abs(float(expected))
    return ROUNDOFF_EPS * EPS * math.sqrt(max(int(row.get("nstep") or 1), 1)) * scale


def fit_orders(rows: Iterable[Mapping[str, Any]]) -> list[Order]:
    """The observed order of every (scenario, case, check, integrator, swept parameter value) in sweep rows."""
    groups: dict[tuple, list[Mapping[str, Any]]] = {}
    checks_seen: dict[tuple, list[str]] = {}
    for row in rows:
        pt = row["point"]
        param = tuple(sorted(pt["param"].items()))
        base = (pt["scenario"], pt["case"], param, pt["integrator"])
        if row["status"] in (PASS, FAIL):
            groups.setdefault((*base, row["check"]), []).append(row)
            names = checks_seen.setdefault(base[:3], [])
            if row["check"] not in names:
                names.append(row["check"])
        groups.setdefault((*base, None), []).append(row)  # every point, diverged and refused included
    out = []
    measured = {key[:4] for key in groups if key[4] is not None}
    for (scenario, case, param, integrator, check), group in groups.items():
        if check is None:
            if (scenario, case, param, integrator) not in measured:  # nothing to fit: say so, not nothing
                nominal = NOMINAL_ORDER.get(integrator, 0)
                reason = "diverged or refused at every timestep"
                out.append(Order(scenario, case, "(every check)", integrator, param, nominal, None, (), reason))
            continue
        everything = groups[(scenario, case, param, integrator, None)]
        steps = sorted({r["point"]["timestep"] for r in everything})
        by_step = {r["point"]["timestep"]: r for r in group}
        errors = [by_step[s]["error"] if s in by_step and by_step[s]["error"] is not None else math.nan for s in steps]
        floors = [roundoff_floor(by_step[s]) if s in by_step else 0.0 for s in steps]
        observed, used, reason = observed_order(steps, errors, floors=floors)
        out.append(
            Order(scenario, case, check, integrator, param, NOMINAL_ORDER.get(integrator, 0), observed, used, reason)
        )
    return out


# ---- the grid ------------------------------------------------------------------------------------------------


def reference(slug: str, case: str, overrides: Mapping[str, Any] | None = None) -> tuple[float, float]:
    """The reference timestep (s) of a case (its model's, or the one that follows its parameters,
    `Scenario.reference_settings`) and its simulated time (s), predicted; nothing is simulated."""
    prep = registry.get(slug).prepare(case, overrides)
    return float(prep.model.opt.timestep), prep.duration


def ladder(dt_ref: float, duration: float | None = None) -> list[float]:
    """The default timesteps (s): dt_ref * 2^k for k = k_min .. `LADDER_TOP`, capped at `settings.MAX_TIMESTEP`.

    k_min = 0 without a `duration` (s); with one, the lowest k >= `LADDER_BOTTOM` whose run of
    ``duration / (dt_ref 2^k)`` steps stays within `STEP_BUDGET` (and never above 0).
    """
    k_min = 0
    if duration is not None and duration > 0:
        k_min = max(LADDER_BOTTOM, min(0, -math.floor(math.log2(STEP_BUDGET * dt_ref / duration))))
    return [dt_ref * 2.0**k for k in range(k_min, LADDER_TOP + 1) if dt_ref * 2.0**k <= MAX_TIMESTEP]


def plan(
    targets: Sequence[str],
    *,
    integrators: Sequence[str] | None = None,
    timesteps: Sequence[float] | None = None,
    params: Mapping[str, Sequence[float]] | None = None,
    base: Settings | None = None,
) -> list[Point]:
    """The grid: for each case of each target, integrators x timesteps x swept parameter values.

    Parameters
    ----------
    targets : sequence of str
        ``scenario`` or ``scenario:case``; none = every registered scenario.
    integrators : sequence of str, optional
        Default: every integrator of `NOMINAL_ORDER` this MuJoCo has.
    timesteps : sequence of float, optional
        Seconds. Default: `ladder` of each case's reference timestep and duration (`reference`).
    params : mapping of str to sequence of float, optional
        Parameters to sweep (SI units), e.g. ``{"stiffness": [1e5, 1e6, 1e7]}``; their values multiply the grid.
        A scenario with a ``stiffness`` parameter that is not named here sweeps it over its default x 10^(-1, 0,
        1): contact stiffness is one of the settings a user chooses.
    base : Settings, optional
        The settings every point runs under before its integrator and timestep (a profile, --option, ...).

    Raises
    ------
    ValueError
        For an unknown scenario, case, integrator or parameter, or a value out of range (naming it).
    """
    base = base or Settings()
    integrators = list(integrators or [name for name in NOMINAL_ORDER if name in INTEGRATORS])
    for name in integrators:
        if name not in INTEGRATORS:
            raise ValueError(f"integrator {name!r} is not one of {', '.join(INTEGRATORS)}")
    for dt in timesteps or ():
        Settings(timestep=dt)  # validates the range
    points = []
    for target in targets or list(registry.scenarios()):
        scenario, cases = registry.parse_target(target)
        swept = dict(params or {})
        names = {p.name for p in scenario.params}
        if "stiffness" in names and "stiffness" not in swept:
            k0 = float(scenario.defaults()["stiffness"])
            swept["stiffness"] = [k0 / 10, k0, k0 * 10]
        for name, values in swept.items():
            if name not in names:
                raise ValueError(
                    f"unknown parameter '{name}' for scenario '{scenario.slug}'; valid: {', '.join(sorted(names))}"
                )
            for v in values:
                scenario.param(name).check(v)
        combos: list[tuple[tuple[str, float], ...]] = [()]
        for name, values in swept.items():
            combos = [(*c, (name, float(v))) for c in combos for v in values]
        for case in cases:
            for combo in combos:
                try:
                    dt_ref, duration = reference(scenario.slug, case, dict(combo))
                except ValueError as exc:
                    raise ValueError(f"{scenario.slug}:{case}: {exc}") from None
                steps = list(timesteps) if timesteps else ladder(dt_ref, duration)
                for integrator in integrators:
                    for dt in steps:
                        points.append(Point(scenario.slug, case, integrator, float(dt), combo, base, dt_ref))
    return points


def run_point(point: Point, timed: bool = False) -> list[dict[str, Any]]:
    """Simulate one grid point; its result rows, each with the ``point`` record (and, if `timed`, the ``cost`` of
    its stepping, `Scenario.run`).

    A point the model refuses (`Scenario.check_model`, e.g. a contact too stiff for the timestep) yields one
    row with status ``"refused"`` and the reason, instead of raising: it is a finding of the sweep.
    """
    scenario = registry.get(point.scenario)
    # MuJoCo's warnings (e.g. "Nan, Inf or huge value in QACC" at a diverging point) are recorded with the point
    # instead of being printed by every worker and appended to MUJOCO_LOG.TXT; divergence is detected anyway.
    warnings: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(warnings.append)
    try:
        run = scenario.run(point.case, dict(point.param), point.settings(), timed=timed)
    except ValueError as exc:
        rows = [
            {
                "scenario": point.scenario,
                "case": point.case,
                "check": REFUSED,
                "status": REFUSED,
                "passed": None,
                "error": None,
                "measured": None,
                "expected": None,
                "reason": str(exc),
                "settings": {
                    "integrator": point.integrator,
                    "timestep": point.timestep,
                    "mujoco": mujoco.__version__,
                },
            }
        ]
    else:
        rows = rows_of(run)
    finally:
        mujoco.set_mju_user_warning(previous)
    for row in rows:
        row["point"] = point.record()
        row["mujoco_warnings"] = list(warnings)
    return rows


def _failed_row(point: Point, exc: BaseException) -> dict[str, Any]:
    return {
        "scenario": point.scenario,
        "case": point.case,
        "check": "error",
        "status": "error",
        "passed": None,
        "error": None,
        "measured": None,
        "expected": None,
        "message": f"{type(exc).__name__}: {exc}",
        "settings": {"integrator": point.integrator, "timestep": point.timestep, "mujoco": mujoco.__version__},
        "point": point.record(),
    }


def point_key(point: Point) -> str:
    """A point's identity in a journal (`rigidbench.journal`), stable across runs."""
    return json.dumps(point.record(), sort_keys=True)


def execute(
    points: Sequence[Point],
    *,
    workers: int = 2,
    progress: Callable[[int, int, Point], None] | None = None,
    finished: Mapping[str, list[dict[str, Any]]] | None = None,
    on_result: Callable[[Point, list[dict[str, Any]]], None] | None = None,
    timed: bool = False,
    executor: Any = None,
) -> Sweep:
    """Run every point (in `workers` processes; in this process if `workers` <= 1) and fit the orders; with
    `timed`, measure each point's cost too (`rigidbench.frontier`).

    The rows come back in grid order, whatever order the points finish in. Points whose rows are in
    `finished` (keyed by `point_key`, e.g. from a journal being resumed) are not run again; `on_result` is
    called with each newly finished point's rows as soon as it finishes (to journal them).
    """
    finished = finished or {}
    results: list[list[dict[str, Any]] | None] = [finished.get(point_key(p)) for p in points]
    todo = [i for i, r in enumerate(results) if r is None]

    def record(i: int, rows: list[dict[str, Any]], done: int) -> None:
        results[i] = rows
        if on_result is not None:
            on_result(points[i], rows)
        if progress is not None:
            progress(done, len(todo), points[i])

    from rigidbench.runner import Processes

    executor = executor or Processes(workers)
    calls = [(points[i], timed) for i in todo]
    for done, (j, rows) in enumerate(executor.map(run_point, calls), start=1):
        if isinstance(rows, BaseException):  # a point that failed on a cluster: a row saying so, never a traceback
            rows = [_failed_row(points[todo[j]], rows)]
        record(todo[j], rows, done)
    sweep = Sweep(points=list(points))
    sweep.rows = [row for rows in results if rows is not None for row in rows]
    sweep.orders = fit_orders(sweep.rows)
    return sweep


def write_json(path: str, sweep: Sweep) -> None:
    atomic_write(path, json.dumps(_jsonable(sweep.document()), indent=1) + "\n", "--json")


def verify_journal(path: str, record: Any) -> None:
    """Check that every journaled point's rows ran at that point's settings (its integrator and timestep, read
    back from the compiled model) and name it; a journal whose rows mix settings is refused.

    Raises
    ------
    rigidbench.journal.JournalError
        Naming the file and line.
    """
    from rigidbench.journal import JournalError

    for key, rows in record.by_job().items():
        line = record.lines[key]
        try:
            point = json.loads(key)
        except json.JSONDecodeError:
            raise JournalError(f"{path}:{line}: {key!r} is not a sweep point") from None
        for i, row in enumerate(rows):
            settings = row.get("settings") if isinstance(row.get("settings"), dict) else {}
            if row.get("point") != point or (
                row.get("status") != REFUSED
                and (
                    settings.get("integrator") != point.get("integrator")
                    or settings.get("timestep") != point.get("timestep")
                )
            ):
                raise JournalError(
                    f"{path}:{line + i}: a row of point {key} ran with other settings than the point's: results "
                    "would mix settings"
                )


# ---- text output ---------------------------------------------------------------------------------------------


def _param_text(param: Mapping[str, float] | Iterable[tuple[str, float]]) -> str:
    items = param.items() if isinstance(param, Mapping) else param
    return ",".join(f"{k}={v:g}" for k, v in items)


def _target(o: Order) -> str:
    extra = _param_text(o.param)
    return f"{o.scenario}:{o.case}" + (f" [{extra}]" if extra else "")


def _short(reason: str) -> str:
    if reason.startswith("two points only"):
        return "2 pts " + reason[len("two points only ") :]
    if reason.startswith("one point"):
        return "1 pt"
    return reason.split(":")[0]


def order_table(orders: Sequence[Order]) -> str:
    """One row per case and check, one column per integrator: observed order (points fitted)."""
    integrators = [i for i in NOMINAL_ORDER if any(o.integrator == i for o in orders)]
    integrators += sorted({o.integrator for o in orders} - set(integrators))
    header = ["target", "check", *[f"{i} (nominal {NOMINAL_ORDER.get(i, '?')})" for i in integrators]]
    cells: dict[tuple[str, str], dict[str, str]] = {}
    for o in orders:
        if o.observed is None:
            text = "-  " + _short(o.reason)
        else:
            text = f"{o.observed:5.2f} ({len(o.used)})"
        cells.setdefault((_target(o), o.check), {})[o.integrator] = text
    lines = [[t, c, *[row.get(i, "") for i in integrators]] for (t, c), row in cells.items()]
    return _format(header, lines) + (
        "\n\n(n) = points in the straight range fitted (rule: rigidbench.sweep.observed_order). No order: "
        "'at round-off' (every error within 100 eps sqrt(nstep) of the value), 'saturated' (error > 0.1 wherever "
        "it is above round-off), 'plateau' (the error does not fall with the timestep: round-off, or a model or "
        "measurement floor), '2 pts (slope)' / '1 pt' (too few points between round-off and saturation), 'diverged'."
    )


def error_table(sweep: Sweep) -> str:
    """Every point's error: one row per case, check and integrator, one column per timestep."""
    steps = sorted({r["point"]["timestep"] for r in sweep.rows})
    header = ["target", "check", "integrator", *[f"{s:.3g}" for s in steps]]
    table: dict[tuple[str, str, str], dict[float, str]] = {}
    diverged: dict[tuple[str, str, str], dict[float, str]] = {}
    for r in sweep.rows:
        pt = r["point"]
        target = f"{pt['scenario']}:{pt['case']}" + (f" [{_param_text(pt['param'])}]" if pt["param"] else "")
        if r["status"] in (DIVERGED, REFUSED):
            mark = "div" if r["status"] == DIVERGED else "ref"
            diverged.setdefault((target, pt["integrator"]), {})[pt["timestep"]] = mark
            continue
        err = r["error"]
        table.setdefault((target, r["check"], pt["integrator"]), {})[pt["timestep"]] = (
            "nan" if err is None or not math.isfinite(err) else f"{err:.1e}"
        )
    lines = []
    for (target, check, integrator), row in table.items():
        bad = diverged.get((target, integrator), {})
        lines.append([target, check, integrator, *[row.get(s, bad.get(s, "")) for s in steps]])
    return _format(header, lines) + "\n\n(div = diverged, ref = refused by the model's checks)"


def _format(header: Sequence[str], lines: Sequence[Sequence[str]]) -> str:
    widths = [max(len(str(x)) for x in col) for col in zip(header, *lines, strict=False)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    out = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    out += [fmt.format(*line) for line in lines]
    return "\n".join(line.rstrip() for line in out)


def progress_line(done: int, total: int, point: Point) -> None:
    extra = f" {_param_text(point.param)}" if point.param else ""
    print(
        f"[{done}/{total}] {point.scenario}:{point.case} {point.integrator} dt={point.timestep:.3g}{extra}",
        file=sys.stderr,
        flush=True,
    )
