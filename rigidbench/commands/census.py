"""``rigidbench census``: draw N valid parameter sets per scenario, run them, tally the verdicts."""

from __future__ import annotations

import argparse
import sys
import time

from rigidbench.commands import shared
from rigidbench.exits import EXIT_FAIL, EXIT_OK


def arguments(sub) -> None:
    p = sub.add_parser(
        "census",
        help="draw N valid parameter sets per scenario, run them, tally passed/failed/refused/crashed",
        description="Draw N valid parameter sets per scenario from the ranges 'rigidbench list' prints "
        "(log-uniform, with a third of the draws near the ends of the ranges; seeded), run each under the "
        "profile, and print per scenario: drawn, refused before simulating (by reason), passed, failed, crashed, "
        "with a command reproducing every failing draw. Exit 0 when nothing failed or crashed, 1 otherwise.",
    )
    shared.targets_argument(p)
    p.add_argument("--n", type=shared.positive_int, default=20, help="draws per target (default 20)")
    p.add_argument("--seed", type=shared.nonnegative_int, default=0, help="seed of the draws (default 0)")
    shared.settings_arguments(p)
    p.add_argument("--json", metavar="PATH", help="write every draw, its verdict and the tally as JSON")
    p.add_argument(
        "--jsonl", metavar="PATH", help="journal: append each finished draw's rows as JSON lines (resumable)"
    )
    p.add_argument("--resume", metavar="PATH", help="continue the census journaled in PATH")
    shared.quiet_argument(p)
    shared.jobs_argument(p, "cases simulated at once, on threads")


def main(args: argparse.Namespace) -> int:
    import mujoco

    from rigidbench import census, outputs, session

    outputs.check_all([("--json", args.json), ("--jsonl", args.jsonl or args.resume)])
    drawn: list = []

    def plan(restored):
        if restored is not None:
            vars(args).update(restored)
        settings = shared.settings(args)
        if not args.quiet:
            print("drawing and checking parameter sets ...", file=sys.stderr, flush=True)
        draws, jobs = census.plan(args.targets, n=args.n, seed=args.seed, settings=settings)
        drawn.extend(draws)
        return settings, jobs

    t0 = time.perf_counter()
    ran = shared.journaled_run(args, arguments, "census", session.CENSUS_INVOCATION, plan)
    result = ran.result
    census.settle(drawn, result)
    settings = shared.settings(args)
    second = census.second_samples(drawn, settings) if result.interrupted is None else {}
    if second:  # a draw that failed only statistical tests, on an independent sample (`rigidbench.census`)
        from rigidbench.runner import run_jobs

        if not args.quiet:
            print(f"re-running {len(second)} draw(s) on an independent sample ...", file=sys.stderr, flush=True)
        again = run_jobs(list(second.values()), settings, workers=shared.workers(args.jobs))
        census.settle_second(drawn, second, again)
        result.interrupted = again.interrupted
    out = shared.human(args.json)
    print(census.table(drawn), file=out)
    print(
        f"\nmujoco {mujoco.__version__}, profile {args.profile}, seed {args.seed}, n {args.n}; "
        f"{len(ran.jobs)} simulated in {time.perf_counter() - t0:.1f} s",
        file=out,
    )
    if args.json:
        doc = census.document(
            drawn, n=args.n, seed=args.seed, profile=args.profile, complete=result.interrupted is None
        )
        outputs.write(args.json, shared.dumps(doc), "--json")
    if result.interrupted is not None:
        print(f"rigidbench: census interrupted by {result.interrupted.name}", file=sys.stderr)
        return result.interrupted.status
    return EXIT_OK if census.clean(drawn) else EXIT_FAIL
