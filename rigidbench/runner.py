"""The validation runner: targets x profile x overrides -> jobs -> result rows, in one journaled, resumable loop.

Every target, parameter and setting is resolved and validated before the first simulation starts (`plan`), so
bad input costs nothing and never leaves a half-finished run. The loop that runs the jobs (`run_jobs`) is the
one every command shares (`run`, `census`, `power`): it journals each finished job's rows (`rigidbench.journal`),
skips the jobs a resumed journal already holds, reports progress, runs cases on threads, and stops cleanly on
SIGINT/SIGTERM (`Interrupted`). The CLI only parses and prints.
"""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import mujoco

from rigidbench import registry
from rigidbench.params import Value
from rigidbench.results import ERROR, rows_of
from rigidbench.scenario import Scenario
from rigidbench.settings import Settings, profile, read_settings

Perturb = Callable[[mujoco.MjModel], None]


class Interrupted(BaseException):
    """SIGINT or SIGTERM during a run; the exit status is 128 + the signal number."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.status = 128 + signum
        self.name = signal.Signals(signum).name


@dataclass(frozen=True)
class Job:
    """One case of one scenario, with its parameter overrides (already validated), optionally a perturbation of
    the simulated model (`rigidbench.power`) named by `variant`."""

    scenario: Scenario
    case: str
    overrides: Mapping[str, Value] = field(default_factory=dict)
    variant: str = ""
    perturb: Perturb | None = field(default=None, compare=False, repr=False)
    # What planning found (`check_job`): the settings the job runs with, read back from its compiled model, and
    # the number of checks of its case; a resumed journal's rows must match them (`journal.verify`).
    expected: tuple[dict[str, Any], int] | None = field(default=None, compare=False, repr=False)

    @property
    def name(self) -> str:
        return f"{self.scenario.slug}:{self.case}"

    @property
    def key(self) -> str:
        """The job's identity in a journal: its name, plus its own overrides and variant when it has them."""
        key = self.name
        if self.overrides:
            key += " " + json.dumps(dict(sorted(self.overrides.items())), separators=(",", ":"))
        if self.variant:
            key += f" [{self.variant}]"
        return key


def parse_overrides(scenario: Scenario, overrides: Mapping[str, str]) -> dict[str, Value]:
    """Command-line text (``"0.3"``, ``"0.1,5,0.1"``) -> validated values, with the scenario's parameters.

    Raises
    ------
    ValueError
        For an unknown parameter or an invalid value, prefixed with the scenario.
    """
    parsed = {}
    for name, text in overrides.items():
        try:
            parsed[name] = scenario.param(name).parse(text)
        except ValueError as exc:
            raise ValueError(f"{scenario.slug}: {exc}") from None
    return parsed


def check_job(job: Job, settings: Settings | None) -> Job:
    """Everything about a job that can be known without simulating: parameters, the theory's domain, the
    compiled model (e.g. contact stiffness against the timestep), the run's step count and memory.

    Returns
    -------
    Job
        The job with `expected` filled in.

    Raises
    ------
    ValueError
        Prefixed with ``scenario:case``.
    """
    try:
        prep = job.scenario.prepare(job.case, job.overrides, settings)
    except ValueError as exc:
        raise type(exc)(*_prefixed(exc, job.name)) from None
    return dataclasses.replace(job, expected=(read_settings(prep.model), len(prep.case.checks)))


def _prefixed(exc: ValueError, name: str) -> tuple:
    from rigidbench.scenario import OutsideDomain

    message = f"{name}: {exc}"
    return (message, exc.domain) if isinstance(exc, OutsideDomain) else (message,)


def plan(
    targets: Sequence[str],
    overrides: Mapping[str, str] | None = None,
    settings: Settings | None = None,
) -> list[Job]:
    """Expand targets (``scenario`` or ``scenario:case``; none = every scenario) into validated jobs.

    `overrides` maps parameter names to command-line text; each scenario parses them with its own parameter
    definitions. Each job is prepared once under `settings` (`check_job`) so that nothing that can be refused
    is found out mid-run.

    Raises
    ------
    ValueError
        For an unknown scenario, case or parameter, an invalid value, a set outside the theory's domain, or a
        run beyond the step or memory limits (naming it).
    """
    jobs = []
    for target in targets or list(registry.scenarios()):
        scenario, cases = registry.parse_target(target)
        parsed = parse_overrides(scenario, overrides or {})
        for case in cases:
            jobs.append(check_job(Job(scenario, case, parsed), settings))
    return jobs


def settings_for(
    profile_name: str,
    integrator: str | None = None,
    timestep: float | None = None,
    *,
    settings_from: str | None = None,
    options: Mapping[str, str] | None = None,
) -> Settings:
    """The settings a command runs under, merged in this order (each overriding the one before): the profile (a
    name or a profile file), a user's MJCF (`settings.from_model`), ``--option NAME=VALUE`` (including
    ``solref``/``solimp`` and flags), then the shorthands ``--integrator`` and ``--timestep``.

    Raises
    ------
    ValueError
        For an unknown profile, option, flag or value, or a model that cannot be carried over (naming it).
    """
    from rigidbench.settings import from_model

    settings = profile(profile_name)
    if settings_from:
        settings = settings.merged(from_model(settings_from))
    if options:
        settings = settings.merged(Settings.from_options(options))
    return settings.merged(Settings(integrator=integrator, timestep=timestep))


