"""The ``rigidbench`` command line.

Exit status: 0 when every check passed; 1 when any check failed or a simulation diverged; 2 for bad usage
(one line on stderr naming the problem, no traceback); 130 when interrupted.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

EXIT_OK, EXIT_FAIL, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


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
        print(f"{sc.slug}  ({sc.env_id or 'no gymnasium env'})\n  {sc.title}")
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
            print(f"    {ch.name:<24} tol {ch.tolerance:.3g} {ch.kind:<3}  [{ch.theory}]")
        print()
    return EXIT_OK


def _cmd_run(args: argparse.Namespace) -> int:
    from rigidbench import results, runner

    try:  # every input is validated here, before anything is simulated
        settings = runner.settings_for(args.profile, args.integrator, args.timestep)
        jobs = runner.plan(args.targets, _parse_sets(args.sets), settings)
    except ValueError as exc:
        raise UsageError(str(exc)) from None

    def progress(i: int, n: int, job: runner.Job) -> None:
        if not args.quiet:
            print(f"[{i + 1}/{n}] {job.name} ...", file=sys.stderr, flush=True)

    rows: list[dict] = []
    t0 = time.perf_counter()
    try:
        for batch in runner.execute(jobs, settings, progress=progress):
            rows.extend(batch)
    except KeyboardInterrupt:
        print(f"rigidbench: interrupted after {len(rows)} checks", file=sys.stderr)
        _write(args, rows)
        return EXIT_INTERRUPTED
    print(results.table(rows))
    print()
    if rows:
        s = rows[0]["settings"]
        print(
            f"mujoco {s['mujoco']}, profile {args.profile}; {results.summary(rows)} in {time.perf_counter() - t0:.1f} s"
        )
    _write(args, rows)
    return EXIT_OK if rows and all(r["status"] == results.PASS for r in rows) else EXIT_FAIL


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
        return _cmd_run(args)
    except UsageError as exc:
        print(f"rigidbench: error: {exc}", file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
