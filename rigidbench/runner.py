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
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any

import mujoco

from rigidbench import interrupt, registry, shards
from rigidbench.interrupt import Interrupted
from rigidbench.params import Value
from rigidbench.results import ERROR, UNSUPPORTED, rows_of
from rigidbench.scenario import Scenario
from rigidbench.settings import Settings, profile

Perturb = Callable[[mujoco.MjModel], None]


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
    # Why the engine in effect cannot run the job (`rigidbench.engines.EngineRefused`): it yields one row of status
    # ``unsupported`` without simulating.
    unsupported: str | None = field(default=None, compare=False, repr=False)

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
    return dataclasses.replace(
        job, expected=(job.scenario.settings_record(prep.model, settings), len(prep.case.checks))
    )


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
    from rigidbench.engines.base import EngineRefused

    jobs = []
    for target in targets or list(registry.scenarios()):
        scenario, cases = registry.parse_target(target)
        parsed = parse_overrides(scenario, overrides or {})
        for case in cases:
            try:
                jobs.append(check_job(Job(scenario, case, parsed), settings))
            except EngineRefused as exc:
                jobs.append(Job(scenario, case, parsed, unsupported=str(exc)))
    if jobs and all(job.unsupported for job in jobs):
        raise ValueError(jobs[0].unsupported + (f" (and the other {len(jobs) - 1} cases)" if len(jobs) > 1 else ""))
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
    if job.unsupported:
        return [unsupported_row(job, settings)]
    try:
        return rows_of(job.scenario.run(job.case, job.overrides, settings, perturb=job.perturb))
    except ClusterError:  # a sharded case's cluster went away: the run stops, resumable (not this case's error)
        raise
    except Exception as exc:  # noqa: BLE001 - recorded as a row, never swallowed
        return [error_row(job, settings, exc)]


def expected_rows(jobs: Sequence[Job], settings: Settings | None) -> dict[str, tuple[dict[str, Any], int]]:
    """What a resumed journal must hold for each planned job (`rigidbench.journal.verify`): the settings it runs
    with and its number of rows (one for a job the engine does not support)."""
    out = {job.key: job.expected for job in jobs if job.expected}
    out.update({job.key: (unsupported_row(job, settings)["settings"], 1) for job in jobs if job.unsupported})
    return out


def unsupported_row(job: Job, settings: Settings | None) -> dict[str, Any]:
    """The row of a job the engine in effect refused while planning (`Job.unsupported`): nothing simulated."""
    engine = settings.engine_object() if settings is not None else None
    row = {**_no_result(job, settings), "check": "unsupported", "status": UNSUPPORTED, "message": job.unsupported}
    row["settings"].update(engine.record() if engine is not None else {})
    return row


def error_row(job: Job, settings: Settings | None, exc: BaseException) -> dict[str, Any]:
    """The row of a job that raised `exc` instead of producing results."""
    frames = traceback.extract_tb(exc.__traceback__)
    where = f"{os.path.basename(frames[-1].filename)}:{frames[-1].lineno}" if frames else ""
    return {
        **_no_result(job, settings),
        "message": f"{type(exc).__name__}: {exc}" + (f" (at {where})" if where else ""),
    }


def _no_result(job: Job, settings: Settings | None) -> dict[str, Any]:
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
        "theory_ref": None,
        "claim": None,
        "status": ERROR,
        "passed": None,
        "diverged_at": None,
        "settings": {**vars(settings or Settings()), "mujoco": mujoco.__version__},
        "params": dict(job.overrides),
    }


# ---- where jobs run ------------------------------------------------------------------------------------------


class ClusterError(Exception):
    """A Dask cluster that cannot be reached or went away; one line, exit status 2 (the journal keeps every row
    that came back, and ``--resume`` continues)."""


