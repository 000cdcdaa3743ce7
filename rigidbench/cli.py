"""The ``rigidbench`` command line.

Exit status: 0 when every check passed; 1 when any check failed or a simulation diverged; 2 for bad usage
(one line on stderr naming the problem, no traceback); 130 when interrupted by Ctrl-C (SIGINT), 143 by SIGTERM,
after writing every finished row (``--jsonl`` journals them as they finish; ``--resume`` continues).
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from collections.abc import Sequence

EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    """Bad command-line input; reported in one line with exit status 2."""


def _parser() -> argparse.ArgumentParser:
    from rigidbench import __version__
    from rigidbench.settings import INTEGRATORS, PROFILES

    parser = argparse.ArgumentParser(
        prog="rigidbench",
        description="Textbook rigid-body scenarios in MuJoCo, scored against closed-form classical mechanics.",
    )
    parser.add_argument("--version", action="version", version=f"rigidbench {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p_list = sub.add_parser("list", help="scenarios, cases, parameters (unit, default, range) and checks")
    p_list.add_argument("scenarios", nargs="*", metavar="SCENARIO", help="only these scenarios")

    p_run = sub.add_parser("run", help="simulate and score against theory")
    p_run.add_argument(
        "targets", nargs="*", metavar="TARGET", help="'scenario' or 'scenario:case' (default: every scenario)"
    )
    p_run.add_argument("--profile", default="reference", help=f"settings profile: {', '.join(PROFILES)}")
    p_run.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a parameter (SI units; vectors comma-separated, e.g. omega=0.1,5,0.1); repeatable",
    )
    p_run.add_argument("--integrator", help=f"override the integrator: {', '.join(INTEGRATORS)}")
    p_run.add_argument("--timestep", type=_positive_float, metavar="SECONDS", help="override the timestep (s)")
    p_run.add_argument("--json", metavar="PATH", help="write the results as JSON")
    p_run.add_argument(
        "--jsonl", metavar="PATH", help="journal: append each finished row as a JSON line as the run goes (resumable)"
    )
    p_run.add_argument(
        "--resume",
        metavar="PATH",
        help="continue the run journaled in PATH (its targets and settings), skipping "
        "finished cases; new rows are appended to PATH",
    )
    p_run.add_argument("--junit", metavar="PATH", help="write the results as JUnit XML")
    p_run.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    return parser


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive finite number, got {text!r}")
    return value


def _parse_sets(items: Sequence[str]) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise UsageError(f"--set expects NAME=VALUE, got {item!r}")
        out[name.strip()] = value.strip()
    return out


def _cmd_list(args: argparse.Namespace) -> int:
    from rigidbench import registry

    chosen = [registry.get(s) for s in args.scenarios] if args.scenarios else list(registry.scenarios().values())
    for sc in chosen:
        print(f"{sc.slug}  ({sc.env_id})\n  {sc.title}")
        defaults = sc.defaults()
        print("  parameters:")
        for p in sc.params:
            d = defaults[p.name]
            dtext = ",".join(f"{x:g}" for x in d) if isinstance(d, tuple) else f"{d:g}"
            print(f"    {p.name:<14} [{p.unit}]  default {dtext}  range {p.valid}  {p.doc}")
        print("  cases:")
        for c in sc.cases:
            print(f"    {c.name:<18} {c.doc}")
        print("  checks:")
        for ch in sc.checks:
            print(f"    {ch.name:<24} tol {ch.tolerance:.0e} {ch.kind:<3}  [{ch.theory}]")
        print()
    return EXIT_OK


def _invocation(args: argparse.Namespace) -> dict:
    return {
        "targets": list(args.targets),
        "profile": args.profile,
        "sets": list(args.sets),
        "integrator": args.integrator,
        "timestep": args.timestep,
    }


def _cmd_run(args: argparse.Namespace) -> int:
    import mujoco

    from rigidbench import journal, results, runner

    previous: list[dict] = []
    journal_path = args.jsonl
    if args.resume:
        try:
            record = journal.read(args.resume)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        given = _invocation(args)
        if given != _invocation(_parser().parse_args(["run"])) and given != record.header["invocation"]:
            raise UsageError("--resume takes the targets and settings from the journal; give no others")
        if record.header["mujoco"] != mujoco.__version__:
            raise UsageError(
                f"journal {args.resume!r} was written with mujoco {record.header['mujoco']}, this is "
                f"{mujoco.__version__}: results would mix versions"
            )
        for key, value in record.header["invocation"].items():
            setattr(args, key, value)
        journal.rewrite(args.resume, record)  # drop a torn tail, if any
        previous, journal_path = record.rows, args.resume
    try:  # every input is validated here, before anything is simulated
        settings = runner.settings_for(args.profile, args.integrator, args.timestep)
        jobs = runner.plan(args.targets, _parse_sets(args.sets), settings)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    done = {r["job"] for r in previous}
    by_job = {job: [r for r in previous if r["job"] == job] for job in done}
    todo = [job for job in jobs if job.name not in done]
    if journal_path and not args.resume:
        journal.start(journal_path, _invocation(args))
    if args.resume and not args.quiet:
        print(f"resuming: {len(jobs) - len(todo)} of {len(jobs)} cases already done", file=sys.stderr)

    def progress(i: int, n: int, job: runner.Job) -> None:
        if not args.quiet:
            print(f"[{i + 1}/{n}] {job.name} ...", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    interrupted = None
    try:
        for job, batch in zip(todo, runner.execute(todo, settings, progress=progress), strict=False):
            by_job[job.name] = batch
            if journal_path:
                journal.append(journal_path, job.name, batch)
    except Interrupted as exc:
        interrupted = exc
    rows = [_strip(r) for job in jobs for r in by_job.get(job.name, [])]
    if interrupted is not None:
        print(
            f"rigidbench: interrupted by {interrupted.name} after {len(by_job)} of {len(jobs)} cases; "
            f"finished rows are in {journal_path or args.json or '(nowhere: use --jsonl)'}",
            file=sys.stderr,
        )
        _write(args, rows)
        return interrupted.status
    print(results.table(rows))
    print()
    if rows:
        s = rows[0]["settings"]
        print(
            f"mujoco {s['mujoco']}, profile {args.profile}; {results.summary(rows)} in {time.perf_counter() - t0:.1f} s"
        )
    _write(args, rows)
    return EXIT_OK if rows and all(r["status"] == results.PASS for r in rows) else EXIT_FAIL


def _strip(row: dict) -> dict:
    return {k: v for k, v in row.items() if k not in ("job", "job_size")}


class Interrupted(BaseException):
    """SIGINT or SIGTERM during a run; the exit status is 128 + the signal number."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.status = 128 + signum
        self.name = signal.Signals(signum).name


def _raise_interrupted(signum: int, _frame: object) -> None:
    raise Interrupted(signum)


def _write(args: argparse.Namespace, rows: list[dict]) -> None:
    from rigidbench import results

    if args.json:
        results.write_json(args.json, rows)
    if args.junit:
        results.write_junit(args.junit, rows)


def main(argv: Sequence[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        if args.command == "list":
            try:
                return _cmd_list(args)
            except ValueError as exc:
                raise UsageError(str(exc)) from None
        handlers = {sig: signal.signal(sig, _raise_interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
        try:
            return _cmd_run(args)
        finally:
            for sig, handler in handlers.items():
                signal.signal(sig, handler)
    except UsageError as exc:
        print(f"rigidbench: error: {exc}", file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
