"""``rigidbench derivatives``: MuJoCo's Jacobians and the sensitivities of the scenarios' observables, scored against
the linearised closed forms (`rigidbench.derivatives`, issue 37); rows, JSON, JUnit and exit status as ``run``."""

from __future__ import annotations

import argparse
import time

from rigidbench.commands import shared
from rigidbench.exits import EXIT_FAIL, EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser(
        "derivatives",
        help="score MuJoCo's one-step Jacobians, mode frequencies and sensitivities against the linearised theory",
        description="For each case of the smooth scenarios (pendulum, coupled-pendulums, pendulum-chain, "
        "double-pendulum): the one-step transition Jacobian (mjd_transitionFD; centred differences of mj_step for "
        "RK4) against the integrator's own map of the linearised theory, the mode frequencies and shapes of that "
        "map and of mjd_inverseFD's stiffness and mass against O1-O7, and dT/da of the pendulum against O1. "
        "Exit status as `run`.",
    )
    shared.targets_argument(p)
    shared.settings_arguments(p)
    shared.sets_argument(p, "override a parameter (SI units; vectors comma-separated); repeatable")
    p.add_argument("--json", metavar="PATH", help="write the results as JSON")
    p.add_argument("--junit", metavar="PATH", help="write the results as JUnit XML")
    shared.quiet_argument(p)
    p.add_argument("--brief", action="store_true", help="print only the rows that did not pass and the summary line")
    p.add_argument(
        "--census",
        type=shared.positive_int,
        metavar="N",
        help="instead of the cases: N random valid parameter sets per scenario, drawn as `rigidbench census` draws "
        "them; prints the tally (drawn, refused, passed, failed, crashed); exit 1 unless 0 failed and 0 crashed",
    )
    p.add_argument("--seed", type=shared.nonnegative_int, default=1, help="the census's seed (default: 1)")


def main(args: argparse.Namespace) -> int:
    import sys

    from rigidbench import derivatives, outputs, results
    from rigidbench.commands.run import write

    outputs.check_all([("--json", args.json), ("--junit", args.junit)])
    settings = shared.settings(args)
    if settings.engine not in (None, "mujoco"):
        raise UsageError(f"derivatives: engine {settings.engine} is not supported yet (C MuJoCo only)")
    sets = shared.parse_sets(args.sets)
    try:
        pairs = derivatives.plan(args.targets)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    t0 = time.perf_counter()
    if args.census:
        return _census(args, settings, t0)
    from rigidbench.interrupt import Interrupted, check

    rows: list[dict] = []
    stopped: Interrupted | None = None
    for i, (scenario, case) in enumerate(pairs):
        if not args.quiet:
            print(f"{scenario.slug}:{case} ...", file=sys.stderr, flush=True)
        try:
            run = derivatives.run_case(scenario, case, sets or None, settings)
            check()  # a signal whose exception was swallowed stops the run here
        except ValueError as exc:  # invalid parameters or settings, a set outside the theory's domain
            raise UsageError(str(exc)) from None
        except Interrupted as exc:  # the files written say which cases did not run (as `run` does)
            stopped = exc
            not_run = tuple(f"{sc.slug}:{c}" for sc, c in pairs[i:])
            break
        rows += results.rows_of(run)
    if stopped is not None:
        write(args, rows, results.Completion(len(pairs), not_run, stopped.name))
        print(f"rigidbench: derivatives interrupted by {stopped.name}", file=sys.stderr)
        return stopped.status
    out = shared.human(args.json, args.junit)
    shown = [r for r in rows if r["status"] != results.PASS] if args.brief else rows
    if shown or not args.brief:
        print(results.table(shown), file=out)
        print(file=out)
    if rows:
        s = rows[0]["settings"]
        print(
            f"mujoco {s['mujoco']}, profile {args.profile}; {results.summary(rows)} in "
            f"{time.perf_counter() - t0:.1f} s",
            file=out,
        )
    write(args, rows, results.Completion(len(pairs)))
    return EXIT_OK if rows and all(r["status"] == results.PASS for r in rows) else EXIT_FAIL


def _census(args: argparse.Namespace, settings, t0: float) -> int:
    from rigidbench import census, derivatives, outputs

    try:
        draws = derivatives.census(args.targets, n=args.census, seed=args.seed, settings=settings)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    out = shared.human(args.json)
    # each failing draw's line reproduces it with this verb, not `run`
    print(census.table(draws).replace("rigidbench run ", "rigidbench derivatives "), file=out)
    print(f"\nderivative checks, seed {args.seed}; {time.perf_counter() - t0:.1f} s", file=out)
    if args.json:
        doc = census.document(draws, n=args.census, seed=args.seed, profile=args.profile, complete=True)
        doc["kind"] = "derivatives-census"
        outputs.write(args.json, shared.dumps(doc), "--json")
    return EXIT_OK if census.clean(draws) else EXIT_FAIL