class Threads:
    """Jobs on this process's threads: a case's time goes to `mujoco.rollout`, which steps in C without the GIL, so
    two cores run two cases. The default executor."""

    def __init__(self, workers: int) -> None:
        self.workers = max(1, int(workers))

    def map(self, fn: Callable, calls: Sequence[tuple]) -> Iterator[tuple[int, Any]]:
        """Yield ``(index, fn(*calls[index]))`` as each call finishes (in order with one worker)."""
        if self.workers <= 1 or len(calls) <= 1:
            for i, args in enumerate(calls):
                yield i, fn(*args)
            return
        pool = ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix="rigidbench-case")
        try:
            futures = {pool.submit(fn, *args): i for i, args in enumerate(calls)}
            for future in as_completed(futures):
                yield futures[future], future.result()
        finally:
            pool.shutdown(wait=False, cancel_futures=True)  # an interrupt: drop what has not started

    def close(self) -> None:
        pass


class Gathered(Threads):
    """Jobs on up to `width` threads at once whose MJX or Warp rollouts are gathered into one batch per model
    structure (`rigidbench.engines.Gather`): what a run, a census or a power table does on those engines, where a
    case's time is its program's compile (MJX: 8-24 s on this CPU) or its kernel launches (Warp), and a batch of
    worlds costs little more than one. `width` bounds the cases (their models, predictions and trajectories) held at
    once."""

    def map(self, fn: Callable, calls: Sequence[tuple]) -> Iterator[tuple[int, Any]]:
        from rigidbench.engines.batching import Gather, gathering

        gather = Gather(len(calls), self.workers)

        def member(*args):
            with gather.member_of():
                return fn(*args)

        with gathering(gather):
            try:
                yield from super().map(member, calls)
            finally:
                gather.close()  # an interrupt cancels the calls not started: those running must not wait for them


# Cases gathered at once on MJX (`Gathered`): a census of one scenario (20 draws) or every case of a run fits.
GATHER_WIDTH = 64


class Processes:
    """Jobs in worker processes here (spawned, never forked from a process that may hold GL or threads; each dies
    with this one, `start_worker`): what a sweep or a frontier uses, so that each point is timed in its own
    process."""

    def __init__(self, workers: int) -> None:
        self.workers = max(1, int(workers))

    def map(self, fn: Callable, calls: Sequence[tuple]) -> Iterator[tuple[int, Any]]:
        """Yield ``(index, fn(*calls[index]))`` as each call finishes (in this process with one worker)."""
        if self.workers <= 1:
            for i, args in enumerate(calls):
                yield i, fn(*args)
            return
        import concurrent.futures
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")
        pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=self.workers, mp_context=ctx, initializer=start_worker, initargs=(os.getpid(),)
        )
        try:
            futures = {pool.submit(fn, *args): i for i, args in enumerate(calls)}
            for future in concurrent.futures.as_completed(futures):
                yield futures[future], future.result()
        except BaseException:  # Ctrl-C or a worker's error: drop what has not started, stop what runs
            running = list((getattr(pool, "_processes", None) or {}).values())
            pool.shutdown(wait=False, cancel_futures=True)
            for process in running:
                process.terminate()
            raise
        pool.shutdown()

    def close(self) -> None:
        pass


def start_worker(parent: int) -> None:
    """Set up a worker process: Ctrl-C is the parent's to handle (a terminal sends SIGINT to the whole process
    group; the parent stops the workers), and the worker ends when the process that started it does, even by
    SIGKILL, which runs no cleanup: on Linux the kernel sends it SIGKILL (``prctl(PR_SET_PDEATHSIG)``); elsewhere,
    and in case the parent died before that was set, a daemon thread polls the parent's pid. Without it a killed
    sweep leaves its workers (~120 MB each) and multiprocessing's resource tracker running for ever."""
    import ctypes
    import threading
    import time

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):
        pass

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    if os.getppid() != parent:
        os._exit(1)
    threading.Thread(target=watch, name="rigidbench-watch-parent", daemon=True).start()


