"""MuJoCo version matrix: the reference profile and the tops sweeps on several MuJoCo versions, in one table.

Each MuJoCo version lives in its own virtual environment with rigidbench installed (``pip install -e .
"mujoco==3.17.0"``). This script runs ``rigidbench run --json`` (reference profile, every scenario) and
``rigidbench sweep --json`` (the tops, default grid) with each environment's ``rigidbench`` executable, then merges
the JSON documents into Markdown tables:

1. the reference profile: checks passed per scenario and the worst error / tolerance, per version;
2. the observed order of convergence per check, for RK4 and Euler, per version.

Usage (from the repository root)::

    python3 -m venv /tmp/venv317 && /tmp/venv317/bin/pip install -e . "mujoco==3.17.0"
    python benchmarks/version_matrix.py --venv /tmp/venv317 --venv .venv --out results/matrix

``--merge-only`` skips the runs and merges the ``run-<version>.json`` / ``sweep-<version>.json`` already in --out.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import statistics
import subprocess
import sys
from collections.abc import Sequence

SWEEP_TARGETS = ("heavy-top", "free-asymmetric-top", "free-symmetric-top")
INTEGRATORS = ("RK4", "Euler")


def run_version(venv: str, out: str) -> str:
    """Run the reference profile and the tops sweep with the rigidbench of `venv`; return its MuJoCo version."""
    exe = os.path.join(venv, "bin", "rigidbench")
    python = os.path.join(venv, "bin", "python")
    version = subprocess.run(
        [python, "-c", "import mujoco; print(mujoco.__version__)"], capture_output=True, text=True, check=True
    ).stdout.strip()
    print(f"mujoco {version} ({venv}): reference profile ...", file=sys.stderr, flush=True)
    subprocess.run([exe, "run", "--quiet", "--json", os.path.join(out, f"run-{version}.json")], check=False)
    print(f"mujoco {version}: sweep of {', '.join(SWEEP_TARGETS)} ...", file=sys.stderr, flush=True)
    subprocess.run(
        [exe, "sweep", "--quiet", *SWEEP_TARGETS, "--json", os.path.join(out, f"sweep-{version}.json")],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    return version


def _version_key(v: str) -> tuple[int, ...]:
    return tuple(int(x) if x.isdigit() else 0 for x in v.split("."))


def load(out: str) -> tuple[dict[str, dict], dict[str, dict]]:
    runs, sweeps = {}, {}
    for path in glob.glob(os.path.join(out, "*.json")):
        with open(path) as f:
            doc = json.load(f)
        (sweeps if doc.get("kind") == "sweep" else runs)[doc["mujoco"]] = doc
    return runs, sweeps


def reference_table(runs: dict[str, dict]) -> str:
    versions = sorted(runs, key=_version_key)
    targets: dict[str, dict[str, list]] = {}
    for v in versions:
        for r in runs[v]["results"]:
            targets.setdefault(r["scenario"], {}).setdefault(v, []).append(r)
    head = "| scenario | " + " | ".join(f"mujoco {v}: passed | worst error/tol" for v in versions) + " |"
    sep = "|---|" + "---|---|" * len(versions)
    lines = [head, sep]
    for scenario, by_v in targets.items():
        cells = []
        for v in versions:
            rows = by_v.get(v, [])
            ok = sum(r["status"] == "pass" for r in rows)
            ratios = [r["error"] / r["tolerance"] for r in rows if r.get("error") is not None and r.get("tolerance")]
            worst = max(ratios) if ratios else float("nan")
            cells.append(f"{ok}/{len(rows)} | {worst:.2g}")
        lines.append(f"| {scenario} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _order_text(o: dict | None) -> str:
    if o is None:
        return ""
    if o["observed"] is None:
        return "-"
    return f"{o['observed']:.2f}"


def order_table(sweeps: dict[str, dict], integrators: Sequence[str] = INTEGRATORS) -> str:
    """One row per (case, check): the observed order per integrator per version."""
    versions = sorted(sweeps, key=_version_key)
    index: dict[tuple[str, str], dict[tuple[str, str], dict]] = {}
    for v in versions:
        for o in sweeps[v]["orders"]:
            if o["integrator"] in integrators and not o["param"]:
                index.setdefault((f"{o['scenario']}:{o['case']}", o["check"]), {})[(o["integrator"], v)] = o
    cols = [(i, v) for i in integrators for v in versions]
    head = "| case | check | " + " | ".join(f"{i} {v}" for i, v in cols) + " |"
    lines = [head, "|---|---|" + "---|" * len(cols)]
    for (target, check), cells in index.items():
        lines.append(f"| {target} | {check} | " + " | ".join(_order_text(cells.get(c)) for c in cols) + " |")
    return "\n".join(lines)


def summary_table(sweeps: dict[str, dict], integrators: Sequence[str] = INTEGRATORS) -> str:
    """Per scenario: median (min - max) of the observed orders over its cases and checks, per integrator and version."""
    versions = sorted(sweeps, key=_version_key)
    groups: dict[str, dict[tuple[str, str], list[float]]] = {}
    for v in versions:
        for o in sweeps[v]["orders"]:
            if o["integrator"] in integrators and o["observed"] is not None and not o["param"]:
                kind = "drift" if o["check"].endswith("-drift") else "state"
                key = f"{o['scenario']} ({'conserved-quantity drifts' if kind == 'drift' else 'trajectory checks'})"
                groups.setdefault(key, {}).setdefault((o["integrator"], v), []).append(o["observed"])
    cols = [(i, v) for i in integrators for v in versions]
    head = "| scenario (checks) | " + " | ".join(f"{i}, mujoco {v}" for i, v in cols) + " |"
    lines = [head, "|---|" + "---|" * len(cols)]
    for key in sorted(groups):
        cells = []
        for c in cols:
            xs = groups[key].get(c, [])
            cells.append(f"{statistics.median(xs):.2f} ({min(xs):.1f}-{max(xs):.1f}, n={len(xs)})" if xs else "-")
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--venv", action="append", default=[], help="a virtual environment with rigidbench and mujoco")
    parser.add_argument("--out", default="results/matrix", help="folder for the JSON documents and the tables")
    parser.add_argument("--merge-only", action="store_true", help="only merge the JSON documents already in --out")
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    if not args.merge_only:
        if not args.venv:
            parser.error("give --venv at least once (or --merge-only)")
        for venv in args.venv:
            run_version(venv, args.out)
    runs, sweeps = load(args.out)
    text = "\n\n".join(
        [
            "Reference profile (`rigidbench run`):",
            reference_table(runs),
            "Observed orders, median (range, number of checks) over each scenario's cases (`rigidbench sweep`):",
            summary_table(sweeps),
            "Observed orders per check:",
            order_table(sweeps),
        ]
    )
    with open(os.path.join(args.out, "matrix.md"), "w") as f:
        f.write(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
