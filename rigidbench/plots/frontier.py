"""Speed-accuracy figures from a frontier (`rigidbench frontier --json`): log error against log cost per scenario,
one curve per integrator (the timestep along it), the Pareto front drawn, the tightest check tolerance as a line,
and, where the scenario has conserved quantities, their drift against the same cost beside it. Generic: no
per-scenario code."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from rigidbench.plots import Figure, pyplot
from rigidbench.plots.convergence import COLORS, MARKERS


def frontier_figures(doc: Mapping[str, Any]) -> list[Figure]:
    """One figure per scenario of a frontier document."""
    plt = pyplot()
    by_scenario: dict[str, list[Mapping[str, Any]]] = {}
    for s in doc["settings"]:
        by_scenario.setdefault(s["scenario"], []).append(s)
    tolerances = doc.get("tolerances", {})
    figures = []
    for slug, group in by_scenario.items():
        usable = [s for s in group if _finite(s["error"]) and _finite(s["cpu_per_sim_second"])]
        if not usable:
            continue
        drift = [s for s in usable if s.get("drift") is not None and _finite(s["drift"])]
        ncol = 2 if drift else 1
        fig, axes = plt.subplots(1, ncol, figsize=(5.2 * ncol, 3.9), layout="constrained", squeeze=False)
        _panel(axes[0, 0], usable, "error", "largest theory-check error")
        tol = tolerances.get(slug)
        if tol:
            axes[0, 0].axhline(tol, color="0.4", ls=":", lw=1)
            axes[0, 0].annotate(
                f"tightest tolerance {tol:.0e}",
                (1, tol),
                xycoords=("axes fraction", "data"),
                ha="right",
                va="bottom",
                fontsize=7,
                color="0.3",
            )
        if drift:
            _panel(axes[0, 1], drift, "drift", "largest conserved-quantity drift")
        machine = doc.get("machine", {})
        caption = (
            f"{slug}: each point is one setting (an integrator at dt = scale x the reference timestep of every "
            "case), its error the largest over the scenario's theory checks and cases, its cost the CPU seconds of "
            "stepping per simulated second (median of repeats; bars: their spread). The black line is the Pareto "
            "front: no setting is both more accurate and cheaper than one on it. "
            + (
                "Right: the drift of the conserved quantities, the accuracy measure available without a closed form. "
                if drift
                else ""
            )
            + f"Timed on {machine.get('cpu', 'this machine')}, {machine.get('cpus', '?')} CPUs."
        )
        figures.append(Figure(f"Speed against accuracy: {slug}", caption, fig))
    return figures


def _finite(x: Any) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


def _panel(ax, settings, key: str, label: str) -> None:
    for integrator in dict.fromkeys(s["integrator"] for s in settings):
        mine = sorted((s for s in settings if s["integrator"] == integrator), key=lambda s: s["cpu_per_sim_second"])
        x = [s["cpu_per_sim_second"] for s in mine]
        y = [max(s[key], 1e-17) for s in mine]
        lo = [s["cpu_per_sim_second"] - s["cpu_per_sim_second_spread"][0] for s in mine]
        hi = [s["cpu_per_sim_second_spread"][1] - s["cpu_per_sim_second"] for s in mine]
        ax.errorbar(
            x,
            y,
            xerr=[lo, hi],
            color=COLORS.get(integrator, "C4"),
            marker=MARKERS.get(integrator, "v"),
            ms=4,
            lw=1,
            capsize=2,
            label=integrator,
        )
    if key == "error":
        front = sorted((s for s in settings if s.get("front")), key=lambda s: s["cpu_per_sim_second"])
        if front:
            ax.step(
                [s["cpu_per_sim_second"] for s in front],
                [max(s["error"], 1e-17) for s in front],
                where="post",
                color="k",
                lw=1.2,
                label="Pareto front",
            )
            marginal = [s for s in front if s.get("marginal")]
            if marginal:
                ax.plot(
                    [s["cpu_per_sim_second"] for s in marginal],
                    [max(s["error"], 1e-17) for s in marginal],
                    "o",
                    mfc="none",
                    mec="k",
                    ms=9,
                    label="marginal (within spread)",
                )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("CPU seconds per simulated second")
    ax.set_ylabel(label)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7)
