"""Run rigidbench targets on MJX with one or more of MJX's findings patched in this process (docs/engines.md, Findings).

A check that MJX fails where C MuJoCo passes is a finding only once its cause is shown. This script shows it the
direct way: the same target on MJX, once as installed and once with the suspected functions replaced in-process
(nothing on disk changes; ``--patch`` may be given more than once), and every check's error for both. What each
patch replaces:

* ``small-rotation``: `mjx._src.math.norm` treats a vector as zero where ``jnp.allclose(x, 0.0)`` (atol 1e-8), so
  `quat_integrate` never turns a body whose angular velocity components are all below 1e-8 rad/s. Patched, only an
  exactly-zero vector is zero. (ball-stick light-ball on MJX float64: energy 3.99e-5 off, 2.84e-6 patched.)
* ``sphere-box-edge``: `mjx._src.math.closest_segment_point` divides by ``|b - a|^2 + 1e-6`` (absolute m^2), which
  tilts a sphere-box contact past a face's short edge (`benchmarks/mjx_sphere_box.py`); patched, by ``|b - a|^2``.
* ``line-search``: `mjx._src.solver._linesearch` keeps a step only where the total cost fell (``<``); patched, where
  it did not rise (``<=``). Only a probe: it fixes `benchmarks/mjx_linesearch.py`'s states, not every state; the
  whole effect is removed by ``--option warmstart=disable``, which needs no patch.

    python benchmarks/mjx_patched_run.py --patch small-rotation ball-stick:light-ball --precision float64 \\
        --set mass=0.009024128553485023 --set length=96.47017487928969 --set ball_mass=1.301032418032902e-07 \\
        --set ball_speed=0.00013754161961767138 --set offset=22.355119268813667
"""

from __future__ import annotations

import argparse
import inspect
import json
import subprocess
import sys
import textwrap

PATCHES = {
    "small-rotation": ("math", "norm", "is_zero = jp.allclose(x, 0.0)", "is_zero = jp.all(x == 0.0)"),
    "sphere-box-edge": (
        "math",
        "closest_segment_point",
        "t = jp.dot(pt - a, ab) / (jp.dot(ab, ab) + 1e-6)",
        "t = jp.dot(pt - a, ab) / jp.maximum(jp.dot(ab, ab), 1e-30)",
    ),
    "line-search": (
        "solver",
        "_linesearch",
        "improved = (lo.cost < p0.cost) | (hi.cost < p0.cost)",
        "improved = (lo.cost <= p0.cost) | (hi.cost <= p0.cost)",
    ),
}


def patch(name: str) -> None:
    """Replace one MJX function in its module (its source with one line changed), before anything is traced."""
    import importlib

    module_name, function, old, new = PATCHES[name]
    module = importlib.import_module(f"mujoco.mjx._src.{module_name}")
    source = textwrap.dedent(inspect.getsource(getattr(module, function)))
    if old not in source:
        raise SystemExit(f"mjx_patched_run.py: this MJX's {module_name}.{function} no longer has {old!r}")
    exec(compile(source.replace(old, new), module.__file__, "exec"), module.__dict__)  # noqa: S102


def run(targets: list[str], overrides: dict[str, str], precision: str | None, options: dict[str, str]) -> list[dict]:
    """Every check of the targets on MJX, in this process (`options`: as ``rigidbench run --option``)."""
    import dataclasses

    from rigidbench import runner
    from rigidbench.settings import Settings

    settings = dataclasses.replace(Settings.from_options(options), engine="mjx", precision=precision)
    jobs = runner.plan(targets, overrides, settings)
    keep = ("scenario", "case", "check", "error", "tolerance", "status")
    return [{k: row[k] for k in keep} for job in jobs for row in runner.run_job(job, settings)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("targets", nargs="+", help="scenario or scenario:case")
    parser.add_argument("--patch", choices=sorted(PATCHES), action="append", required=True, help="repeatable")
    parser.add_argument("--precision", choices=("float32", "float64"), default=None)
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="a parameter override")
    parser.add_argument("--option", action="append", default=[], metavar="NAME=VALUE", help="as rigidbench run's")
    parser.add_argument("--worker", choices=("plain", "patched"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    try:
        import mujoco.mjx  # noqa: F401
    except ImportError:
        parser.exit(2, "mjx_patched_run.py: needs MJX: pip install 'rigidbench[mjx]'\n")
    for flag, items in (("--set", args.set), ("--option", args.option)):
        bad = [item for item in items if "=" not in item]
        if bad:
            parser.error(f"{flag} {bad[0]!r}: expected NAME=VALUE")
    options = dict(item.split("=", 1) for item in args.option)
    if args.worker:  # one of the two runs, in a process of its own (a compiled program keeps what it traced)
        if args.worker == "patched":
            for name in args.patch:
                patch(name)
        overrides = dict(item.split("=", 1) for item in args.set)
        try:
            rows = run(args.targets, overrides, args.precision, options)
        except ValueError as exc:  # an unknown target, parameter or option, a refused case: one line
            parser.exit(2, f"mjx_patched_run.py: {exc}\n")
        print(json.dumps(rows))
        return
    rows = []
    for mode in ("plain", "patched"):
        out = subprocess.run(
            [sys.executable, __file__, *sys.argv[1:], "--worker", mode], capture_output=True, text=True
        )
        if out.returncode != 0:  # the worker's own last line (above it: JAX's and Warp's warnings)
            lines = [line for line in out.stderr.splitlines() if line.strip()]
            parser.exit(out.returncode, (lines[-1] if lines else f"worker exited {out.returncode}") + "\n")
        rows.append(json.loads(out.stdout.splitlines()[-1]))
    also = f"; both runs with options {options}" if options else ""
    patched = ", ".join(f"{name!r} ({PATCHES[name][0]}.{PATCHES[name][1]}: {PATCHES[name][3]})" for name in args.patch)
    print(f"MJX with {patched} patched{also}")
    print(f"{'target':32s} {'check':24s} {'as installed':>18s} {'patched':>18s} {'tolerance':>10s}")
    for before, after in zip(*rows, strict=True):
        target = f"{before['scenario']}:{before['case']}"
        print(
            f"{target:32s} {before['check']:24s} {before['error']:>10.3g} {before['status']:>7s} "
            f"{after['error']:>10.3g} {after['status']:>7s} {before['tolerance']:>10.3g}"
        )


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:  # the workers get the same signal and stop; nothing is written
        sys.exit("mjx_patched_run.py: interrupted")
