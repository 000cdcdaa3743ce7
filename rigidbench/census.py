"""Census: the benchmark's trust across its parameter space (issue 13).

Draw N valid parameter sets per scenario from the ranges `rigidbench list` prints (each parameter's range, its
dependent range and the case's regime), run them under the `reference` profile through the shared run loop
(`rigidbench.runner.run_jobs`), and tally per scenario: drawn, refused before simulating (grouped by reason),
passed, failed, crashed. A range that `list` prints is a promise: every set inside it passes or is refused with
the theory's reason, so a clean census has 0 failed and 0 crashed.

The draws are seeded per scenario (numpy's Generator on ``(seed, crc32(slug))``), so restricting the targets or
resuming a journal gives the same sets. The cases of a scenario take the draws in turn. Each parameter the case
does not derive is drawn:

- log-uniform over a positive range spanning a factor of 10 or more (or a negative one), else uniform; a range
  that straddles zero is drawn uniformly half the time and with a log-uniform magnitude (down to 1e-6 of its
  largest end) and a random sign the other half, so small values are tried too;
- in one draw in three ("edge" draws) one or two parameters are put within `EDGE_SPAN` of an end of their range
  (of its logarithm for a log-uniform one): the near-separatrix tops, fast spins, grazing impacts, extreme mass
  ratios and large amplitudes live there.

A parameter whose range depends on others (`Param.within`, or a case regime given as a `Bound`) is drawn after
the parameters it needs. A value the case derives from the others is drawn too in one draw in four
(`DERIVED_PROBABILITY`), since a user may set it. A budget parameter (`Param.budget`: a Monte Carlo sample count,
steps per contact) is drawn between its lower end and its default, so that a census costs what a run costs: larger
values only tighten statistics or resolution (the `thorough` profile and the scenario's tests run those).

A statistical test (`Check.false_alarm`: a Monte Carlo sample's goodness of fit at level alpha) fails for one correct
set in 1/alpha, so a census of enough draws meets such failures by chance. A draw that failed only statistical tests
is run once more on an independent sample (its sampling seed, the parameter `SAMPLE_SEED`, replaced by one derived
from it): a correct simulation fails both with probability alpha^2, a wrong one fails both. Such a draw counts as
passed only if its second sample passes every check; the table gives how many statistical tests failed on a first
sample beside the number a correct simulation fails on average (the sum of their levels).
"""

from __future__ import annotations

import math
import re
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rigidbench import registry
from rigidbench.engines.base import EngineRefused
from rigidbench.params import Bound, Param, Range, Value
from rigidbench.results import DIVERGED, ERROR, FAIL, PASS, UNRESOLVED
from rigidbench.runner import Job, RunResult, check_job
from rigidbench.scenario import Case, OutsideDomain, Scenario
from rigidbench.settings import Settings

EDGE_PROBABILITY = 1 / 3
# The share of draws in which a value the case derives (a steady-precession rate, the marble shot's centre of
# percussion) is drawn like a free parameter, as a user's ``--set`` of it would be: every set a case accepts can be
# drawn (issue 35: a case that accepted any offset never had one drawn).
DERIVED_PROBABILITY = 1 / 4
EDGE_SPAN = 0.02  # an edge draw lies within 2 % of the range's (log-)span from one of its ends
LOG_SPAN = 10.0  # a positive range spanning at least this factor is drawn log-uniformly
SMALL = 1e-6  # a range straddling zero: log-uniform magnitudes go down to this fraction of its largest end

PASSED, FAILED, REFUSED, CRASHED = "passed", "failed", "refused", "crashed"
# The parameter that seeds a Monte Carlo scenario's sample (a draw failing only statistical tests is re-run with
# another value of it).
SAMPLE_SEED = "seed"


@dataclass
class Draw:
    """One drawn parameter set and what became of it."""

    scenario: str
    case: str
    index: int
    params: dict[str, Value]
    status: str = ""
    reason: str = ""  # a refusal's group (the domain's name) or a crash's message
    message: str = ""  # the full refusal message
    rows: list[dict[str, Any]] = field(default_factory=list)
    job: Job | None = field(default=None, repr=False)
    # a draw that failed only statistical tests: its second, independent sample (`second_samples`)
    second: dict[str, Any] | None = None

    def command(self) -> str:
        """The `rigidbench run` command that reproduces this draw."""
        sets = " ".join(f"--set {k}={_exact(v)}" for k, v in self.params.items())
        return f"rigidbench run {self.scenario}:{self.case} {sets}".rstrip()

    def record(self) -> dict[str, Any]:
        out = {
            "scenario": self.scenario,
            "case": self.case,
            "index": self.index,
            "params": self.params,
            "status": self.status,
            "command": self.command(),
        }
        if self.second is not None:
            out["second_sample"] = self.second
        if self.reason:
            out["reason"] = self.reason
        if self.message:
            out["message"] = self.message
        if self.status in (FAILED, CRASHED):
            out["rows"] = [r for r in self.rows if r["status"] != PASS]
        return out