class Cluster:
    """Jobs on a Dask cluster: ``local:N`` starts N single-threaded worker processes here; anything else is the
    address of a running scheduler (``tcp://host:8786``, e.g. from ``dask scheduler`` or dask-jobqueue on SLURM).

    Each call is submitted under a key that hashes what it computes (the job, its settings, the rigidbench and
    MuJoCo versions), so a retry or a resubmission never computes a job twice, and a worker that dies has its calls
    recomputed elsewhere by the scheduler. A scheduler that cannot be reached within `CONNECT_TIMEOUT` seconds, or
    that goes away mid-run, is a `ClusterError` (never a hang).
    """

    CONNECT_TIMEOUT = 10.0
    POLL = 2.0

    def __init__(self, address: str) -> None:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise ClusterError("--cluster needs Dask distributed: pip install 'rigidbench[cluster]'") from None
        import logging

        # Dask logs its reconnect attempts with tracebacks; what went wrong reaches the user as one line here.
        for name in ["distributed", "tornado", *logging.root.manager.loggerDict]:
            if name.split(".")[0] in ("distributed", "tornado"):
                logging.getLogger(name).setLevel(logging.CRITICAL)
        self.address = address
        self._cluster = None
        try:
            if address.startswith("local:"):
                n = address.split(":", 1)[1]
                if not n.isdigit() or int(n) < 1:
                    raise ClusterError(f"--cluster {address}: give local:N with N >= 1 workers")
                self._cluster = LocalCluster(
                    n_workers=int(n), threads_per_worker=1, processes=True, dashboard_address=None
                )
                self.client = Client(self._cluster, timeout=self.CONNECT_TIMEOUT)
            else:
                self.client = Client(address, timeout=self.CONNECT_TIMEOUT)
        except ClusterError:
            raise
        except (OSError, TimeoutError, ValueError) as exc:
            self.close()
            raise ClusterError(
                f"--cluster {address}: cannot reach a Dask scheduler ({' '.join(str(exc).split())})"
            ) from None
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))

    def map(self, fn: Callable, calls: Sequence[tuple]) -> Iterator[tuple[int, Any]]:
        """Yield ``(index, fn(*calls[index]))`` as each call finishes on the cluster."""
        from distributed import wait

        keys = [f"rigidbench-{fn.__name__}-{_digest(args)}" for args in calls]
        futures = [self.client.submit(fn, *args, key=key, pure=False) for args, key in zip(calls, keys, strict=True)]
        index = {f.key: i for i, f in enumerate(futures)}
        pending = set(futures)
        try:
            while pending:
                try:
                    done, pending = wait(pending, timeout=self.POLL, return_when="FIRST_COMPLETED")
                except TimeoutError:
                    done = set()
                except Exception as exc:  # noqa: BLE001 - the scheduler went away (cancelled futures, closed comm)
                    raise self._lost(len(calls) - len(pending), len(calls), exc) from None
                if not done and self.client.status != "running":
                    raise self._lost(len(calls) - len(pending), len(calls), None)
                for future in done:
                    if future.status == "error":
                        yield index[future.key], future.exception()
                    elif future.status == "cancelled":
                        raise self._lost(len(calls) - len(pending), len(calls), None)
                    else:
                        yield index[future.key], future.result()
        finally:
            if pending and self.client.status == "running":
                self.client.cancel(list(pending))

    def _lost(self, done: int, total: int, exc: BaseException | None) -> ClusterError:
        why = f" ({type(exc).__name__})" if exc is not None else ""
        return ClusterError(f"--cluster {self.address}: lost the Dask scheduler after {done} of {total} jobs{why}")

    def close(self) -> None:
        client = getattr(self, "client", None)
        if client is not None:
            client.close(timeout=5)
        if self._cluster is not None:
            self._cluster.close(timeout=10)


