"""``rigidbench run``: simulate and score against theory; journaled (``--jsonl``) and resumable (``--resume``)."""

from __future__ import annotations

import argparse
import sys
import time

from rigidbench.commands import shared
from rigidbench.exits import EXIT_FAIL, EXIT_OK


def arguments(sub) -> None:
    p = sub.add_parser("run", help="simulate and score against theory")
    shared.targets_argument(p)
    shared.settings_arguments(p)
    shared.sets_argument(
        p, "override a parameter (SI units; vectors comma-separated, e.g. omega=0.1,5,0.1); repeatable"
    )
    p.add_argument("--json", metavar="PATH", help="write the results as JSON")
    p.add_argument(
        "--jsonl", metavar="PATH", help="journal: append each finished row as a JSON line as the run goes (resumable)"
    )
    p.add_argument(
        "--resume",
        metavar="PATH",
        help="continue the run journaled in PATH (its targets and settings), skipping "
        "finished cases; new rows are appended to PATH",
    )
    p.add_argument("--junit", metavar="PATH", help="write the results as JUnit XML")
    shared.quiet_argument(p)
    p.add_argument(
        "--brief",
        action="store_true",
        help="print only the rows that did not pass (failed, diverged, unresolved, crashed) and the summary line",
    )
    shared.jobs_argument(p, "cases simulated at once, on threads")


def main(args: argparse.Namespace) -> int:
    from rigidbench import outputs, results, runner, session

    outputs.check_all([("--json", args.json), ("--junit", args.junit), ("--jsonl", args.jsonl or args.resume)])

    def plan(restored):
        if restored is not None:
            vars(args).update(restored)
        settings = shared.settings(args)
        return settings, runner.plan(args.targets, shared.parse_sets(args.sets), settings)

    t0 = time.perf_counter()
    ran = shared.journaled_run(args, arguments, "run", session.RUN_INVOCATION, plan)
    jobs, result, path = ran.jobs, ran.result, ran.path
    rows = result.ordered()
    completion = results.Completion(
        len(jobs), tuple(job.key for job in result.missing), result.interrupted and result.interrupted.name
    )
    if result.interrupted is not None:
        print(
            f"rigidbench: interrupted by {result.interrupted.name} after {len(jobs) - len(result.missing)} of "
            f"{len(jobs)} cases; finished rows are in {path or args.json or '(nowhere: use --jsonl)'}",
            file=sys.stderr,
        )
        write(args, rows, completion)
        return result.interrupted.status
    out = shared.human(args.json, args.junit)
    shown = [r for r in rows if r["status"] not in (results.PASS, results.UNSUPPORTED)] if args.brief else rows
    if shown or not args.brief:
        print(results.table(shown), file=out)
        print(file=out)
    if rows:
        elapsed = time.perf_counter() - t0
        s = rows[0]["settings"]
        print(f"mujoco {s['mujoco']}, profile {args.profile}; {results.summary(rows)} in {elapsed:.1f} s", file=out)
    write(args, rows, completion)
    scored = [r for r in rows if r["status"] not in (results.UNSUPPORTED, results.UNRESOLVED)]
    return EXIT_OK if scored and all(r["status"] == results.PASS for r in scored) else EXIT_FAIL


def write(args: argparse.Namespace, rows: list[dict], completion) -> None:
    """The run's machine outputs (``--json``, ``--junit``), written atomically (`rigidbench.outputs`)."""
    from rigidbench import results

    if args.json:
        results.write_json(args.json, rows, completion)
    if args.junit:
        results.write_junit(args.junit, rows, completion)
