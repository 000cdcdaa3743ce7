"""The ``rigidbench`` command line.

Exit status (README "CI"): 0 when every check passed; 1 when any check failed, a simulation diverged or a case
raised an error (each in its row); 2 for bad usage, a parameter set outside the theory's domain, an output that
cannot be written or a journal that cannot be used (one line on stderr naming it, no traceback); 130 when
interrupted by Ctrl-C (SIGINT), 143 by SIGTERM, after writing every finished row (``--jsonl`` journals them as
they finish, ``--resume`` continues; ``--json`` and ``--junit`` say the run is incomplete).
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import signal
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any, TextIO

EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    """Bad command-line input; reported in one line with exit status 2."""


def _parser() -> argparse.ArgumentParser:
    from rigidbench import __version__

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
    _settings_arguments(p_run)
    p_run.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a parameter (SI units; vectors comma-separated, e.g. omega=0.1,5,0.1); repeatable",
    )
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
    _jobs_argument(p_run, "cases simulated at once, on threads")

    p_sweep = sub.add_parser(
        "sweep",
        help="errors over integrators x timesteps (x parameters) and the observed order of convergence",
        description="Run every check of the targets over integrators x timesteps (x swept parameter values) and "
        "fit the observed order of convergence (rule: rigidbench.sweep.observed_order). Default grid: all four "
        "integrators x dt_ref * 2^k, k = -3..9 (fewer below 0 for long cases), dt_ref the case's reference "
        "timestep (which follows its parameters).",
    )
    _grid_arguments(p_sweep)
    _jobs_argument(p_sweep, "worker processes")
    p_sweep.add_argument("--errors", action="store_true", help="also print the error at every grid point")

    p_frontier = sub.add_parser(
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
    _grid_arguments(p_frontier)
    _jobs_argument(p_frontier, "worker processes (each times its own points; at most one per CPU)")
    p_frontier.add_argument(
        "--target-error",
        nargs="+",
        type=float,
        metavar="E",
        help="errors to find the cheapest settings for (default: 1e-3 1e-6 1e-9)",
    )
    p_frontier.add_argument("--markdown", metavar="PATH", help="write the cheapest-settings table as Markdown")
    p_frontier.add_argument("--figures", metavar="DIR", help="write one speed-accuracy plot per scenario (PNG)")

    p_census = sub.add_parser(
        "census",
        help="draw N valid parameter sets per scenario, run them, tally passed/failed/refused/crashed",
        description="Draw N valid parameter sets per scenario from the ranges 'rigidbench list' prints "
        "(log-uniform, with a third of the draws near the ends of the ranges; seeded), run each under the "
        "profile, and print per scenario: drawn, refused before simulating (by reason), passed, failed, crashed, "
        "with a command reproducing every failing draw. Exit 0 when nothing failed or crashed, 1 otherwise.",
    )
    p_census.add_argument(
        "targets", nargs="*", metavar="TARGET", help="'scenario' or 'scenario:case' (default: every scenario)"
    )
    p_census.add_argument("--n", type=_positive_int, default=20, help="draws per target (default 20)")
    p_census.add_argument("--seed", type=_nonnegative_int, default=0, help="seed of the draws (default 0)")
    _settings_arguments(p_census)
    p_census.add_argument("--json", metavar="PATH", help="write every draw, its verdict and the tally as JSON")
    p_census.add_argument(
        "--jsonl", metavar="PATH", help="journal: append each finished draw's rows as JSON lines (resumable)"
    )
    p_census.add_argument("--resume", metavar="PATH", help="continue the census journaled in PATH")
    p_census.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    _jobs_argument(p_census, "cases simulated at once, on threads")

    p_power = sub.add_parser(
        "power",
        help="the benchmark's detection limit: smallest perturbation of a simulated quantity that fails a check",
        description="For every physical quantity of each scenario's model (body masses and inertias, g, spring "
        "constants, friction, contact stiffness), simulate a copy scaled by 1 + delta against the prediction of "
        "the unperturbed model, for delta = 1e-2, 1e-3, ... 1e-8 (stopping at the first delta no check catches), "
        "and print the smallest delta detected, the checks that caught it, and the delta at which the theory "
        "itself moves by a tolerance. Exit 0 (the table is the result).",
    )
    p_power.add_argument("targets", nargs="*", metavar="SCENARIO", help="scenarios (default: every scenario)")
    _settings_arguments(p_power)
    p_power.add_argument("--json", metavar="PATH", help="write the limits as JSON")
    p_power.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    _jobs_argument(p_power, "cases simulated at once, on threads")

    p_compare = sub.add_parser(
        "compare",
        help="regressions between two runs: each check's error before and after, newly failing or passing",
        description="Match the checks of two 'rigidbench run --json' results (e.g. a pinned baseline and a run on a "
        "new MuJoCo) and print each one that changed: newly failing or passing, error grown or shrunk by more than "
        "the noise band (errors at round-off never count), rows missing on either side. Exit 1 when anything is "
        "newly failing, regressed or missing, 0 otherwise.",
    )
    p_compare.add_argument("base", metavar="BASE.json", help="the baseline results")
    p_compare.add_argument("new", metavar="NEW.json", help="the results to check against it")
    p_compare.add_argument(
        "--band",
        type=float,
        default=2.0,
        metavar="FACTOR",
        help="noise band: an error counts as changed when it moves by more than this factor (default 2)",
    )
    p_compare.add_argument("--markdown", metavar="PATH", help="also write the table as Markdown (a CI job summary)")
    p_compare.add_argument("--json", metavar="PATH", help="also write every check's comparison as JSON")

    p_report = sub.add_parser(
        "report",
        help="one self-contained HTML page: results table, settings, figures, convergence",
        description="Build one self-contained HTML page (figures embedded as PNG, no external resources). Results "
        "come from --from files (rigidbench run --json / sweep --json); with no run results among them, the "
        "targets are simulated under the reference profile first.",
    )
    p_report.add_argument(
        "targets", nargs="*", metavar="TARGET", help="scenarios to simulate when no run results are given"
    )
    p_report.add_argument("--out", required=True, metavar="PATH", help="the HTML file to write")
    p_report.add_argument(
        "--from",
        dest="sources",
        nargs="+",
        default=[],
        metavar="JSON",
        help="results of 'rigidbench run --json', 'sweep --json', 'power --json' and/or 'census --json'",
    )
    p_report.add_argument("--figures", metavar="DIR", help="also write every figure as a PNG file into DIR")
    p_report.add_argument(
        "--clips", action="store_true", help="also embed a short GIF of each scenario (needs OpenGL and Pillow)"
    )
    p_report.add_argument("--quiet", action="store_true", help="no progress lines on stderr")

    p_render = sub.add_parser(
        "render",
        help="render a case headless to .gif, .mp4 (needs ffmpeg) or .png",
        description="Simulate a case (as 'run' does) and render it offscreen (EGL, or OSMesa as a fallback) with "
        "a camera that frames the whole motion. The clip spans the whole run in slow motion.",
    )
    p_render.add_argument("target", metavar="TARGET", help="'scenario' (its first case) or 'scenario:case'")
    p_render.add_argument("--out", required=True, metavar="FILE", help="output file: .gif, .mp4 or .png")
    _settings_arguments(p_render)
    p_render.add_argument(
        "--set", dest="sets", action="append", default=[], metavar="NAME=VALUE", help="override a parameter"
    )
    p_render.add_argument("--frames", type=int, default=90, help="frames over the run (default 90)")
    p_render.add_argument("--fps", type=_positive_float, default=30.0, help="playback frames per second (default 30)")
    p_render.add_argument("--size", default="480x360", metavar="WxH", help="pixels (default 480x360)")
    p_render.add_argument("--at", type=float, metavar="SECONDS", help="for .png: the simulated time (default 0)")
    p_render.add_argument("--no-trail", action="store_true", help="do not draw the centre-of-mass trail")
    return parser


def _jobs_argument(p: argparse.ArgumentParser, what: str) -> None:
    """One name for "how many at once" on every command (``--workers`` is kept as an alias), and where."""
    p.add_argument(
        "--cluster",
        metavar="ADDRESS",
        help="run the jobs on a Dask cluster: a scheduler's address (tcp://host:8786) or local:N (N worker processes "
        "here); needs the 'cluster' extra. Without it nothing of Dask is imported",
    )
    p.add_argument(
        "--jobs",
        "--workers",
        dest="jobs",
        type=_positive_int,
        metavar="N",
        help=f"{what} (default: the CPUs available; capped there, so timings never share a core); "
        "results are the same for any N",
    )


def _grid_arguments(p: argparse.ArgumentParser) -> None:
    """The grid of a sweep (and of a frontier, its view)."""
    from rigidbench.settings import INTEGRATORS

    p.add_argument(
        "targets", nargs="*", metavar="TARGET", help="'scenario' or 'scenario:case' (default: every scenario)"
    )
    p.add_argument("--integrators", nargs="+", metavar="NAME", help=f"default: all of {', '.join(INTEGRATORS)}")
    p.add_argument(
        "--timesteps",
        nargs="+",
        type=_positive_float,
        metavar="SECONDS",
        help="default: dt_ref * 2^k, k = -3..9, per case",
    )
    p.add_argument(
        "--param",
        dest="params",
        action="append",
        default=[],
        metavar="NAME=V1,V2,...",
        help="sweep a numeric parameter over these values (SI units), e.g. stiffness=1e5,1e6,1e7; repeatable",
    )
    p.add_argument(
        "--stiffness", metavar="K1,K2,...", help="shorthand for --param stiffness=K1,K2,... (contact scenarios)"
    )
    p.add_argument("--json", metavar="PATH", help="write every point's rows (and the analysis) as JSON")
    p.add_argument(
        "--jsonl", metavar="PATH", help="journal: append each finished point's rows as JSON lines (resumable)"
    )
    p.add_argument(
        "--resume", metavar="PATH", help="skip the points already journaled in PATH (same grid) and append the rest"
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    _settings_arguments(p, grid=True)


def _settings_arguments(p: argparse.ArgumentParser, *, grid: bool = False) -> None:
    """The options every simulating command takes to choose its settings (merged in the order listed)."""
    from rigidbench.settings import FLAGS, INTEGRATORS, OPTIONS, profile_names

    p.add_argument(
        "--profile",
        default="reference",
        help=f"settings profile: {', '.join(profile_names())}, or a profile file (*.toml) (default: reference)",
    )
    p.add_argument(
        "--settings-from",
        metavar="MODEL.xml[#CLASS]",
        help="take <option>, <flag> and the default class's contact softness from your own MJCF",
    )
    p.add_argument(
        "--option",
        dest="options",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help=f"a MuJoCo option ({', '.join(OPTIONS)}), a flag (NAME=enable|disable: {', '.join(FLAGS)}), or "
        "solref=A,B / solimp=A,B,C[,D,E] for every contact and equality constraint; repeatable",
    )
    p.add_argument(
        "--engine",
        choices=("mujoco", "warp", "mjx"),
        help="what steps the models: C MuJoCo (default), MuJoCo Warp (float32; the 'warp' extra) or MJX (JAX; the "
        "'mjx' extra)",
    )
    p.add_argument("--device", metavar="DEVICE", help="the engine's device: cpu (default), cuda:0, ...")
    p.add_argument(
        "--precision", choices=("float32", "float64"), help="the engine's float precision (MJX: float32 by default)"
    )
    p.add_argument("--solref", metavar="A,B", help="shorthand for --option solref=A,B")
    p.add_argument("--solimp", metavar="A,B,C[,D,E]", help="shorthand for --option solimp=...")
    if not grid:
        p.add_argument("--integrator", help=f"shorthand for --option integrator=NAME: {', '.join(INTEGRATORS)}")
        p.add_argument("--timestep", type=_positive_float, metavar="SECONDS", help="shorthand for --option timestep=")


def _settings(args: argparse.Namespace):
    """The command's settings (`runner.settings_for`), from its settings arguments."""
    from rigidbench import runner

    options = _parse_pairs(args.options, "--option")
    for name in ("solref", "solimp"):
        if getattr(args, name, None):
            options[name] = getattr(args, name)
    from rigidbench.settings import Settings

    settings = runner.settings_for(
        args.profile,
        getattr(args, "integrator", None),
        getattr(args, "timestep", None),
        settings_from=args.settings_from,
        options=options,
    )
    return settings.merged(Settings(engine=args.engine, device=args.device, precision=args.precision))


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive finite number, got {text!r}")
    return value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {text!r}")
    return value


