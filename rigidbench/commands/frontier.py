"""``rigidbench frontier``: speed against accuracy over a sweep's grid, the Pareto front, and the cheapest settings
for a wanted accuracy."""

from __future__ import annotations

import argparse

from rigidbench.commands import shared
from rigidbench.exits import EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser(
        "frontier",
        help="speed against accuracy: each setting's error and measured cost, the Pareto front, the cheapest "
        "settings for a wanted accuracy",
        description="The sweep's grid (the same flags and settings), with the cost of every point measured: CPU "
        "seconds of stepping per simulated second (only the stepping is timed; >= 0.2 s and >= 3 repeats per "
        "point, median and spread kept). Prints every setting's error (theory checks) and drift (conserved "
        "quantities) against its cost, marks the Pareto front (* where a cost spread makes membership marginal), "
        "and, for each --target-error E, the cheapest setting whose error is at most E and how much cheaper it is "
        "than the scenario's reference settings.",
    )
    shared.grid_arguments(p)
    shared.jobs_argument(p, "worker processes (each times its own points; at most one per CPU)")
    p.add_argument(
        "--target-error",
        nargs="+",
        type=float,
        metavar="E",
        help="errors to find the cheapest settings for (default: 1e-3 1e-6 1e-9)",
    )
    p.add_argument("--markdown", metavar="PATH", help="write the cheapest-settings table as Markdown")
    p.add_argument("--figures", metavar="DIR", help="write one speed-accuracy plot per scenario (PNG)")


def main(args: argparse.Namespace) -> int:
    from rigidbench import frontier, outputs, simulate
    from rigidbench.commands.sweep import grid

    targets = args.target_error or list(frontier.TARGET_ERRORS)
    for e in targets:
        if not (e > 0 and e < float("inf")):
            raise UsageError(f"--target-error = {e!r} must be a positive number")
    machine = simulate.machine()
    ran = grid(args, "frontier")
    if isinstance(ran, int):
        return ran
    points, result, elapsed = ran
    machine["load_after"] = simulate.machine()["load"]
    machine["jobs"] = shared.workers(args.jobs)
    settings = frontier.settings_of(result.rows)
    frontier.mark_fronts(settings)
    references = frontier.references({s.scenario for s in settings})
    answers = [a for e in targets for a in frontier.cheapest(settings, e, references)]
    out = shared.human(args.json, args.markdown)
    print(frontier.table(settings), file=out)
    print(file=out)
    print(frontier.answers_table(answers), file=out)
    load = machine["load"] or ["?"]
    print(
        f"\nmujoco {machine['mujoco']}; {len(points)} points in {elapsed:.1f} s on {machine['cpu']} "
        f"({machine['cpus']} CPUs, {machine['jobs']} at a time, load {load[0]:.2g})",
        file=out,
    )
    doc = frontier.document(result.rows, settings, answers, machine)
    if args.json:
        outputs.write(args.json, shared.dumps(doc), "--json")
    if args.markdown:
        outputs.write(args.markdown, frontier.markdown(doc, answers), "--markdown")
    if args.figures:
        import os

        from rigidbench import report
        from rigidbench.plots.frontier import frontier_figures

        os.makedirs(args.figures, exist_ok=True)
        for fig in frontier_figures(doc):
            slug = fig.title.split(": ", 1)[1]
            outputs.write_bytes(os.path.join(args.figures, f"frontier-{slug}.png"), report.png(fig.figure), "--figures")
    return EXIT_OK
