"""The validation runner: targets x profile x overrides -> result rows.

Every target, parameter and setting is resolved and validated before the first simulation starts, so bad
input costs nothing and never leaves a half-finished run.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

from rigidbench import registry
from rigidbench.results import rows_of
from rigidbench.scenario import Scenario
from rigidbench.settings import Settings, profile


@dataclass(frozen=True)
class Job:
    """One case of one scenario, with its parameter overrides (already validated)."""

    scenario: Scenario
    case: str
    overrides: Mapping[str, Any]

    @property
    def name(self) -> str:
        return f"{self.scenario.slug}:{self.case}"


def plan(
    targets: Sequence[str],
    overrides: Mapping[str, str] | None = None,
    settings: Settings | None = None,
) -> list[Job]:
    """Expand targets (``scenario`` or ``scenario:case``; none = every scenario) into validated jobs.

    `overrides` maps parameter names to command-line text (``"0.3"``, ``"0.1,5,0.1"``); each scenario parses
    them with its own parameter definitions. Each job's model is compiled once under `settings` so that
    settings-dependent checks (`Scenario.check_model`) fail here too.

    Raises
    ------
    ValueError
        For an unknown scenario, case or parameter, or an invalid value (naming it).
    """
    overrides = dict(overrides or {})
    jobs = []
    for target in targets or list(registry.scenarios()):
        scenario, cases = registry.parse_target(target)
        parsed = {}
        for name, text in overrides.items():
            try:
                parsed[name] = scenario.param(name).parse(text)
            except ValueError as exc:
                raise ValueError(f"{scenario.slug}: {exc}") from None
        for case in cases:
            try:
                params = scenario.resolve(scenario.case(case), parsed)
                scenario.build(params, settings)  # compile-time checks, e.g. contact stiffness vs timestep
            except ValueError as exc:
                raise ValueError(f"{scenario.slug}:{case}: {exc}") from None
            jobs.append(Job(scenario, case, parsed))
    return jobs


def settings_for(profile_name: str, integrator: str | None = None, timestep: float | None = None) -> Settings:
    """The named profile with command-line overrides on top.

    Raises
    ------
    ValueError
        For an unknown profile or integrator, or a timestep outside (0, 0.1] s.
    """
    return profile(profile_name).merged(Settings(integrator=integrator, timestep=timestep))


def execute(
    jobs: Sequence[Job],
    settings: Settings,
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
            yield rows_of(job.scenario.run(job.case, job.overrides, settings))
        return
    pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="rigidbench-case")
    try:
        futures = [pool.submit(job.scenario.run, job.case, job.overrides, settings) for job in jobs]
        for i, (job, future) in enumerate(zip(jobs, futures, strict=True)):
            if progress is not None:
                progress(i, len(jobs), job)
            yield rows_of(future.result())
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


def default_workers() -> int:
    """Cases run at once by default: the CPUs this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