def _digest(args: tuple) -> str:
    """A hash of what a call computes: its arguments' identity and the versions that compute them."""
    import hashlib

    from rigidbench import __version__

    parts = []
    for a in args:
        if isinstance(a, Job):
            parts.append(a.key)
        elif isinstance(a, Settings):
            parts.append(json.dumps(a.record(), sort_keys=True, default=str))
        else:
            parts.append(json.dumps(getattr(a, "record", lambda a=a: repr(a))(), sort_keys=True, default=str))
    text = "\x1f".join([*parts, __version__, mujoco.__version__])
    return hashlib.sha1(text.encode()).hexdigest()[:20]


def executor_for(
    cluster: str | None, workers: int, *, processes: bool = False, settings: Settings | None = None, jobs: int = 0
) -> Threads | Processes | Cluster:
    """The executor a command asked for: a Dask cluster (``--cluster``), or `workers` threads (or, with
    `processes`, worker processes) here; on MJX or Warp (`settings`) the `jobs` cases gathered into batches
    (`Gathered`, up to `GATHER_WIDTH` at once)."""
    if cluster:
        return Cluster(cluster)
    if processes:
        return Processes(workers)
    if settings is not None and settings.engine in ("mjx", "warp") and jobs > 1:
        return Gathered(min(jobs, GATHER_WIDTH))
    return Threads(workers)


def execute(
    jobs: Sequence[Job],
    settings: Settings | None,
    *,
    progress: Callable[[int, int, Job], None] | None = None,
    workers: int = 1,
    executor: Threads | Processes | Cluster | None = None,
) -> Iterator[tuple[int, list[dict[str, Any]]]]:
    """Run the jobs, yielding ``(index, rows)`` as each job finishes (in job order with one worker).

    Each case is independent and deterministic, so the rows do not depend on the executor or the number of
    workers. Closing the iterator early (an interrupt) cancels the cases not yet started.
    """
    executor = executor or Threads(workers)
    # On a cluster a sharded case (a Monte Carlo batch, `Scenario.sharded`) runs here and maps its shards over the
    # workers (`rigidbench.shards`); every other case is one call on a worker.
    here = [i for i, job in enumerate(jobs) if isinstance(executor, Cluster) and job.scenario.sharded]
    away = [i for i in range(len(jobs)) if i not in set(here)]
    done = 0
    for k, rows in executor.map(run_job, [(jobs[i], settings) for i in away]):
        i = away[k]
        if isinstance(rows, BaseException):  # a job that failed on a cluster (e.g. killed its workers every time)
            rows = [error_row(jobs[i], settings, rows)]
        if progress is not None:
            progress(done, len(jobs), jobs[i])
        done += 1
        yield i, rows
    for i in here:
        with shards.use(executor.map):
            rows = run_job(jobs[i], settings)
        if progress is not None:
            progress(done, len(jobs), jobs[i])
        done += 1
        yield i, rows


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
    executor: Threads | Processes | Cluster | None = None,
) -> RunResult:
    """The one run loop: skip the jobs `previous` (a resumed journal's rows, by job key) holds, run the rest on
    `executor` (threads here by default), append each finished job's rows to the journal at `journal_path` (if
    any) as it finishes, and stop at an interrupt with every finished row kept.

    The journal's header must already be written (`rigidbench.journal.start`) or read (resume).

    Raises
    ------
    ClusterError
        If the cluster went away; every row that came back is journaled.
    """
    from rigidbench import journal

    done = dict(previous or {})
    todo = [job for job in jobs if job.key not in done]
    result = RunResult(list(jobs), done)
    try:
        interrupt.check()  # a signal swallowed while planning (during `import jax`, say): nothing is started
    except Interrupted as exc:
        result.interrupted = exc
        return result
    batches = execute(todo, settings, progress=progress, workers=workers, executor=executor)
    try:
        for i, batch in batches:
            done[todo[i].key] = batch
            if journal_path:
                journal.append(journal_path, todo[i].key, batch)
            interrupt.check()  # a signal whose exception was swallowed where it landed stops the run here
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
