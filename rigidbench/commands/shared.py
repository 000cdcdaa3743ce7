"""What several verbs share: their option groups (settings, jobs, a sweep's grid), argument types, and the helpers
that turn parsed arguments into settings and print or write results.

Nothing heavy is imported at the top: the parser is built from these on every start (`rigidbench --version`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any, TextIO

from rigidbench.exits import UsageError


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive finite number, got {text!r}")
    return value


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {text!r}")
    return value


def nonnegative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return value


def targets_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "targets", nargs="*", metavar="TARGET", help="'scenario' or 'scenario:case' (default: every scenario)"
    )


def jobs_argument(p: argparse.ArgumentParser, what: str) -> None:
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
        type=positive_int,
        metavar="N",
        help=f"{what} (default: the CPUs available; capped there, so timings never share a core); "
        "results are the same for any N",
    )


def quiet_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def grid_arguments(p: argparse.ArgumentParser) -> None:
    """The grid of a sweep (and of a frontier, its view)."""
    from rigidbench.settings import INTEGRATORS

    targets_argument(p)
    p.add_argument("--integrators", nargs="+", metavar="NAME", help=f"default: all of {', '.join(INTEGRATORS)}")
    p.add_argument(
        "--timesteps",
        nargs="+",
        type=positive_float,
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
    quiet_argument(p)
    settings_arguments(p, grid=True)


def settings_arguments(p: argparse.ArgumentParser, *, grid: bool = False) -> None:
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
        p.add_argument("--timestep", type=positive_float, metavar="SECONDS", help="shorthand for --option timestep=")


def sets_argument(p: argparse.ArgumentParser, help: str) -> None:
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE", help=help)


def defaults(arguments, verb: str) -> argparse.Namespace:
    """A verb's arguments as given with nothing on the command line (what ``--resume`` compares with)."""
    parser = argparse.ArgumentParser(prog="rigidbench")
    arguments(parser.add_subparsers(dest="command"))
    return parser.parse_args([verb])


def settings(args: argparse.Namespace):
    """The command's settings (`runner.settings_for`), from its settings arguments."""
    from rigidbench import runner
    from rigidbench.settings import Settings

    options = parse_pairs(args.options, "--option")
    for name in ("solref", "solimp"):
        if getattr(args, name, None):
            options[name] = getattr(args, name)
    merged = runner.settings_for(
        args.profile,
        getattr(args, "integrator", None),
        getattr(args, "timestep", None),
        settings_from=args.settings_from,
        options=options,
    )
    return merged.merged(Settings(engine=args.engine, device=args.device, precision=args.precision))


def parse_pairs(items: Sequence[str], option: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise UsageError(f"{option} expects NAME=VALUE, got {item!r}")
        out[name.strip()] = value.strip()
    return out


def parse_sets(items: Sequence[str]) -> dict[str, str]:
    return parse_pairs(items, "--set")


def workers(requested: int | None, option: str = "--jobs") -> int:
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


def human(*paths: str | None) -> TextIO:
    """Where the human-readable table goes: standard output, unless a machine output is written there (``-``)."""
    return sys.stderr if "-" in paths else sys.stdout


def dumps(doc: dict[str, Any]) -> str:
    """A JSON document as every verb writes it (one-space indent, NaN and numpy values made JSON)."""
    import json

    from rigidbench.results import _jsonable

    return json.dumps(_jsonable(doc), indent=1) + "\n"


def progress(i: int, n: int, job) -> None:
    print(f"[{i + 1}/{n}] {job.key} ...", file=sys.stderr, flush=True)


def say(text: str) -> None:
    print(text, file=sys.stderr)


def journaled_run(args: argparse.Namespace, arguments, verb: str, invocation, plan):
    """`rigidbench.session.run` of a `verb` that runs jobs (``run``, ``census``): its journal, ``--resume``, cluster,
    workers and progress, from the verb's `args` (`invocation`: the arguments a resumed journal must match)."""
    from rigidbench import session

    return session.run(
        verb,
        invocation,
        given=session.invocation(args, invocation),
        default=session.invocation(defaults(arguments, verb), invocation),
        resume=args.resume,
        jsonl=args.jsonl,
        plan=plan,
        cluster=args.cluster,
        workers=lambda: workers(args.jobs),
        progress=None if args.quiet else progress,
        say=None if args.quiet else say,
    )
