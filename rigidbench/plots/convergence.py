"""Convergence figures from a sweep (`rigidbench sweep --json`): log-log error against timestep, one panel per check,
one colour per integrator, the fitted slope drawn over the points it used. Generic: no per-scenario code."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rigidbench.plots import Figure, pyplot

COLORS = {"Euler": "C0", "implicit": "C1", "implicitfast": "C2", "RK4": "C3", "discrete": "C5"}
MARKERS = {"Euler": "o", "implicit": "s", "implicitfast": "x", "RK4": "D", "discrete": "^"}


def convergence_figures(doc: Mapping[str, Any]) -> list[Figure]:
    """One figure per (scenario, case, swept parameter value) of a sweep document."""
    plt = pyplot()
    rows = [r for r in doc["results"] if r.get("error") is not None]
    orders = doc.get("orders", [])
    groups: dict[tuple, list[Mapping[str, Any]]] = {}
    for r in rows:
        pt = r["point"]
        key = (pt["scenario"], pt["case"], tuple(sorted(pt["param"].items())))
        groups.setdefault(key, []).append(r)
    figures = []
    for (scenario, case, param), group in groups.items():
        checks = list(dict.fromkeys(r["check"] for r in group))
        ncol = min(4, len(checks))
        nrow = math.ceil(len(checks) / ncol)
        fig, axes = plt.subplots(
            nrow, ncol, figsize=(3.2 * ncol, 2.9 * nrow + 0.4), layout="constrained", squeeze=False
        )
        for ax in axes.flat[len(checks) :]:
            ax.set_visible(False)
        for ax, check in zip(axes.flat, checks, strict=False):
            _panel(ax, [r for r in group if r["check"] == check], _orders_of(orders, scenario, case, param, check))
            ax.set_title(check, fontsize=9)
        extra = ", ".join(f"{k}={v:g}" for k, v in param)
        integrators = list(dict.fromkeys(r["point"]["integrator"] for r in group))
        handles = [
            plt.Line2D([], [], color=COLORS.get(i, "C7"), marker=MARKERS.get(i, "o"), ls="-", label=i)
            for i in integrators
        ]
        fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize=8)
        fig.suptitle(f"{scenario}:{case}{' [' + extra + ']' if extra else ''} - mujoco {doc['mujoco']}", fontsize=10)
        figures.append(
            Figure(
                f"Convergence: {scenario}:{case}" + (f" [{extra}]" if extra else "") + f" (mujoco {doc['mujoco']})",
                "Error of each check against the timestep, log-log, per integrator (markers; hollow = not used by "
                "the fit: at round-off, saturated or outside the straight range). Lines: the least-squares fit over "
                "the straight range; the box gives the observed order p and the nominal order in brackets ('-': "
                "no order, see the orders table). An "
                "integrator in its asymptotic regime shows a straight line of slope equal to its order.",
                fig,
            )
        )
    return figures


def _orders_of(orders: Sequence[Mapping[str, Any]], scenario: str, case: str, param: tuple, check: str) -> dict:
    return {
        o["integrator"]: o
        for o in orders
        if o["scenario"] == scenario
        and o["case"] == case
        and o["check"] == check
        and tuple(sorted(o["param"].items())) == param
    }


def _panel(ax, rows: Sequence[Mapping[str, Any]], orders: Mapping[str, Mapping[str, Any]]) -> None:
    notes = []
    for integrator in dict.fromkeys(r["point"]["integrator"] for r in rows):
        pts = sorted(
            (r["point"]["timestep"], r["error"])
            for r in rows
            if r["point"]["integrator"] == integrator and r["error"] is not None and r["error"] > 0
        )
        if not pts:
            continue
        h, e = np.array(pts).T
        o = orders.get(integrator, {})
        used = np.isin(h, o.get("used", []) if o.get("observed") is not None else [])
        color, marker = COLORS.get(integrator, "C7"), MARKERS.get(integrator, "o")
        short = {"implicitfast": "ifast", "implicit": "impl"}.get(integrator, integrator)
        if o.get("observed") is not None:
            notes.append(f"{short} {o['observed']:.2f} [{o['nominal']}]")
        else:
            notes.append(f"{short} -")
        ax.loglog(h[used], e[used], marker, color=color, ms=4, ls="none")
        ax.loglog(h[~used], e[~used], marker, color=color, ms=4, ls="none", mfc="none", alpha=0.6)
        if o.get("observed") is not None and used.sum() >= 2:
            x = np.log(h[used])
            c = np.polyfit(x, np.log(e[used]), 1)
            xs = np.linspace(x.min(), x.max(), 2)
            ax.loglog(np.exp(xs), np.exp(np.polyval(c, xs)), "-", color=color, lw=1.0)
    from matplotlib.ticker import NullFormatter

    ax.xaxis.set_minor_formatter(NullFormatter())  # a narrow range would label minor ticks over each other
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("timestep (s)", fontsize=8)
    ax.set_ylabel("error", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(True, which="major", lw=0.3)
    ax.text(
        0.98,
        0.03,
        "p: " + "\n".join(notes),
        transform=ax.transAxes,
        ha="right",
        va="bottom",
        fontsize=6.5,
        family="monospace",
        bbox={"facecolor": "white", "alpha": 0.8, "lw": 0},
    )
