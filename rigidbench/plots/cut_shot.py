"""Figures of the rolling cut shot (docs/theory.md B4, with B2-B3 for the skids and C2/C8 for the impact): the top
view of both balls' paths, opening at 90 degrees and the cue ball curving onto its final line at delta, and the
deflection delta(phi) over every cut angle with the 33.75 degree maximum (the "30 degree rule"). Simulation
(coloured) over theory (black, `rigidbench.analytic.cut_shot`).

Extra simulations: the deflection figure gets four cut angles beyond the cases' (each run about a second).
"""

from __future__ import annotations

import math

import numpy as np

from rigidbench import signals
from rigidbench.analytic import cut_shot
from rigidbench.envs.planar import free_body_motion
from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, measured_value, plot, settings_text, thin, try_run

SIM = {"lw": 0, "marker": "o", "ms": 2.0, "alpha": 0.8}
# Cut angles (deg) simulated for the deflection curve beyond the cases' 10, 28.1, 30 and 60 degrees, inside the
# scenario's 5.7 to 74.5 degrees.
EXTRA_CUTS = (6.0, 20.0, 45.0, 70.0)


def _top_view(ctx: PlotContext, ax, case: str) -> tuple[str, object] | None:
    """One case's top view on `ax`; returns (case, run) if it could be drawn."""
    run = try_run(ctx, case)
    if run is None:
        return None
    model, pred, traj = ctx.model(case), run.prediction, run.trajectory
    cue, obj = (free_body_motion(model, traj, b) for b in ("cue", "object"))
    t = np.asarray(traj.time)
    radius = pred["_a"] / 2
    shot: cut_shot.CutShot = pred["_shot"]
    phi = float(run.params["cut"])
    separation = np.hypot(*(cue.com_W[:, :2] - obj.com_W[:, :2]).T) - pred["_a"]
    exits = signals.crossings(t, separation, direction=1)
    if not exits.size:
        return None
    t_e = exits[:1]
    after = t >= t_e[0]
    every = thin(int(after.sum()), 300)
    mm = 1e3
    for body, skid, color, name in ((cue, shot.cue, "C0", "cue"), (obj, shot.object, "C3", "object")):
        start = np.array([float(signals.interpolate(t, body.com_W[:, i], t_e)[0]) for i in range(2)])
        path = body.com_W[:, :2]
        ax.plot(mm * path[~after, 0], mm * path[~after, 1], color=color, lw=1.5)
        ax.plot(
            mm * path[after][every, 0], mm * path[after][every, 1], color=color, **SIM, label=f"{name} ball (MuJoCo)"
        )
        dense = np.linspace(0.0, t[-1] - t_e[0], 400)
        ideal = start + skid.position(dense)
        ax.plot(
            mm * ideal[:, 0],
            mm * ideal[:, 1],
            **THEORY_STYLE,
            label="theory (B3 skid, then rolling)" if name == "cue" else None,
        )
        roll = start + skid.position(np.array([skid.time_to_roll]))[0]
        ax.plot(
            mm * roll[0],
            mm * roll[1],
            "D",
            color=color,
            mec="k",
            ms=6,
            label="theory: rolls from here" if name == "cue" else None,
        )
        if name == "cue":
            cue_start, cue_roll = start, roll
        else:
            obj_start = start
    # The balls at the touch (phi on the line of centres) and the cue ball's first line.
    touch = np.array([-pred["_a"] * math.cos(phi), pred["_a"] * math.sin(phi)])
    for centre, color in ((touch, "C0"), (np.zeros(2), "C3")):
        ax.add_patch(_circle(mm * centre, mm * radius, color))
    # The 90 degree opening: the directions right after the impact, from the end of the impact, the object ball's
    # (the line of centres) drawn back through the cue ball's centre, where the right angle sits.
    reach = 0.6 * float(np.hypot(*(cue.com_W[-1, :2] - cue_start)))
    u_obj = shot.object_after / np.hypot(*shot.object_after)
    u_cue = shot.cue_after / np.hypot(*shot.cue_after)
    for start, end in ((cue_start, cue_start + reach * u_cue), (cue_start, obj_start + reach * u_obj)):
        ax.plot(mm * np.array([start[0], end[0]]), mm * np.array([start[1], end[1]]), color="0.45", lw=1.0, ls=":")
    side = 0.08 * reach
    corner = cue_start + side * np.array([u_obj, u_obj + u_cue, u_cue])
    ax.plot(mm * corner[:, 0], mm * corner[:, 1], color="0.3", lw=0.9)
    ax.annotate("90 deg", mm * (cue_start + 1.5 * side * (u_obj + u_cue)), fontsize=7.5, color="0.3")
    delta = shot.deflection
    first_end = cue.com_W[-1, 0] + 0.1 * reach
    ax.plot(
        mm * np.array([touch[0] - 0.3 * reach, first_end]),
        mm * np.full(2, touch[1]),
        color="0.6",
        lw=0.8,
        ls="-.",
        label="cue ball's first line (+x)",
    )
    final = np.array([math.cos(delta), math.sin(delta)])
    line = cue_roll + np.outer(np.linspace(-1.2, 0.6, 2) * reach, final)
    ax.plot(mm * line[:, 0], mm * line[:, 1], color="k", lw=0.9, ls="--", label="final line at delta (B4)")
    ax.annotate("delta", mm * (cue_roll - 0.9 * reach * final), xytext=(0, 6), textcoords="offset points", fontsize=7.5)
    measured = measured_value(run, "deflection")
    opening = measured_value(run, "opening-angle")
    ax.set_title(
        f"{case}: phi = {math.degrees(phi):.2f} deg; opening {math.degrees(opening):.4f} deg (90),\n"
        f"delta {math.degrees(measured):.3f} deg (soft impact {math.degrees(pred['deflection']):.3f}, "
        f"B4 {math.degrees(pred['deflection-closed-form']):.3f})",
        fontsize=8.5,
    )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    return case, run