def _exact(value: Value) -> str:
    if isinstance(value, tuple):
        return ",".join(repr(float(x)) for x in value)
    return repr(float(value))


# ---- drawing --------------------------------------------------------------------------------------------------


def _interval(bound: Range | Bound | None, values: Mapping[str, Value]) -> Range | None:
    if bound is None:
        return None
    return bound.range(values) if isinstance(bound, Bound) else bound


def _intersect(a: Range, b: Range | None) -> Range:
    if b is None:
        return a
    if a.magnitude != b.magnitude:  # a signed range symmetric about 0 and a range of magnitudes: magnitudes
        signed, sized = (a, b) if b.magnitude else (b, a)
        top = min(abs(signed.low), abs(signed.high))
        return Range(sized.low, min(sized.high, top), sized.low_open, sized.high_open, magnitude=True)
    if a.low != b.low:
        low, low_open = (a.low, a.low_open) if a.low > b.low else (b.low, b.low_open)
    else:
        low, low_open = a.low, a.low_open or b.low_open
    if a.high != b.high:
        high, high_open = (a.high, a.high_open) if a.high < b.high else (b.high, b.high_open)
    else:
        high, high_open = a.high, a.high_open or b.high_open
    return Range(low, high, low_open, high_open, magnitude=a.magnitude)


def sampling_range(scenario: Scenario, case: Case, p: Param, values: Mapping[str, Value]) -> Range:
    """Where a census draws `p` for `case`: its range, its dependent range and the case's regime, intersected (up
    to its default for a budget parameter)."""
    r = _intersect(p.valid, _interval(p.within, values))
    r = _intersect(r, _interval(case.ranges.get(p.name), values))
    if p.budget:
        r = _intersect(r, Range(r.low, float(np.max(scenario.defaults()[p.name])), r.low_open))
    return r


def _inside(r: Range) -> tuple[float, float]:
    low = math.nextafter(r.low, math.inf) if r.low_open else r.low
    high = math.nextafter(r.high, -math.inf) if r.high_open else r.high
    return low, high


def draw_value(r: Range, rng: np.random.Generator, *, edge: str | None = None, integer: bool = False) -> float:
    """One number drawn from `r` (see the module docstring); `edge` = ``"low"`` or ``"high"`` puts it within
    `EDGE_SPAN` of that end."""
    if r.magnitude:  # a size from the range and a random sign
        size = draw_value(Range(r.low, r.high, r.low_open, r.high_open), rng, edge=edge, integer=integer)
        return size if rng.random() < 0.5 else -size
    low, high = _inside(r)
    if not low <= high:
        raise EmptyRange(f"empty range {r}")
    if integer:
        lo, hi = math.ceil(low), math.floor(high)
        if edge is not None:
            span = max(1, round(EDGE_SPAN * (hi - lo)))
            return float(rng.integers(lo, lo + span + 1) if edge == "low" else rng.integers(hi - span, hi + 1))
        if lo > 0 and hi / lo >= LOG_SPAN:
            return float(min(hi, max(lo, round(math.exp(rng.uniform(math.log(lo), math.log(hi + 1)))))))
        return float(rng.integers(lo, hi + 1))
    if low == high:
        return low
    positive = low > 0 and high / low >= LOG_SPAN
    negative = high < 0 and low / high >= LOG_SPAN
    if positive or negative:
        a, b = (math.log(low), math.log(high)) if positive else (math.log(-high), math.log(-low))
        if edge is not None:
            near_low = (edge == "low") == positive  # the log of |x| runs the other way for negative ranges
            u = rng.uniform(0, EDGE_SPAN)
            x = math.exp(a + u * (b - a) if near_low else b - u * (b - a))
        else:
            x = math.exp(rng.uniform(a, b))
        x = x if positive else -x
    elif edge is not None:
        u = rng.uniform(0, EDGE_SPAN) * (high - low)
        x = low + u if edge == "low" else high - u
    elif low < 0 < high and rng.random() < 0.5:
        top = max(-low, high)
        magnitude = math.exp(rng.uniform(math.log(SMALL * top), math.log(top)))
        x = magnitude if rng.random() < 0.5 else -magnitude
    else:
        x = rng.uniform(low, high)
    return float(min(high, max(low, x)))


