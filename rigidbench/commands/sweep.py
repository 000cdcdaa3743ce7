"""``rigidbench sweep``: errors over integrators x timesteps (x parameters) and the observed order of convergence."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from rigidbench.commands import shared
from rigidbench.exits import EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser(
        "sweep",
        help="errors over integrators x timesteps (x parameters) and the observed order of convergence",
        description="Run every check of the targets over integrators x timesteps (x swept parameter values) and "
        "fit the observed order of convergence (rule: rigidbench.sweep.observed_order). Default grid: all four "
        "integrators x dt_ref * 2^k, k = -3..9 (fewer below 0 for long cases), dt_ref the case's reference "
        "timestep (which follows its parameters).",
    )
    shared.grid_arguments(p)
    shared.jobs_argument(p, "worker processes")
    p.add_argument("--errors", action="store_true", help="also print the error at every grid point")


def main(args: argparse.Namespace) -> int:
    import mujoco

    from rigidbench import sweep

    ran = grid(args, "sweep")
    if isinstance(ran, int):
        return ran
    points, result, elapsed = ran
    out = shared.human(args.json)
    if args.errors:
        print(sweep.error_table(result), file=out)
        print(file=out)
    print(sweep.order_table(result.orders), file=out)
    print(f"\nmujoco {mujoco.__version__}; {len(points)} points in {elapsed:.1f} s", file=out)
    if args.json:
        sweep.write_json(args.json, result)
    return EXIT_OK


def parse_sweeps(items: Sequence[str], stiffness: str | None) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {}
    for item in [*items, *([f"stiffness={stiffness}"] if stiffness else [])]:
        name, sep, values = item.partition("=")
        if not sep or not name.strip() or not values.strip():
            raise UsageError(f"--param expects NAME=V1,V2,..., got {item!r}")
        try:
            out[name.strip()] = [float(v) for v in values.split(",")]
        except ValueError:
            raise UsageError(f"--param {name.strip()}: cannot read {values!r} as comma-separated numbers") from None
    return out


def grid(args: argparse.Namespace, kind: str):
    """Plan and run a sweep grid (`sweep`, and `frontier`, which also times every point), journaled and resumable
    (`rigidbench.session.grid`).

    Returns (points, result, elapsed seconds), or an exit status if interrupted.
    """
    from rigidbench import outputs, runner, session, sweep

    outputs.check_all(
        [("--json", args.json), ("--jsonl", args.jsonl or args.resume), ("--markdown", getattr(args, "markdown", None))]
    )
    workers = shared.workers(args.jobs)

    def plan():
        return sweep.plan(
            args.targets,
            integrators=args.integrators,
            timesteps=args.timesteps,
            params=parse_sweeps(args.params, args.stiffness),
            base=shared.settings(args),
        )

    try:
        return session.grid(
            kind,
            plan,
            resume=args.resume,
            jsonl=args.jsonl,
            cluster=args.cluster,
            workers=workers,
            progress=None if args.quiet else sweep.progress_line,
        )
    except runner.Interrupted as exc:
        print(
            f"rigidbench: {kind} interrupted by {exc.name}; finished points are in "
            f"{args.resume or args.jsonl or '(nowhere: use --jsonl)'}",
            file=sys.stderr,
        )
        return exc.status
