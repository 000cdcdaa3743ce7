"""The journaled run a command asks for: lock the journal, restore what to run from it (``--resume``) or start it
(``--jsonl``), plan, check a resumed journal's rows against the plan, and run the jobs not yet done.

The command line (`rigidbench.commands`) only parses its arguments and prints; what a journal holds and how a
resumed run continues lives here, beside the run loop it serves (`rigidbench.runner.run_jobs`, and
`rigidbench.sweep.execute` for a grid). The journal format is `rigidbench.journal`'s.
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from rigidbench import journal, runner
from rigidbench.exits import UsageError

# What a journal restores on --resume: what to run, never where to write (issue 20), with the types it must have.
SETTINGS_INVOCATION = {
    "engine": ((str, type(None)), None),
    "device": ((str, type(None)), None),
    "precision": ((str, type(None)), None),
    "profile": (str, None),
    "settings_from": ((str, type(None)), None),
    "options": (list, str),
    "solref": ((str, type(None)), None),
    "solimp": ((str, type(None)), None),
}
RUN_INVOCATION = {
    "targets": (list, str),
    "sets": (list, str),
    "integrator": ((str, type(None)), None),
    "timestep": ((float, int, type(None)), None),
    **SETTINGS_INVOCATION,
}
CENSUS_INVOCATION = {"targets": (list, str), "n": (int, None), "seed": (int, None), **SETTINGS_INVOCATION}


def invocation(args: Any, schema: Mapping[str, Any]) -> dict[str, Any]:
    """What to run, as a journal records it: the `schema`'s fields of a command's parsed arguments."""
    return {key: getattr(args, key) for key in schema}


def restore(path: str, record: journal.Journal, schema: Mapping[str, Any]) -> dict[str, Any]:
    """A journal's invocation, refusing anything a journal does not record or of the wrong type.

    Raises
    ------
    rigidbench.journal.JournalError
        Naming the file and the field.
    """
    recorded = record.invocation
    unknown = sorted(set(recorded) - set(schema))
    if unknown:
        raise journal.JournalError(
            f"{path}:1: the invocation holds {', '.join(map(repr, unknown))}, which a journal does not record"
        )
    out = {}
    for key, (kind, item) in schema.items():
        if key not in recorded:
            raise journal.JournalError(f"{path}:1: the invocation has no {key!r}")
        value = recorded[key]
        bad = not isinstance(value, kind) or isinstance(value, bool) and kind in (int, float)
        if not bad and item is not None:
            bad = not all(isinstance(v, item) for v in value)
        if bad:
            raise journal.JournalError(f"{path}:1: the invocation's {key!r} is {value!r}, not what a run records")
        out[key] = value
    return out


@dataclass
class Session:
    """What a journaled run produced: its settings, its jobs, the run loop's result and the journal's path."""

    settings: Any
    jobs: list
    result: runner.RunResult
    path: str | None


def run(
    kind: str,
    schema: Mapping[str, Any],
    *,
    given: Mapping[str, Any],
    default: Mapping[str, Any],
    resume: str | None,
    jsonl: str | None,
    plan: Callable[[dict[str, Any] | None], tuple[Any, list]],
    cluster: str | None,
    workers: Callable[[], int],
    progress: Callable[[int, int, runner.Job], None] | None = None,
    say: Callable[[str], None] | None = None,
) -> Session:
    """The journaled run every job command shares (``run``, ``census``).

    Parameters
    ----------
    kind : str
        The journal's kind (`rigidbench.journal.KINDS`).
    schema : mapping
        What the journal records of the invocation (`RUN_INVOCATION`, `CENSUS_INVOCATION`).
    given, default : mapping
        The invocation as given, and as the command's defaults give it: a resumed run takes what to run from
        its journal, so `given` must be one of `default` or the journal's.
    resume, jsonl : str or None
        The journal to continue, or to start.
    plan : callable
        The restored invocation (or None when not resuming) -> (settings, jobs); every input validated before
        anything is simulated. A ValueError is a usage error.
    cluster : str or None
        ``--cluster``.
    workers : callable
        -> how many jobs at once (called after planning).
    progress, say : callable, optional
        Each finished job; a line for the user (the resumed count).

    Raises
    ------
    UsageError
        For targets or settings given with ``--resume``, or an invalid plan.
    """
    path = resume or jsonl
    with journal.lock(path, create=not resume) if path else contextlib.nullcontext():
        record = None
        restored = None
        if resume:
            record = journal.read(resume, kind)
            journal.warn(record)
            if dict(given) != dict(default) and dict(given) != record.invocation:
                raise UsageError("--resume takes what to run from the journal; give no targets, parameters or settings")
            restored = restore(resume, record, schema)
        try:
            settings, jobs = plan(restored)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        previous: dict = {}
        if record is not None:
            journal.verify(resume, record, runner.expected_rows(jobs, settings))
            journal.truncate_tail(resume, record)
            previous = record.by_job()
            if say is not None:
                done = sum(job.key in previous for job in jobs)
                say(f"resuming: {done} of {len(jobs)} cases already done")
        elif path:
            journal.start(path, kind, given)
        executor = runner.executor_for(cluster, workers(), settings=settings, jobs=len(jobs) - len(previous))
        try:
            with mujoco_warnings():
                result = runner.run_jobs(
                    jobs, settings, journal_path=path, previous=previous, progress=progress, executor=executor
                )
        finally:
            executor.close()
    return Session(settings, jobs, result, path)


def grid(
    kind: str,
    plan: Callable[[], list],
    *,
    resume: str | None,
    jsonl: str | None,
    cluster: str | None,
    workers: int,
    progress: Callable | None = None,
) -> tuple[list, Any, float]:
    """A sweep's grid (``sweep``, and ``frontier``, which also times every point), journaled and resumable.

    Returns (points, `rigidbench.sweep.Sweep`, elapsed seconds).

    Raises
    ------
    UsageError
        For an invalid or empty grid, or a journal of another grid.
    rigidbench.runner.Interrupted
        On SIGINT or SIGTERM; the finished points are journaled.
    """
    from rigidbench import sweep

    path = resume or jsonl
    with journal.lock(path, create=not resume) if path else contextlib.nullcontext():
        try:
            points = plan()
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        if not points:
            raise UsageError("the grid is empty: give at least one target, integrator and timestep")
        finished: dict[str, list[dict]] = {}
        recorded = {kind: [sweep.point_key(p) for p in points]}
        if resume:
            record = journal.read(resume, kind)
            journal.warn(record)
            if record.invocation != recorded:
                raise UsageError(f"journal {resume} holds a different {kind} grid; give the same targets and grid")
            sweep.verify_journal(resume, record)
            journal.truncate_tail(resume, record)
            for job, rows in record.by_job().items():
                finished[job] = [runner.strip(r) for r in rows]
        elif path:
            journal.start(path, kind, recorded)

        def on_result(point: sweep.Point, rows: list[dict]) -> None:
            if path:
                journal.append(path, sweep.point_key(point), rows)

        t0 = time.perf_counter()
        executor = runner.executor_for(cluster, workers, processes=True)
        try:
            result = sweep.execute(
                points,
                workers=workers,
                progress=progress,
                finished=finished,
                on_result=on_result,
                timed=kind == "frontier",
                executor=executor,
            )
        finally:
            executor.close()
    return points, result, time.perf_counter() - t0


@contextlib.contextmanager
def mujoco_warnings() -> Iterator[None]:
    """Collect MuJoCo's warnings (printed by default, one per blown-up step) while the block runs, and say in one
    line how many there were; each diverged case says so in its own row."""
    import mujoco

    seen: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(seen.append)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(previous)
        if seen:
            first = " ".join(seen[0].split())
            print(f"rigidbench: MuJoCo warned {len(seen)} time(s) (first: {first})", file=sys.stderr)