def _order(scenario: Scenario, case: Case) -> list[Param]:
    """Parameters in an order where every dependent range comes after the parameters it needs."""
    pending = list(scenario.params)
    ordered: list[Param] = []
    placed: set[str] = set()
    while pending:
        for p in pending:
            needs = set(p.within.needs if p.within else ())
            regime = case.ranges.get(p.name)
            if isinstance(regime, Bound):
                needs |= set(regime.needs)
            if needs <= placed | {p.name}:
                ordered.append(p)
                placed.add(p.name)
                pending.remove(p)
                break
        else:  # a cycle: keep the declared order
            ordered.extend(pending)
            break
    return ordered


# Redraws of one set whose dependent range came out empty (the region is sampled by rejection).
MAX_REDRAWS = 1000


class EmptyRange(ValueError):
    """A dependent range that is empty for the values drawn before it."""


def draw(scenario: Scenario, case: Case, rng: np.random.Generator) -> dict[str, Value]:
    """One random parameter set for `case`: every parameter the case does not derive, inside the ranges that
    `rigidbench list` prints for it (module docstring). A dependent range that comes out empty for the values drawn
    before it (e.g. no spring constant puts a tiny attachment height in a coupling regime) means those values lie
    outside the case's region: the set is drawn again (rejection sampling), up to `MAX_REDRAWS` times.

    Raises
    ------
    ValueError
        If no set is found in `MAX_REDRAWS` draws (the regime is too narrow to sample).
    """
    for _ in range(MAX_REDRAWS):
        try:
            return _draw_once(scenario, case, rng)
        except EmptyRange:
            continue
    raise ValueError(f"{scenario.slug}:{case.name}: no parameter set inside its ranges in {MAX_REDRAWS} draws")


def _draw_once(scenario: Scenario, case: Case, rng: np.random.Generator) -> dict[str, Value]:
    derived = {name for name, v in case.values.items() if callable(v)}
    if derived:  # a user may set a value the case derives (it wins): drawn too, in one draw in `DERIVED_PROBABILITY`
        derived = {name for name in sorted(derived) if rng.random() >= DERIVED_PROBABILITY}
    free = [p for p in _order(scenario, case) if p.name not in derived]
    edges: dict[str, str] = {}
    if free and rng.random() < EDGE_PROBABILITY:
        k = min(len(free), int(rng.integers(1, 3)))
        for i in rng.choice(len(free), size=k, replace=False):
            edges[free[int(i)].name] = "low" if rng.random() < 0.5 else "high"
    values: dict[str, Value] = dict(scenario.defaults())
    for name, v in case.values.items():
        if not callable(v):
            values[name] = v
    for name, fn in case.values.items():
        if callable(fn):
            try:
                values[name] = fn(values)
            except (ArithmeticError, ValueError):
                pass  # derived from values not drawn yet; refreshed below
    out: dict[str, Value] = {}
    for p in free:
        r = sampling_range(scenario, case, p, values)
        components = [draw_value(r, rng, edge=edges.get(p.name), integer=p.integer) for _ in range(p.size)]
        value: Value = components[0] if p.size == 1 else tuple(components)
        out[p.name] = values[p.name] = value
        for name, fn in case.values.items():  # keep derived values current for the dependent ranges that follow
            if callable(fn):
                try:
                    values[name] = fn(values)
                except (ArithmeticError, ValueError):
                    pass
    return out