def run_job(job: Job, settings: Settings | None) -> list[dict[str, Any]]:
    """The result rows of one job. An exception other than an interrupt becomes one row of status ``"error"``
    (its type, message and where it was raised), so one broken case never loses the others' rows."""
    try:
        return rows_of(job.scenario.run(job.case, job.overrides, settings, perturb=job.perturb))
    except Exception as exc:  # noqa: BLE001 - recorded as a row, never swallowed
        return [error_row(job, settings, exc)]


def error_row(job: Job, settings: Settings | None, exc: BaseException) -> dict[str, Any]:
    """The row of a job that raised `exc` instead of producing results."""
    frames = traceback.extract_tb(exc.__traceback__)
    where = f"{os.path.basename(frames[-1].filename)}:{frames[-1].lineno}" if frames else ""
    return {
        "scenario": job.scenario.slug,
        "case": job.case,
        "check": "error",
        "unit": "",
        "measured": None,
        "expected": None,
        "error": None,
        "tolerance": None,
        "tolerance_kind": None,
        "tolerance_reason": None,
        "theory": None,
        "status": ERROR,
        "passed": None,
        "diverged_at": None,
        "message": f"{type(exc).__name__}: {exc}" + (f" (at {where})" if where else ""),
        "settings": {**vars(settings or Settings()), "mujoco": mujoco.__version__},
        "params": dict(job.overrides),
    }


def execute(
    jobs: Sequence[Job],
    settings: Settings | None,
    *,
    progress: Callable[[int, int, Job], None] | None = None,
    workers: int = 1,
) -> Iterator[list[dict[str, Any]]]:
    """Run the jobs, yielding each job's result rows in job order as soon as it and every job before it finished.

    With ``workers > 1`` up to that many cases run at once on threads: a case's time goes to
    `mujoco.rollout`, which steps in C without the GIL, so two cores run two cases. Each case is independent
    and deterministic, so the rows are the same as with one worker. Closing the iterator early (an interrupt)
    cancels the cases not yet started; those running finish in the background and are dropped.
    """
    if workers <= 1 or len(jobs) <= 1:
        for i, job in enumerate(jobs):
            if progress is not None:
                progress(i, len(jobs), job)
            yield run_job(job, settings)
        return
    pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="rigidbench-case")
    try:
        futures = [pool.submit(run_job, job, settings) for job in jobs]
        for i, (job, future) in enumerate(zip(jobs, futures, strict=True)):
            if progress is not None:
                progress(i, len(jobs), job)
            yield future.result()
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


@dataclass
class RunResult:
    """What `run_jobs` produced: the rows of every finished job (resumed ones included) and whether it was cut
    short."""

    jobs: list[Job]
    rows: dict[str, list[dict[str, Any]]]
    interrupted: Interrupted | None = None

    def ordered(self) -> list[dict[str, Any]]:
        """Every finished row, in job order (the journal's bookkeeping fields removed)."""
        return [strip(r) for job in self.jobs for r in self.rows.get(job.key, [])]

    @property
    def missing(self) -> list[Job]:
        """The jobs that did not finish (an interrupted run)."""
        return [job for job in self.jobs if job.key not in self.rows]


def run_jobs(
    jobs: Sequence[Job],
    settings: Settings | None,
    *,
    journal_path: str | None = None,
    previous: Mapping[str, list[dict[str, Any]]] | None = None,
    progress: Callable[[int, int, Job], None] | None = None,
    workers: int = 1,
) -> RunResult:
    """The one run loop: skip the jobs `previous` (a resumed journal's rows, by job key) holds, run the rest,
    append each finished job's rows to the journal at `journal_path` (if any) as it finishes, and stop at an
    interrupt with every finished row kept.

    The journal's header must already be written (`rigidbench.journal.start`) or read (resume).
    """
    from rigidbench import journal

    done = dict(previous or {})
    todo = [job for job in jobs if job.key not in done]
    result = RunResult(list(jobs), done)
    batches = execute(todo, settings, progress=progress, workers=workers)
    try:
        for job, batch in zip(todo, batches, strict=False):
            done[job.key] = batch
            if journal_path:
                journal.append(journal_path, job.key, batch)
    except Interrupted as exc:
        result.interrupted = exc
    finally:
        batches.close()  # an interrupt: cases not started are cancelled
    return result


def strip(row: dict) -> dict:
    """A journaled row without the journal's bookkeeping (``job``, ``job_size``)."""
    return {k: v for k, v in row.items() if k not in ("job", "job_size")}


def default_workers() -> int:
    """Cases run at once by default: the CPUs this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
