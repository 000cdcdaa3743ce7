"""``rigidbench report``: one self-contained HTML page of results, settings, figures and convergence."""

from __future__ import annotations

import argparse

from rigidbench.commands import shared
from rigidbench.exits import EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser(
        "report",
        help="one self-contained HTML page: results table, settings, figures, convergence",
        description="Build one self-contained HTML page (figures embedded as PNG, no external resources). Results "
        "come from --from files (rigidbench run --json / sweep --json); with no run results among them, the "
        "targets are simulated under the reference profile first.",
    )
    p.add_argument("targets", nargs="*", metavar="TARGET", help="scenarios to simulate when no run results are given")
    p.add_argument("--out", required=True, metavar="PATH", help="the HTML file to write")
    p.add_argument(
        "--from",
        dest="sources",
        nargs="+",
        default=[],
        metavar="JSON",
        help="results of 'rigidbench run --json', 'sweep --json', 'power --json' and/or 'census --json'",
    )
    p.add_argument("--figures", metavar="DIR", help="also write every figure as a PNG file into DIR")
    p.add_argument(
        "--clips", action="store_true", help="also embed a short GIF of each scenario (needs OpenGL and Pillow)"
    )
    shared.quiet_argument(p)


def main(args: argparse.Namespace) -> int:
    from rigidbench import outputs, plots, report, results, runner

    outputs.check_all([("--out", args.out)])
    try:
        runs, sweeps, audits = report.load(args.sources)
        jobs = runner.plan(args.targets, {}, runner.settings_for("reference")) if not runs else []
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    try:
        plots.pyplot()
    except plots.MissingDependency as exc:
        raise UsageError(str(exc)) from None
    say = None if args.quiet else report.progress_line
    if jobs:

        def progress(i: int, n: int, job) -> None:
            if say:
                say(f"[{i + 1}/{n}] {job.name}")

        result = runner.run_jobs(jobs, runner.settings_for("reference"), progress=progress)
        if result.interrupted is not None:
            raise result.interrupted
        runs = [results.document(result.ordered())]
    text = report.build(runs, sweeps, audits, progress=say, figure_dir=args.figures, clips=args.clips)
    report.write(args.out, text)
    print(f"{args.out}: {len(text) / 1e6:.2f} MB, {text.count('<img ')} figures")
    return EXIT_OK