def plan(targets: Sequence[str], *, n: int, seed: int, settings: Settings | None) -> tuple[list[Draw], list[Job]]:
    """Draw `n` sets per scenario and check each before simulating (`runner.check_job`).

    Returns every draw (a refused or crashed one already has its status) and the jobs to run, one per draw that
    was not refused, in draw order.

    Raises
    ------
    ValueError
        For an unknown scenario or case, or n < 1.
    """
    if n < 1:
        raise ValueError(f"--n = {n} must be >= 1")
    draws: list[Draw] = []
    jobs: list[Job] = []
    for target in targets or list(registry.scenarios()):
        scenario, case_names = registry.parse_target(target)
        rng = np.random.default_rng([seed, zlib.crc32(f"{scenario.slug}:{','.join(case_names)}".encode())])
        for i in range(n):
            case = scenario.case(case_names[i % len(case_names)])
            d = Draw(scenario.slug, case.name, i, {})
            draws.append(d)
            try:
                d.params = draw(scenario, case, rng)
                job = check_job(Job(scenario, case.name, d.params, variant=f"census {i}"), settings)
            except OutsideDomain as exc:
                d.status, d.reason, d.message = REFUSED, exc.domain, str(exc)
            except EngineRefused as exc:
                d.status, d.reason, d.message = REFUSED, "unsupported by the engine: " + _shape(str(exc)), str(exc)
            except ValueError as exc:
                d.status, d.reason, d.message = REFUSED, "not a domain: " + _shape(str(exc)), str(exc)
            except Exception as exc:  # noqa: BLE001 - a crash is what the census counts
                d.status, d.reason = CRASHED, f"{type(exc).__name__}: {exc}"
            else:
                d.job = job
                jobs.append(job)
    return draws, jobs


def _shape(message: str) -> str:
    """A refusal message with its numbers and the draw's prefix removed, to group refusals by cause."""
    message = message.split(": ", 1)[-1] if re.match(r"^[\w-]+:[\w-]+: ", message) else message
    return re.sub(r"[-+]?\d[\d.]*(e[-+]?\d+)?", "#", message)[:160]


def settle(draws: Sequence[Draw], result: RunResult) -> None:
    """Give every draw that ran its rows and status (passed, failed or crashed); unrun draws keep ``""``."""
    for d in draws:
        if d.job is None or d.job.key not in result.rows:
            continue
        rows = result.rows[d.job.key]
        d.rows = [{k: v for k, v in r.items() if k not in ("job", "job_size")} for r in rows]
        statuses = {r["status"] for r in rows}
        if ERROR in statuses:
            d.status = CRASHED
            d.reason = next(r["message"] for r in rows if r["status"] == ERROR)
        elif statuses <= {PASS, UNRESOLVED}:  # a check float32 cannot resolve is reported, not failed
            d.status = PASSED
        else:
            d.status = FAILED
            d.reason = ", ".join(sorted({r["check"] for r in rows if r["status"] in (FAIL, DIVERGED)}))


def _statistical_only(d: Draw) -> bool:
    failing = [r for r in d.rows if r["status"] in (FAIL, DIVERGED)]
    return d.status == FAILED and bool(failing) and all(r.get("claim") == "statistical" for r in failing)


def second_sample_seed(first: Value) -> int:
    """An independent sampling seed for a draw whose sample was seeded with `first` (deterministic)."""
    return int(np.random.default_rng([int(first), 1]).integers(0, 2**53))


def second_samples(draws: Sequence[Draw], settings: Settings | None) -> dict[int, Job]:
    """The re-runs on an independent sample of every draw that failed only statistical tests (module docstring),
    by the draw's position in `draws`; a scenario without a `SAMPLE_SEED` parameter gets none (its failure stands)."""
    out = {}
    for i, d in enumerate(draws):
        if d.job is None or not _statistical_only(d):
            continue
        scenario = d.job.scenario
        seed = next((p for p in scenario.params if p.name == SAMPLE_SEED), None)
        if seed is None:
            continue
        first = d.params.get(SAMPLE_SEED, scenario.defaults()[SAMPLE_SEED])
        params = {**d.params, SAMPLE_SEED: float(second_sample_seed(first))}
        out[i] = check_job(Job(scenario, d.case, params, variant=f"census {d.index} second sample"), settings)
    return out


def settle_second(draws: Sequence[Draw], jobs: Mapping[int, Job], result: RunResult) -> None:
    """A draw whose second sample passed every check passes (the first sample's failure was chance); otherwise it
    stays failed, its reason saying the second sample failed too."""
    for i, job in jobs.items():
        d = draws[i]
        rows = result.rows.get(job.key)
        if rows is None:  # interrupted before it ran
            continue
        statuses = {r["status"] for r in rows}
        passed = statuses <= {PASS, UNRESOLVED}
        d.second = {
            "params": dict(job.overrides),
            "status": PASSED if passed else FAILED,
            "first_failed": d.reason,
            "failed": sorted({r["check"] for r in rows if r["status"] not in (PASS, UNRESOLVED)}),
        }
        if passed:
            d.status = PASSED
        else:
            d.reason += " (and on an independent second sample: " + ", ".join(d.second["failed"]) + ")"


