"""``rigidbench power``: the benchmark's detection limit, the smallest perturbation of a simulated quantity that
fails a check."""

from __future__ import annotations

import argparse
import sys
import time

from rigidbench.commands import shared
from rigidbench.exits import EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser(
        "power",
        help="the benchmark's detection limit: smallest perturbation of a simulated quantity that fails a check",
        description="For every physical quantity of each scenario's model (body masses and inertias, g, spring "
        "constants and damping, the inverse-square strength, friction, contact stiffness and damping, a turning "
        "platform's rate, an applied load), simulate a copy scaled by 1 + delta against the prediction of "
        "the unperturbed model (a rate or a load: the simulated start state or controls computed from it), for "
        "delta = 1e-2, 1e-3, ... 1e-8 (stopping at the first delta no check catches), "
        "and print the smallest delta detected, the checks that caught it, and the delta at which the theory "
        "itself moves by a tolerance. Exit 0 (the table is the result).",
    )
    p.add_argument("targets", nargs="*", metavar="SCENARIO", help="scenarios (default: every scenario)")
    shared.settings_arguments(p)
    p.add_argument("--json", metavar="PATH", help="write the limits as JSON")
    shared.quiet_argument(p)
    shared.jobs_argument(p, "cases simulated at once, on threads")


def main(args: argparse.Namespace) -> int:
    import mujoco

    from rigidbench import outputs, power, runner, session

    outputs.check_all([("--json", args.json)])
    try:
        settings = shared.settings(args)
        pairs = power.plan(args.targets, settings)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    t0 = time.perf_counter()
    # on MJX the cases of each delta's round are gathered into batches (`runner.Gathered`)
    executor = runner.executor_for(args.cluster, shared.workers(args.jobs), settings=settings, jobs=runner.GATHER_WIDTH)

    def say(delta: float, alive: int) -> None:
        if not args.quiet:
            print(f"delta = {delta:.0e}: {alive} quantities", file=sys.stderr, flush=True)

    try:
        with session.mujoco_warnings():
            limits, interrupted = power.walk(pairs, settings, executor, progress=say)
    finally:
        executor.close()
    out = shared.human(args.json)
    print(power.table(limits), file=out)
    print(
        f"\nmujoco {mujoco.__version__}, profile {args.profile}; deltas {power.DELTAS[0]:.0e} .. "
        f"{power.DELTAS[-1]:.0e}; {time.perf_counter() - t0:.1f} s",
        file=out,
    )
    if args.json:
        doc = {
            "kind": "power",
            "mujoco": mujoco.__version__,
            "profile": args.profile,
            "complete": interrupted is None,
            "limits": [lim.record() for lim in limits],
        }
        outputs.write(args.json, shared.dumps(doc), "--json")
    if interrupted is not None:
        print(f"rigidbench: power interrupted by {interrupted.name}", file=sys.stderr)
        return interrupted.status
    return EXIT_OK