def _circle(centre, radius, color):
    from matplotlib.patches import Circle

    return Circle(tuple(centre), radius, fill=False, ec=color, lw=1.0, ls="-", alpha=0.7)


def _paths(ctx: PlotContext) -> Figure | None:
    cases = [c.name for c in ctx.scenario.cases]
    fig, axes = ctx.subplots(2, 2, figsize=(11.0, 9.0))
    drawn = [d for ax, case in zip(axes.flat, cases, strict=False) if (d := _top_view(ctx, ax, case)) is not None]
    if not drawn:
        return None
    for ax in axes.flat[len(drawn) :]:
        ax.set_visible(False)
    fig.legend(*axes.flat[0].get_legend_handles_labels(), loc="outside lower center", ncols=4, fontsize=8)
    fig.suptitle(f"Rolling cut shot, top view ({settings_text(drawn[0][1])})", fontsize=10)
    return Figure(
        "Cut shot: top view of both balls' paths",
        "The cue ball (blue) rolls along +x (dash-dotted: its first line) into the resting object ball (red) at cut "
        "angle phi (circles: the balls at the touch). Dotted: the directions right after the impact, 90 degrees "
        "apart for equal masses (docs/theory.md B4, C2; the titles give the measured opening). Each ball then "
        "skids on B3's parabola (black, from the simulated end of the impact) until it rolls (diamonds); the cue "
        "ball curves onto its final line at delta (dashed), tan delta = 5 sin phi cos phi / (2 cos^2 phi + 7 sin^2 "
        "phi). Agreement: the dots on the black curves and the cue ball's path running into the dashed line. The "
        "titles give delta measured, predicted for MuJoCo's soft impact, and B4's hard-sphere closed form.",
        fig,
    )