def _nonnegative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return value


def _parse_sets(items: Sequence[str]) -> dict[str, str]:
    return _parse_pairs(items, "--set")


def _parse_pairs(items: Sequence[str], option: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise UsageError(f"{option} expects NAME=VALUE, got {item!r}")
        out[name.strip()] = value.strip()
    return out


def _parse_sweeps(items: Sequence[str], stiffness: str | None) -> dict[str, list[float]]:
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


def _grid(args: argparse.Namespace, kind: str):
    """Plan and run a sweep grid (`sweep`, and `frontier`, which also times every point), journaled and resumable.

    Returns (points, result, elapsed seconds), or an exit status if interrupted.
    """
    from rigidbench import journal, outputs, runner, sweep

    outputs.check_all(
        [("--json", args.json), ("--jsonl", args.jsonl or args.resume), ("--markdown", getattr(args, "markdown", None))]
    )
    workers = _workers(args.jobs, "--jobs")
    path = args.resume or args.jsonl
    with journal.lock(path, create=not args.resume) if path else contextlib.nullcontext():
        try:
            points = sweep.plan(
                args.targets,
                integrators=args.integrators,
                timesteps=args.timesteps,
                params=_parse_sweeps(args.params, args.stiffness),
                base=_settings(args),
            )
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        if not points:
            raise UsageError("the grid is empty: give at least one target, integrator and timestep")
        finished: dict[str, list[dict]] = {}
        invocation = {kind: [sweep.point_key(p) for p in points]}
        if args.resume:
            record = journal.read(args.resume, kind)
            journal.warn(record)
            if record.invocation != invocation:
                raise UsageError(f"journal {args.resume} holds a different {kind} grid; give the same targets and grid")
            sweep.verify_journal(args.resume, record)
            journal.truncate_tail(args.resume, record)
            for job, rows in record.by_job().items():
                finished[job] = [runner.strip(r) for r in rows]
        elif path:
            journal.start(path, kind, invocation)

        def on_result(point: sweep.Point, rows: list[dict]) -> None:
            if path:
                journal.append(path, sweep.point_key(point), rows)

        t0 = time.perf_counter()
        executor = runner.executor_for(args.cluster, workers, processes=True)
        try:
            result = sweep.execute(
                points,
                workers=workers,
                progress=None if args.quiet else sweep.progress_line,
                finished=finished,
                on_result=on_result,
                timed=kind == "frontier",
                executor=executor,
            )
        except runner.Interrupted as exc:
            print(
                f"rigidbench: {kind} interrupted by {exc.name}; finished points are in "
                f"{path or '(nowhere: use --jsonl)'}",
                file=sys.stderr,
            )
            return exc.status
        finally:
            executor.close()
    return points, result, time.perf_counter() - t0


def _cmd_sweep(args: argparse.Namespace) -> int:
    import mujoco

    from rigidbench import sweep

    ran = _grid(args, "sweep")
    if isinstance(ran, int):
        return ran
    points, result, elapsed = ran
    out = _human(args.json)
    if args.errors:
        print(sweep.error_table(result), file=out)
        print(file=out)
    print(sweep.order_table(result.orders), file=out)
    print(f"\nmujoco {mujoco.__version__}; {len(points)} points in {elapsed:.1f} s", file=out)
    if args.json:
        sweep.write_json(args.json, result)
    return EXIT_OK


def _cmd_frontier(args: argparse.Namespace) -> int:
    from rigidbench import frontier, outputs, simulate

    targets = args.target_error or list(frontier.TARGET_ERRORS)
    for e in targets:
        if not (e > 0 and e < float("inf")):
            raise UsageError(f"--target-error = {e!r} must be a positive number")
    machine = simulate.machine()
    ran = _grid(args, "frontier")
    if isinstance(ran, int):
        return ran
    points, result, elapsed = ran
    machine["load_after"] = simulate.machine()["load"]
    machine["jobs"] = _workers(args.jobs, "--jobs")
    settings = frontier.settings_of(result.rows)
    frontier.mark_fronts(settings)
    references = frontier.references({s.scenario for s in settings})
    answers = [a for e in targets for a in frontier.cheapest(settings, e, references)]
    out = _human(args.json, args.markdown)
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
        outputs.write(args.json, _dumps(doc), "--json")
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


def _workers(requested: int | None, option: str) -> int:
    """Workers to use: `requested`, capped at the CPUs this process may use (saying so), or all of them."""
    from rigidbench import runner

    cpus = runner.default_workers()
    if requested is None:
        return cpus
    if requested < 1:
        raise UsageError(f"{option} = {requested} must be >= 1")
    if requested > cpus:
        print(f"rigidbench: {option} {requested} capped at the {cpus} CPUs available", file=sys.stderr)
        return cpus
    return requested


def _human(*paths: str | None) -> TextIO:
    """Where the human-readable table goes: standard output, unless a machine output is written there (``-``)."""
    return sys.stderr if "-" in paths else sys.stdout


def _cmd_compare(args: argparse.Namespace) -> int:
    from rigidbench import compare, outputs

    outputs.check_all([("--markdown", args.markdown), ("--json", args.json)])
    try:
        base, new = compare.load(args.base), compare.load(args.new)
        changes = compare.compare(base["results"], new["results"], args.band)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    print(compare.table(changes, base, new, args.band), file=_human(args.markdown, args.json))
    if args.markdown:
        outputs.write(args.markdown, compare.markdown(changes, base, new, args.band), "--markdown")
    if args.json:
        doc = {"kind": "compare", "band": args.band, "changes": [c.record() for c in changes]}
        outputs.write(args.json, _dumps(doc), "--json")
    return EXIT_FAIL if compare.regressed(changes) else EXIT_OK


def _cmd_report(args: argparse.Namespace) -> int:
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


def _cmd_render(args: argparse.Namespace) -> int:
    import os
    import subprocess

    from rigidbench import outputs, render

    outputs.check_all([("--out", args.out)])
    try:
        settings = _settings(args)
        width, _, height = args.size.lower().partition("x")
        try:
            size = (int(width), int(height))
        except ValueError:
            raise ValueError(f"--size expects WxH in pixels, got {args.size!r}") from None
        scenario, cases = _target(args.target)
        overrides = {n: scenario.param(n).parse(v) for n, v in _parse_sets(args.sets).items()}
        if os.path.splitext(args.out)[1].lower() not in render.FORMATS:
            raise ValueError(f"--out {args.out!r}: the extension must be one of {', '.join(render.FORMATS)}")
        still = os.path.splitext(args.out)[1].lower() == ".png"
        clip = render.render_clip(
            f"{scenario.slug}:{cases[0]}",
            overrides=overrides,
            settings=settings,
            frames=args.frames,
            fps=args.fps,
            width=size[0],
            height=size[1],
            at=(args.at or 0.0) if still else None,
            trail=not args.no_trail,
        )
        print(render.write(clip, args.out))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    except render.RenderError as exc:
        # EGL is what `import rigidbench` picks without a display; OSMesa is the software fallback. A backend
        # is chosen once per process, so the retry is a fresh process.
        if (
            isinstance(exc, render.NoGLContext)
            and os.environ.get("MUJOCO_GL") == "egl"
            and not os.environ.get("RIGIDBENCH_NO_GL_FALLBACK")
        ):
            print(f"rigidbench: {exc}; retrying with MUJOCO_GL=osmesa", file=sys.stderr)
            env = {**os.environ, "MUJOCO_GL": "osmesa", "PYOPENGL_PLATFORM": "osmesa", "RIGIDBENCH_NO_GL_FALLBACK": "1"}
            return subprocess.run([sys.executable, "-m", "rigidbench", *sys.argv[1:]], env=env, check=False).returncode
        print(f"rigidbench: error: {exc}", file=sys.stderr)
        return EXIT_FAIL
    return EXIT_OK


def _target(target: str):
    from rigidbench import registry

    return registry.parse_target(target)


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
            budget = " (budget: a census draws it up to its default)" if p.budget else ""
            print(f"    {p.name:<14} [{p.unit}]  default {dtext}  range {p.range_text()}{budget}  {p.doc}")
        print("  cases:")
        for c in sc.cases:
            print(f"    {c.name:<18} {c.doc}")
            if c.ranges:
                ranges = ", ".join(f"{name} in {bound}" for name, bound in c.ranges.items())
                print(f"    {'':<18} regime: {ranges} ({c.regime})")
        if sc.domains:
            print("  domains (refused outside, before simulating):")
            for d in sc.domains:
                where = f" [cases {', '.join(d.cases)}]" if d.cases else ""
                print(f"    {d.name}{where}: {d.text} ({d.theory})")
        print("  checks:")
        for ch in sc.checks:
            print(f"    {ch.name:<24} tol {ch.tolerance:.3g} {ch.kind:<3}  [{ch.theory}]")
        print()
    return EXIT_OK


# What a journal restores on --resume: what to run, never where to write (issue 20), with the types it must have.
_SETTINGS_INVOCATION = {
    "engine": ((str, type(None)), None),
    "device": ((str, type(None)), None),
    "precision": ((str, type(None)), None),
    "profile": (str, None),
    "settings_from": ((str, type(None)), None),
    "options": (list, str),
    "solref": ((str, type(None)), None),
    "solimp": ((str, type(None)), None),
}
_RUN_INVOCATION = {
    "targets": (list, str),
    "sets": (list, str),
    "integrator": ((str, type(None)), None),
    "timestep": ((float, int, type(None)), None),
    **_SETTINGS_INVOCATION,
}
_CENSUS_INVOCATION = {"targets": (list, str), "n": (int, None), "seed": (int, None), **_SETTINGS_INVOCATION}


def _invocation(args: argparse.Namespace, schema: dict = _RUN_INVOCATION) -> dict:
    return {key: getattr(args, key) for key in schema}


def _restore(args: argparse.Namespace, path: str, record, schema: dict) -> None:
    """Set what to run from a journal's invocation onto `args`, refusing anything else or of the wrong type."""
    from rigidbench.journal import JournalError

    invocation = record.invocation
    unknown = sorted(set(invocation) - set(schema))
    if unknown:
        raise JournalError(
            f"{path}:1: the invocation holds {', '.join(map(repr, unknown))}, which a journal does not record"
        )
    for key, (kind, item) in schema.items():
        if key not in invocation:
            raise JournalError(f"{path}:1: the invocation has no {key!r}")
        value = invocation[key]
        bad = not isinstance(value, kind) or isinstance(value, bool) and kind in (int, float)
        if not bad and item is not None:
            bad = not all(isinstance(v, item) for v in value)
        if bad:
            raise JournalError(f"{path}:1: the invocation's {key!r} is {value!r}, not what a run records")
        setattr(args, key, value)


def _session(
    args: argparse.Namespace,
    kind: str,
    schema: dict,
    plan: Callable[[], tuple[Any, list]],
) -> tuple[Any, list, Any, str | None]:
    """The journaled run every command shares: lock the journal, restore what to run from it (--resume) or start
    it (--jsonl), plan (every input validated before anything is simulated), check a resumed journal's rows
    against the plan, and run the jobs not yet done (`runner.run_jobs`).

    Returns (settings, jobs, result, journal path).
    """
    from rigidbench import journal, runner

    path = args.resume or args.jsonl
    with journal.lock(path, create=not args.resume) if path else contextlib.nullcontext():
        record = None
        if args.resume:
            record = journal.read(args.resume, kind)
            journal.warn(record)
            default = _invocation(_parser().parse_args([kind]), schema)
            given = _invocation(args, schema)
            if given != default and given != record.invocation:
                raise UsageError("--resume takes what to run from the journal; give no targets, parameters or settings")
            _restore(args, args.resume, record, schema)
        try:
            settings, jobs = plan()
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        previous: dict = {}
        if record is not None:
            journal.verify(args.resume, record, runner.expected_rows(jobs, settings))
            journal.truncate_tail(args.resume, record)
            previous = record.by_job()
            if not args.quiet:
                done = sum(job.key in previous for job in jobs)
                print(f"resuming: {done} of {len(jobs)} cases already done", file=sys.stderr)
        elif path:
            journal.start(path, kind, _invocation(args, schema))
        executor = runner.executor_for(
            args.cluster, _workers(args.jobs, "--jobs"), settings=settings, jobs=len(jobs) - len(previous)
        )
        try:
            with _mujoco_warnings():
                result = runner.run_jobs(
                    jobs,
                    settings,
                    journal_path=path,
                    previous=previous,
                    progress=None if args.quiet else _progress,
                    executor=executor,
                )
        finally:
            executor.close()
    return settings, jobs, result, path


@contextlib.contextmanager
def _mujoco_warnings():
    """Collect MuJoCo's warnings (printed by default, one per blown-up step) while the block runs, and say in one
    line how many there were; each diverged case says so in its own row."""
    import mujoco

    seen: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(seen.append)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(previous)
        if seen:
            first = " ".join(seen[0].split())
            print(f"rigidbench: MuJoCo warned {len(seen)} time(s) (first: {first})", file=sys.stderr)


def _cmd_run(args: argparse.Namespace) -> int:
    from rigidbench import outputs, results, runner

    outputs.check_all([("--json", args.json), ("--junit", args.junit), ("--jsonl", args.jsonl or args.resume)])

    def plan():
        settings = _settings(args)
        return settings, runner.plan(args.targets, _parse_sets(args.sets), settings)

    t0 = time.perf_counter()
    _, jobs, result, path = _session(args, "run", _RUN_INVOCATION, plan)
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
        _write(args, rows, completion)
        return result.interrupted.status
    out = _human(args.json, args.junit)
    print(results.table(rows), file=out)
    print(file=out)
    if rows:
        elapsed = time.perf_counter() - t0
        s = rows[0]["settings"]
        print(f"mujoco {s['mujoco']}, profile {args.profile}; {results.summary(rows)} in {elapsed:.1f} s", file=out)
    _write(args, rows, completion)
    scored = [r for r in rows if r["status"] not in (results.UNSUPPORTED, results.UNRESOLVED)]
    return EXIT_OK if scored and all(r["status"] == results.PASS for r in scored) else EXIT_FAIL


def _progress(i: int, n: int, job) -> None:
    print(f"[{i + 1}/{n}] {job.key} ...", file=sys.stderr, flush=True)


def _cmd_census(args: argparse.Namespace) -> int:
    import mujoco

    from rigidbench import census, outputs

    outputs.check_all([("--json", args.json), ("--jsonl", args.jsonl or args.resume)])
    drawn: list = []

    def plan():
        settings = _settings(args)
        if not args.quiet:
            print("drawing and checking parameter sets ...", file=sys.stderr, flush=True)
        draws, jobs = census.plan(args.targets, n=args.n, seed=args.seed, settings=settings)
        drawn.extend(draws)
        return settings, jobs

    t0 = time.perf_counter()
    _, jobs, result, _path = _session(args, "census", _CENSUS_INVOCATION, plan)
    census.settle(drawn, result)
    out = _human(args.json)
    print(census.table(drawn), file=out)
    print(
        f"\nmujoco {mujoco.__version__}, profile {args.profile}, seed {args.seed}, n {args.n}; "
        f"{len(jobs)} simulated in {time.perf_counter() - t0:.1f} s",
        file=out,
    )
    if args.json:
        doc = census.document(
            drawn, n=args.n, seed=args.seed, profile=args.profile, complete=result.interrupted is None
        )
        outputs.write(args.json, _dumps(doc), "--json")
    if result.interrupted is not None:
        print(f"rigidbench: census interrupted by {result.interrupted.name}", file=sys.stderr)
        return result.interrupted.status
    return EXIT_OK if census.clean(drawn) else EXIT_FAIL


def _cmd_power(args: argparse.Namespace) -> int:
    import mujoco

    from rigidbench import outputs, power, runner

    outputs.check_all([("--json", args.json)])
    try:
        settings = _settings(args)
        pairs = power.plan(args.targets, settings)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    t0 = time.perf_counter()
    # on MJX the cases of each delta's round are gathered into batches (`runner.Gathered`)
    executor = runner.executor_for(
        args.cluster, _workers(args.jobs, "--jobs"), settings=settings, jobs=runner.GATHER_WIDTH
    )

    def say(delta: float, alive: int) -> None:
        if not args.quiet:
            print(f"delta = {delta:.0e}: {alive} quantities", file=sys.stderr, flush=True)

    try:
        with _mujoco_warnings():
            limits, interrupted = power.walk(pairs, settings, executor, progress=say)
    finally:
        executor.close()
    out = _human(args.json)
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
        outputs.write(args.json, _dumps(doc), "--json")
    if interrupted is not None:
        print(f"rigidbench: power interrupted by {interrupted.name}", file=sys.stderr)
        return interrupted.status
    return EXIT_OK


def _dumps(doc: dict) -> str:
    import json

    from rigidbench.results import _jsonable

    return json.dumps(_jsonable(doc), indent=1) + "\n"


def _raise_interrupted(signum: int, _frame: object) -> None:
    # never rigidbench.runner: it may be half imported right now. The signal is noted first: the exception may come
    # out wrapped by the code it landed in (ctypes, during `import mujoco`'s EGL probing, turns it into an
    # ArgumentError) or be swallowed (`rigidbench.interrupt.check`).
    from rigidbench import interrupt

    interrupt.note(signum)
    raise interrupt.Interrupted(signum)


def _quiet_interrupted(previous, unraisable) -> None:
    """`sys.unraisablehook` during a command: the handler's exception, raised inside a callback that cannot pass it
    on (importlib's module-lock weakref callback, JAX's garbage-collection callback), is not printed as "Exception
    ignored ... Traceback": `_raise_interrupted` noted the signal, and the run loop or `main` raises it again."""
    from rigidbench.interrupt import Interrupted

    if isinstance(unraisable.exc_value, Interrupted):
        return
    previous(unraisable)


def _write(args: argparse.Namespace, rows: list[dict], completion) -> None:
    from rigidbench import results

    if args.json:
        results.write_json(args.json, rows, completion)
    if args.junit:
        results.write_junit(args.junit, rows, completion)


def main(argv: Sequence[str] | None = None, *, last: bool = False) -> int:
    """Run one command; its exit status. `last`: the process ends after it (`entry`), so SIGINT and SIGTERM are left
    at the system default afterwards instead of the handlers found on entry: a SIGINT in the interpreter's last
    moments (atexit callbacks, such as the worker pools' joins) then ends the process with 130 and no output,
    where Python's own handler would print a KeyboardInterrupt traceback. The run's files are whole by then."""
    # Signals first: from here on SIGINT/SIGTERM end the command with one line and 130/143, planning included.
    from rigidbench import interrupt

    interrupt.clear()
    handlers = {sig: signal.signal(sig, _raise_interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
    unraisable_hook = sys.unraisablehook
    sys.unraisablehook = functools.partial(_quiet_interrupted, unraisable_hook)
    try:
        status = _main(argv)
        signum = interrupt.pending()
        if signum is not None and status not in (128 + signal.SIGINT, 128 + signal.SIGTERM):
            # swallowed where it landed (a weakref callback) in a command that never asks again: still 130/143
            raise interrupt.Interrupted(signum)
        return status
    except BaseException as exc:  # noqa: BLE001 - sorted below: everything a user can cause is one line
        from rigidbench.interrupt import Interrupted

        if not isinstance(exc, Interrupted) and interrupt.pending() is not None:
            exc = Interrupted(interrupt.pending())  # raised inside code that wrapped it (e.g. ctypes' ArgumentError)
        if isinstance(exc, Interrupted):
            print(f"rigidbench: interrupted by {exc.name}", file=sys.stderr)
            return exc.status
        if isinstance(exc, UsageError) or _is_one_line(exc):
            print(f"rigidbench: error: {exc}", file=sys.stderr)
            return EXIT_USAGE
        raise
    finally:
        for sig, handler in handlers.items():
            # Python's KeyboardInterrupt handler only: an ignored signal (nohup, a background job) stays ignored
            signal.signal(sig, signal.SIG_DFL if last and handler is signal.default_int_handler else handler)
        sys.unraisablehook = unraisable_hook
        interrupt.clear()  # a later command (or runner call) in this process starts uninterrupted


def _is_one_line(exc: BaseException) -> bool:
    """An error a user's input or machine causes (an output, a journal), reported in one line with status 2."""
    from rigidbench.journal import JournalError
    from rigidbench.outputs import OutputError
    from rigidbench.runner import ClusterError

    return isinstance(exc, (OutputError, JournalError, ClusterError))


def _main(argv: Sequence[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command == "list":
        try:
            return _cmd_list(args)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    commands = {
        "frontier": _cmd_frontier,
        "compare": _cmd_compare,
        "report": _cmd_report,
        "render": _cmd_render,
        "sweep": _cmd_sweep,
        "run": _cmd_run,
        "census": _cmd_census,
        "power": _cmd_power,
    }
    return commands[args.command](args)


def entry() -> None:
    """The `rigidbench` command and `python -m rigidbench`: the command's status is the process's."""
    sys.exit(main(last=True))


if __name__ == "__main__":
    entry()