def statistics(draws: Sequence[Draw]) -> tuple[int, int, float]:
    """Statistical tests run on first samples, how many failed, and how many a correct simulation fails on average
    (the sum of their levels, ``false_alarm``)."""
    rows = [r for d in draws for r in d.rows if r.get("claim") == "statistical"]  # first samples' rows
    failed = sum(1 for r in rows if r["status"] == FAIL)
    return len(rows), failed, float(sum(r.get("false_alarm", 0.0) for r in rows))


# ---- reporting ------------------------------------------------------------------------------------------------


def tally(draws: Sequence[Draw]) -> dict[str, dict[str, Any]]:
    """Per scenario: drawn, refused (and by reason), passed, failed, crashed, not run."""
    out: dict[str, dict[str, Any]] = {}
    for d in draws:
        t = out.setdefault(
            d.scenario,
            {"drawn": 0, REFUSED: 0, PASSED: 0, FAILED: 0, CRASHED: 0, "not run": 0, "refusals": {}},
        )
        t["drawn"] += 1
        t[d.status or "not run"] += 1
        if d.status == REFUSED:
            t["refusals"][d.reason] = t["refusals"].get(d.reason, 0) + 1
    return out


def table(draws: Sequence[Draw]) -> str:
    """The census as text: one line per scenario, then the refusal reasons and every failing or crashed draw."""
    counts = tally(draws)
    header = ("scenario", "drawn", REFUSED, PASSED, FAILED, CRASHED)
    lines = [(s, *(str(t[k]) for k in header[1:])) for s, t in counts.items()]
    total = ("total", *(str(sum(t[k] for t in counts.values())) for k in header[1:]))
    widths = [max(len(x) for x in col) for col in zip(header, *lines, total, strict=True)]
    fmt = "  ".join(f"{{:<{widths[0]}}}" if i == 0 else f"{{:>{w}}}" for i, w in enumerate(widths))
    out = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    out += [fmt.format(*line) for line in lines]
    out += [fmt.format(*("-" * w for w in widths)), fmt.format(*total)]
    refusals = [(s, reason, k) for s, t in counts.items() for reason, k in t["refusals"].items()]
    if refusals:
        out += ["", "refused (before simulating), by reason:"]
        out += [f"  {s}: {k} x {reason}" for s, reason, k in refusals]
    tests, failed, expected = statistics(draws)
    if tests:
        out += [
            "",
            f"statistical tests: {failed} of {tests} failed on the first sample (a correct simulation fails "
            f"{expected:.2g} on average)"
            + ("; a draw failing only these is re-run on an independent sample:" if failed else ""),
        ]
        out += [
            f"  {d.second['status']} on the second sample ({d.second['first_failed']} failed on the first): "
            f"{d.command()}"
            for d in draws
            if d.second is not None
        ]
    bad = [d for d in draws if d.status in (FAILED, CRASHED)]
    if bad:
        out += ["", "failed and crashed draws (each line reproduces one):"]
        for d in bad:
            out.append(f"  {d.status.upper()} {d.reason}")
            out.append(f"    {d.command()}")
            for r in d.rows:
                if r["status"] in (FAIL, DIVERGED):
                    if r["status"] == DIVERGED:
                        out.append(f"      {r['check']}: diverged at t = {r['diverged_at']:.4g} s")
                    else:
                        out.append(
                            f"      {r['check']}: measured {r['measured']:.10g}, expected {r['expected']:.10g} "
                            f"{r['unit']}, {r['tolerance_kind']} error {r['error']:.2e} > {r['tolerance']:.1e}"
                        )
    return "\n".join(out)


def document(draws: Sequence[Draw], *, n: int, seed: int, profile: str, complete: bool) -> dict[str, Any]:
    """The census as a JSON document (`rigidbench census --json`)."""
    import mujoco

    from rigidbench import __version__

    return {
        "kind": "census",
        "rigidbench": __version__,
        "mujoco": mujoco.__version__,
        "n": n,
        "seed": seed,
        "profile": profile,
        "complete": complete,
        "scenarios": tally(draws),
        "draws": [d.record() for d in draws],
    }


def clean(draws: Sequence[Draw]) -> bool:
    """0 failed and 0 crashed."""
    return not any(d.status in (FAILED, CRASHED) for d in draws)
