"""Speed against accuracy (issue 19): for every setting of a sweep grid, each check's error against theory and what
the stepping cost, the Pareto front, and the cheapest settings that reach a wanted accuracy.

A frontier is a view of `rigidbench.sweep`: the same grid (integrators x timesteps x swept parameters, on top of the
user's settings), the same rows (`rigidbench run`'s, so an error here is the error `run` reports for those
settings), plus a measured cost per point (`Scenario.run(timed=True)`): CPU seconds of stepping per simulated
second, timed without the prediction or the measurement, at least `simulate.TIMING_BUDGET` seconds and
`simulate.TIMING_REPEATS` repeats per point, median kept, spread recorded (`simulate.time_stepping`). Costs are
relative by nature: every document records the CPU, the CPUs used, the load and the versions.

Settings are compared per scenario, at the same place on every case's timestep ladder: a *setting* is an
integrator and a scale ``dt / dt_ref`` (each case's reference timestep follows its parameters), aggregated over the
scenario's cases: its error is the largest error of any case's theory checks, its cost the CPU seconds of all its
cases over their simulated seconds. Checks of a conserved quantity (named ``*-drift``: energy, angular momentum)
are a second accuracy axis, *drift*, as in Erez, Tassa and Todorov (ICRA 2015), who had no ground truth and
measured accuracy by drift alone; reporting both lets the two views be compared.

The Pareto front: settings no other setting beats in both error and cost (a diverged or refused setting is never
on it). Costs have a spread, errors do not: a setting whose membership would change with costs anywhere inside
their spreads is marked *marginal* (repeated runs may disagree on it, and only on it).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rigidbench.results import DIVERGED, ERROR

TARGET_ERRORS = (1e-3, 1e-6, 1e-9)
CONSERVED_SUFFIX = "-drift"
REFUSED = "refused"


@dataclass
class Setting:
    """One setting of one scenario (an integrator at one place of the timestep ladder), over its cases."""

    scenario: str
    integrator: str
    scale: float  # dt / dt_ref (the same on every case); or the timestep itself when the grid gave timesteps
    cases: int = 0
    error: float = math.nan  # largest theory-check error over the cases (inf: diverged)
    drift: float | None = None  # largest conserved-quantity drift over the cases
    cpu: float = math.nan  # CPU seconds of stepping per simulated second
    cpu_spread: tuple[float, float] = (math.nan, math.nan)
    steps: int = 0
    diverged: bool = False
    refused: bool = False
    checks: dict[str, float] = field(default_factory=dict)  # each check's largest error over the cases
    tolerances: dict[str, float] = field(default_factory=dict)
    front: bool = False
    marginal: bool = False
    _sim: float = 0.0
    _cpu: float = 0.0
    _lo: float = 0.0
    _hi: float = 0.0

    @property
    def usable(self) -> bool:
        return not (self.diverged or self.refused) and math.isfinite(self.error) and math.isfinite(self.cpu)

    def record(self) -> dict[str, Any]:
        return {
            "scenario": self.scenario,
            "integrator": self.integrator,
            "scale": self.scale,
            "cases": self.cases,
            "error": self.error,
            "drift": self.drift,
            "cpu_per_sim_second": self.cpu,
            "cpu_per_sim_second_spread": list(self.cpu_spread),
            "realtime_factor": 1 / self.cpu if self.cpu and math.isfinite(self.cpu) else None,
            "steps": self.steps,
            "diverged": self.diverged,
            "refused": self.refused,
            "front": self.front,
            "marginal": self.marginal,
            "checks": self.checks,
        }


def _scale(point: Mapping[str, Any]) -> float:
    ref = point.get("reference_timestep")
    return round(point["timestep"] / ref, 9) if ref else point["timestep"]


def settings_of(rows: Iterable[Mapping[str, Any]]) -> list[Setting]:
    """Aggregate timed sweep rows into settings per scenario (module docstring), in grid order."""
    out: dict[tuple, Setting] = {}
    seen: dict[tuple, set] = {}
    for row in rows:
        pt = row["point"]
        key = (pt["scenario"], pt["integrator"], _scale(pt))
        s = out.setdefault(key, Setting(pt["scenario"], pt["integrator"], key[2]))
        case = (pt["case"], tuple(sorted(pt["param"].items())))
        first = case not in seen.setdefault(key, set())
        seen[key].add(case)
        if first:
            s.cases += 1
        status = row["status"]
        if status == REFUSED:
            s.refused = True
            continue
        if status in (DIVERGED, ERROR):
            s.diverged = True
            s.error = math.inf
            continue
        error = row["error"]
        error = math.inf if error is None or error == "inf" else float(error)
        if math.isnan(error):  # a measurement that failed (max(0.0, nan) would be 0.0: the best error of all)
            error = math.inf
        check = row["check"]
        s.checks[check] = max(s.checks.get(check, 0.0), error)
        if row.get("tolerance") is not None:
            s.tolerances[check] = min(s.tolerances.get(check, math.inf), float(row["tolerance"]))
        if check.endswith(CONSERVED_SUFFIX):
            s.drift = error if s.drift is None else max(s.drift, error)
        else:
            s.error = error if math.isnan(s.error) else max(s.error, error)
        cost = row.get("cost")
        if first and cost:
            s._sim += float(row["duration"])
            s._cpu += cost["cpu_per_sim_second"] * float(row["duration"])
            lo, hi = cost["cpu_per_sim_second_spread"]
            s._lo += lo * float(row["duration"])
            s._hi += hi * float(row["duration"])
            s.steps += int(row["nstep"])
    for s in out.values():
        if s._sim > 0:
            s.cpu = s._cpu / s._sim
            s.cpu_spread = (s._lo / s._sim, s._hi / s._sim)
    return list(out.values())


# ---- the front ------------------------------------------------------------------------------------------------


def _dominates(e1: float, c1: float, e2: float, c2: float) -> bool:
    return e1 <= e2 and c1 <= c2 and (e1 < e2 or c1 < c2)


def pareto(points: Sequence[tuple[float, float, float, float]]) -> list[tuple[bool, bool]]:
    """Front membership of (error, cost, cost_low, cost_high) points: for each, (on the front, marginal).

    On the front: no other point has error and cost both <= its own, one of them strictly (by the median costs);
    a point whose error or cost is not finite (diverged) is never on it, and equal points are both on it.
    Marginal: the membership would differ for some costs inside the spreads [cost_low, cost_high] (surely on: no
    point dominates it even at its highest cost against their lowest; surely off: some point dominates it even at
    its lowest cost against that point's highest).
    """
    out = []
    for i, (e, c, lo, hi) in enumerate(points):
        if not (math.isfinite(e) and math.isfinite(c)):
            out.append((False, False))
            continue
        others = [p for j, p in enumerate(points) if j != i and math.isfinite(p[0]) and math.isfinite(p[1])]
        on = not any(_dominates(e2, c2, e, c) for e2, c2, _, _ in others)
        surely_on = not any(_dominates(e2, lo2, e, hi) for e2, _, lo2, _ in others)
        surely_off = any(_dominates(e2, hi2, e, lo) for e2, _, _, hi2 in others)
        out.append((on, not surely_on and not surely_off))
    return out


def mark_fronts(settings: Sequence[Setting]) -> None:
    """Set `front` and `marginal` of every setting, per scenario, on (error, cost)."""
    by_scenario: dict[str, list[Setting]] = {}
    for s in settings:
        by_scenario.setdefault(s.scenario, []).append(s)
    for group in by_scenario.values():
        points = [(s.error if s.usable else math.inf, s.cpu if s.usable else math.inf, *s.cpu_spread) for s in group]
        for s, (on, marginal) in zip(group, pareto(points), strict=True):
            s.front, s.marginal = on, marginal


# ---- the cheapest settings -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Answer:
    """The cheapest setting of a scenario (or of one check) whose error is at most `target`, or, if none is,
    the best error reached and where."""

    scenario: str
    check: str | None
    target: float
    cheapest: Setting | None
    best: Setting | None
    best_error: float
    reference: Setting | None
    # The cheapest setting is its integrator's largest step on the grid (issue 36): a larger step, off the grid, may
    # meet the target too, so the answer is an upper bound on the cost: extend the grid (--timesteps) past it.
    at_grid_edge: bool = False

    @property
    def speedup(self) -> float | None:
        """How many times cheaper than the scenario's reference settings (None if either is missing)."""
        if self.cheapest is None or self.reference is None or not self.reference.usable:
            return None
        return self.reference.cpu / self.cheapest.cpu

    def record(self) -> dict[str, Any]:
        return {
            "scenario": self.scenario,
            "check": self.check,
            "target_error": self.target,
            "cheapest": self.cheapest.record() if self.cheapest else None,
            "best_error": self.best_error,
            "best": self.best.record() if self.best else None,
            "times_cheaper_than_reference": self.speedup,
            "at_grid_edge": self.at_grid_edge,
        }


def _error_of(s: Setting, check: str | None) -> float:
    if not s.usable:
        return math.inf
    return s.error if check is None else s.checks.get(check, math.nan)


def cheapest(settings: Sequence[Setting], target: float, references: Mapping[str, tuple[str, float]]) -> list[Answer]:
    """Per scenario, and per check where a check's cheapest setting differs from the scenario's: the cheapest
    setting with error <= `target`.

    Parameters
    ----------
    references : mapping of scenario to (integrator, scale)
        Each scenario's reference setting (its model file's integrator at scale 1), to say how much cheaper.

    Raises
    ------
    ValueError
        If `target` is not positive.
    """
    if not (math.isfinite(target) and target > 0):
        raise ValueError(f"--target-error = {target!r} must be a positive number")
    answers = []
    by_scenario: dict[str, list[Setting]] = {}
    for s in settings:
        by_scenario.setdefault(s.scenario, []).append(s)
    for slug, group in by_scenario.items():
        ref_integrator, ref_scale = references.get(slug, ("", math.nan))
        reference = next((s for s in group if s.integrator == ref_integrator and s.scale == ref_scale), None)
        checks: list[str | None] = [
            None,
            *sorted({c for s in group for c in s.checks if not c.endswith(CONSERVED_SUFFIX)}),
        ]
        whole = None
        for check in checks:
            errors = [(_error_of(s, check), s) for s in group]
            errors = [(e, s) for e, s in errors if not math.isnan(e)]
            if not errors:
                continue
            ok = [s for e, s in errors if e <= target]
            best_error, best = min(errors, key=lambda x: (x[0], x[1].cpu))
            pick = min(ok, key=lambda s: s.cpu) if ok else None
            edge = pick is not None and pick.scale >= max(s.scale for s in group if s.integrator == pick.integrator)
            answer = Answer(slug, check, target, pick, best, best_error, reference, at_grid_edge=edge)
            if check is None:
                whole = answer
                answers.append(answer)
            elif whole is None or pick is not whole.cheapest:
                answers.append(answer)
    return answers


# ---- text ---------------------------------------------------------------------------------------------------


def _g(x: float | None, fmt: str = ".2e") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return format(x, fmt) if math.isfinite(x) else "inf"


def _where(s: Setting | None) -> str:
    if s is None:
        return "-"
    return f"{s.integrator} x{s.scale:g}"


def table(settings: Sequence[Setting]) -> str:
    """Every setting: error, drift, cost (spread), real-time factor, front membership."""
    header = ("scenario", "integrator", "dt/dt_ref", "error", "drift", "CPU s/sim s", "spread", "RTF", "front")
    lines = []
    for s in settings:
        status = "diverged" if s.diverged else ("refused" if s.refused else "")
        front = ("yes" if s.front else "no") + ("*" if s.marginal else "")
        lines.append(
            (
                s.scenario,
                s.integrator,
                f"{s.scale:g}",
                status or _g(s.error),
                _g(s.drift),
                _g(s.cpu, ".3g"),
                f"{_g(s.cpu_spread[0], '.3g')}-{_g(s.cpu_spread[1], '.3g')}",
                _g(1 / s.cpu if s.cpu and math.isfinite(s.cpu) else None, ".3g"),
                front if s.usable else "-",
            )
        )
    widths = [max(len(x) for x in col) for col in zip(header, *lines, strict=True)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    out = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    out += [fmt.format(*line).rstrip() for line in lines]
    out.append(
        "\nerror: largest theory-check error over the cases; drift: largest conserved-quantity drift (*-drift checks); "
        "CPU s/sim s: CPU seconds of stepping per simulated second (median; spread over the repeats); RTF: its "
        "inverse; front: on the Pareto front of (error, cost), * = marginal (membership changes within the cost spread)"
    )
    return "\n".join(out)


def answers_table(answers: Sequence[Answer], markdown: bool = False) -> str:
    """The cheapest settings per target error: where, its error and cost, and how much cheaper than reference."""
    header = ("scenario", "check", "target", "cheapest setting", "its error", "CPU s/sim s", "x cheaper than ref")
    lines = []
    for a in answers:
        if a.cheapest is None:
            where = f"none reaches it (best {_g(a.best_error)} at {_where(a.best)})"
            lines.append((a.scenario, a.check or "all", f"{a.target:g}", where, "-", "-", "-"))
            continue
        lines.append(
            (
                a.scenario,
                a.check or "all",
                f"{a.target:g}",
                _where(a.cheapest) + (" (grid's edge: a larger step may do)" if a.at_grid_edge else ""),
                _g(_error_of(a.cheapest, a.check)),
                _g(a.cheapest.cpu, ".3g"),
                _g(a.speedup, ".3g"),
            )
        )
    if markdown:
        out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        return "\n".join(out + ["| " + " | ".join(line) + " |" for line in lines])
    widths = [max(len(x) for x in col) for col in zip(header, *lines, strict=True)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    out = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    return "\n".join(out + [fmt.format(*line).rstrip() for line in lines])


def references(slugs: Iterable[str]) -> dict[str, tuple[str, float]]:
    """Each scenario's reference setting: its model file's integrator at scale 1 (the reference timestep)."""
    from rigidbench import registry
    from rigidbench.settings import INTEGRATORS

    names = {int(v): k for k, v in INTEGRATORS.items()}
    out = {}
    for slug in slugs:
        model = registry.get(slug).spec().compile()
        out[slug] = (names.get(int(model.opt.integrator), ""), 1.0)
    return out


def document(
    rows: Sequence[Mapping[str, Any]], settings: Sequence[Setting], answers: Sequence[Answer], machine: Mapping
) -> dict[str, Any]:
    """The frontier as a JSON document: the machine the costs were measured on, every setting, the cheapest
    settings, each scenario's tightest theory tolerance (for the plots) and every row."""
    import mujoco

    from rigidbench import __version__

    tolerances: dict[str, float] = {}
    for s in settings:
        for check, tol in s.tolerances.items():
            if not check.endswith(CONSERVED_SUFFIX):
                tolerances[s.scenario] = min(tolerances.get(s.scenario, math.inf), tol)
    return {
        "kind": "frontier",
        "rigidbench": __version__,
        "mujoco": mujoco.__version__,
        "machine": dict(machine),
        "settings": [s.record() for s in settings],
        "answers": [a.record() for a in answers],
        "tolerances": tolerances,
        "results": list(rows),
    }


def markdown(doc: Mapping[str, Any], answers: Sequence[Answer]) -> str:
    """The cheapest-settings table as Markdown, with the machine it was measured on."""
    m = doc["machine"]
    return (
        "## Cheapest settings for a wanted accuracy\n\n"
        f"mujoco {doc['mujoco']}, rigidbench {doc['rigidbench']}; costs in CPU seconds of stepping per simulated "
        f"second on {m.get('cpu')} ({m.get('cpus')} CPUs, {m.get('jobs')} point(s) at a time, load "
        f"{(m.get('load') or [math.nan])[0]:.2g}). A setting is an integrator at dt = scale x each case's reference "
        "timestep; *x cheaper than ref* compares it with the scenario's reference settings (its model file's "
        "integrator at scale 1).\n\n" + answers_table(answers, markdown=True) + "\n"
    )