def _deflection(ctx: PlotContext) -> Figure | None:
    points = []  # (label, cut angle rad, run)
    for case in ctx.scenario.cases:
        if (run := try_run(ctx, case.name)) is not None:
            points.append((case.name, float(run.params["cut"]), run))
    for deg in EXTRA_CUTS:
        if (run := try_run(ctx, "thirty", {"cut": math.radians(deg)})) is not None:
            points.append((None, math.radians(deg), run))
    if not points:
        return None
    points.sort(key=lambda p: p[1])
    fig, (top, res) = ctx.subplots(2, 1, figsize=(8.0, 6.6), sharex=True, height_ratios=(2.2, 1))
    phi = np.linspace(0.0, math.pi / 2, 500)
    gamma = points[0][2].prediction["_shot"].gamma
    top.plot(
        np.degrees(phi),
        np.degrees(cut_shot.deflection(phi, gamma)),
        **THEORY_STYLE,
        label="B4: tan delta = 5 sin phi cos phi / (2 cos^2 phi + 7 sin^2 phi)",
    )
    phi_max, delta_max = cut_shot.max_deflection(gamma)
    top.axhline(math.degrees(delta_max), color="0.5", lw=0.8, ls=":")
    top.axvline(math.degrees(phi_max), color="0.5", lw=0.8, ls=":")
    top.plot(
        math.degrees(phi_max),
        math.degrees(delta_max),
        "*",
        color="k",
        ms=14,
        mfc="gold",
        label=f"maximum: {math.degrees(delta_max):.2f} deg at phi = {math.degrees(phi_max):.2f} deg",
    )
    cuts = np.array([p[1] for p in points])
    measured = np.array([measured_value(p[2], "deflection") for p in points])
    soft = np.array([p[2].prediction["deflection"] for p in points])
    hard = cut_shot.deflection(cuts, gamma)
    tol = np.array([p[2].prediction["_tolerance"]["deflection-closed-form"] for p in points])
    is_case = np.array([p[0] is not None for p in points])
    for mask, marker, label in ((is_case, "o", "MuJoCo, the cases"), (~is_case, "s", "MuJoCo, extra cut angles")):
        top.plot(
            np.degrees(cuts[mask]), np.degrees(measured[mask]), marker, color="C0", ms=7, mec="k", lw=0, label=label
        )
    shift = {"max-deflection": (-80, -4)}
    for name, cut, _ in points:
        if name is not None:
            top.annotate(
                name,
                (math.degrees(cut), math.degrees(measured[cuts == cut][0])),
                xytext=shift.get(name, (5, -12)),
                textcoords="offset points",
                fontsize=7.5,
            )
    top.set_ylabel("cue ball's deflection delta (deg)")
    top.set_ylim(0, 40)
    top.legend(fontsize=7.5, loc="lower center")
    top.set_title(f"Rolling cut shot: deflection against cut angle ({settings_text(points[0][2])})", fontsize=9.5)
    res.errorbar(
        np.degrees(cuts),
        np.zeros(len(cuts)),
        yerr=1e3 * tol,
        fmt="none",
        ecolor="0.6",
        capsize=3,
        label="deflection-closed-form tolerance (per run)",
    )
    res.plot(np.degrees(cuts), 1e3 * (measured - hard), "o", color="C0", ms=8, mec="k", lw=0, label="MuJoCo")
    res.plot(
        np.degrees(cuts), 1e3 * (soft - hard), "x", color="k", ms=5, mew=1.2, label="predicted for the soft impact"
    )
    res.set_ylim(-1.7e3 * tol.max(), 1.7e3 * tol.max())
    res.axhline(0.0, color="k", lw=0.8)
    res.set_xlabel("cut angle phi (deg)")
    res.set_ylabel("delta - B4 (mrad)")
    res.set_xlim(0, 90)
    res.legend(fontsize=7, loc="upper center", ncols=3)
    return Figure(
        "Cut shot: deflection against cut angle (the 30 degree rule)",
        "Top: B4's closed form for a rolling cue ball after a frictionless, elastic cut (black), its maximum "
        "33.75 degrees at tan phi = sqrt(2/7), phi = 28.1 degrees (star), and MuJoCo's deflection read from the "
        "final rolling velocities: the four cases (circles) and four more cut angles (squares). Agreement: every "
        "point on the curve. Bottom: the differences from the closed form, in mrad: MuJoCo's contact is a spring "
        "lasting 60 steps, whose soft impact moves delta by a predicted amount (black crosses, C8); the simulated "
        "points sit on the black crosses, well inside the per-run tolerance of the closed-form check (grey bars).",
        fig,
    )


@plot("cut-shot")
def cut_shot_figures(ctx: PlotContext) -> list[Figure]:
    return [f for f in (_paths(ctx), _deflection(ctx)) if f is not None]
