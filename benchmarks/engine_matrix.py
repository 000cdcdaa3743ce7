"""The engine matrix (issue 15): scenario x engine, checks passed, worst error / tolerance, from `rigidbench run`
JSON files, as the Markdown table in docs/engines.md.

Usage::

    rigidbench run --json results/mujoco.json
    rigidbench run --engine warp --json results/warp.json                      # pip install 'rigidbench[warp]'
    rigidbench run --engine mjx --json results/mjx.json                        # pip install 'rigidbench[mjx]'
    rigidbench run --engine mjx --precision float64 --json results/mjx64.json
    python benchmarks/engine_matrix.py results/mujoco.json results/warp.json results/mjx.json results/mjx64.json

A cell reads ``passed/scored (worst error/tolerance)``, then what was not scored: ``u`` cases the engine does not
support (refused before simulating, naming the feature), ``r`` checks its precision cannot resolve (the float32
round-off floor reaches a tenth of the quantity, `rigidbench.scenario.UNRESOLVED_FRACTION`).
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict


def column(path: str) -> tuple[str, dict[str, str]]:
    """The engine a run JSON was made with (its heading) and its cell per scenario."""
    rows = json.load(open(path))["results"]
    s = rows[0]["settings"]
    heading = f"{s.get('engine') or 'mujoco'} {s.get('precision') or 'float64'}"
    by: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        by[r["scenario"]].append(r)
    cells = {}
    for scenario, group in by.items():
        scored = [r for r in group if r["status"] in ("pass", "fail", "diverged", "error")]
        passed = sum(r["status"] == "pass" for r in scored)
        ratios = [r["error"] / r["tolerance"] for r in scored if r["status"] in ("pass", "fail") and r["tolerance"]]
        unsupported = sum(r["status"] == "unsupported" for r in group)
        unresolved = sum(r["status"] == "unresolved" for r in group)
        if not scored:
            cell = f"unsupported ({unsupported} cases)" if unsupported else "-"
        else:
            cell = f"{passed}/{len(scored)} ({max(ratios):.2g})" if ratios else f"{passed}/{len(scored)}"
            extra = [f"{unsupported} u" for _ in [0] if unsupported] + [f"{unresolved} r" for _ in [0] if unresolved]
            if extra:
                cell += ", " + ", ".join(extra)
        cells[scenario] = cell
    return heading, cells


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="rigidbench run --json files, one per engine")
    args = parser.parse_args()
    columns = [column(p) for p in args.runs]
    scenarios = list(dict.fromkeys(s for _, cells in columns for s in cells))
    print("| scenario | " + " | ".join(h for h, _ in columns) + " |")
    print("|---|" + "---|" * len(columns))
    for s in scenarios:
        print(f"| `{s}` | " + " | ".join(cells.get(s, "-") for _, cells in columns) + " |")


if __name__ == "__main__":
    main()
