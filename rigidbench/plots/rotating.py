"""Figures of the rotating-frame family: the Foucault rosette (the bob's path seen from the turning platform, over
N2's swing) and the swing plane's azimuth against time; the eastward deflection along the fall, over N3 and the
exact motion. Simulation in colour, theory in black (`rigidbench.analytic.rotating`). Every figure reuses the
cases' runs; nothing extra is simulated.
"""

from __future__ import annotations

import numpy as np

from rigidbench.analytic import rotating as rot
from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, plot, settings_text, try_run


@plot("foucault")
def foucault(ctx: PlotContext) -> list[Figure]:
    figures = []
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    rosettes = [(name, run) for name, run in runs if name in ("mid-latitude", "southern")]
    if rosettes:
        fig, axes = ctx.subplots(1, len(rosettes), figsize=(5.2 * len(rosettes), 5.4), squeeze=False)
        for ax, (name, run) in zip(axes[0], rosettes, strict=True):
            p = run.prediction
            model = ctx.model(name)
            times, azimuth, x, y = ctx.scenario.swing(model, run.trajectory, p)
            t = run.trajectory.time
            q = rot.foucault_swing(
                t, p["_omega0"], -p["precession-rate"], p["_length"] * np.sin(p["_amplitude"]), p["_azimuth"]
            )
            early = t <= 3 * p["_period"]
            ax.plot(1e3 * x, 1e3 * y, color="C0", lw=0.3, alpha=0.5, label="MuJoCo: bob across the plumb line")
            ax.plot(1e3 * x[early], 1e3 * y[early], color="C3", lw=1.2, label="MuJoCo: first three periods")
            ax.plot(1e3 * q.real, 1e3 * q.imag, lw=0.4, ls=(0, (2, 3)), color="k", label="N2 small-amplitude swing")
            a = 1e3 * p["_length"] * np.sin(p["_amplitude"])
            # A zoom on the first three turning points: the cusps of a release at rest, over N2's.
            zoom = ax.inset_axes([0.62, 0.04, 0.36, 0.3])
            tip = early & (x * np.cos(p["_azimuth"]) + y * np.sin(p["_azimuth"]) > 0.9e-3 * a)
            zoom.plot(1e3 * x[tip], 1e3 * y[tip], "o", ms=1.5, color="C3")
            zoom.plot(1e3 * np.where(tip, q.real, np.nan), 1e3 * np.where(tip, q.imag, np.nan), **THEORY_STYLE)
            zoom.tick_params(labelsize=6)
            zoom.set_title("tips, 3 periods (mm)", fontsize=7)
            ax.set_aspect("equal")
            ax.set_xlabel("East (mm)")
            ax.set_ylabel("North (mm)")
            lat = np.degrees(p["_latitude"])
            ax.set_title(f"{name}: latitude {lat:.2f} deg, half a turn in {np.pi / abs(p['precession-rate']):.0f} s")
            ax.legend(loc="upper right", fontsize=7)
        figures.append(
            Figure(
                "Foucault rosette: the swing seen from the turning platform",
                "The bob's path across the plumb line, in the platform's East-North axes (blue), from its release at "
                "rest until the swing plane has turned by half a turn, its first three periods in red, and N2's "
                "small-amplitude solution (dashed black); the inset zooms on the first turning points (the cusps of a "
                "release at rest). Agreement: the two paths lie on top "
                "of each other; the plane turns clockwise in the northern hemisphere and counter-clockwise in the "
                f"southern, at Omega |sin(latitude)|. {settings_text(rosettes[0][1])}.",
                fig,
            )
        )
    fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1.6), figsize=(8.0, 6.0))
    for i, (name, run) in enumerate(runs):
        p = run.prediction
        times, azimuth, _, _ = ctx.scenario.swing(ctx.model(name), run.trajectory, p)
        theory = azimuth[0] + p["precession-rate"] * times
        ax.plot(times, np.degrees(azimuth - azimuth[0]), "o", ms=3, color=f"C{i}", label=f"MuJoCo: {name}")
        ax.plot(times, np.degrees(theory - azimuth[0]), **THEORY_STYLE)
        res.plot(times, np.degrees(azimuth - theory), "o", ms=2, color=f"C{i}")
    ax.plot([], [], label="N2: -Omega sin(latitude) t", **THEORY_STYLE)
    ax.set_ylabel("swing-plane azimuth turned (deg)")
    ax.legend(fontsize=8)
    res.set_xlabel("time (s)")
    res.set_ylabel("MuJoCo - N2 (deg)")
    figures.append(
        Figure(
            "Swing-plane azimuth against time",
            "The azimuth of the swing line at each maximum excursion (from East towards North, about the plumb line), "
            "for every case, over N2's uniform turn at -Omega sin(latitude) (black). The residual underneath is what "
            "N2 neglects: Airy's precession of the slightly elliptic swing (against the turn), the plumb line's lean "
            "and the centrifugal anisotropy, which makes the rate vary with the azimuth; the equator's line stays "
            f"flat. {settings_text(runs[0][1])}.",
            fig,
        )
    )
    return figures


@plot("eastward-deflection")
def eastward_deflection(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1.6), figsize=(8.0, 6.0))
    for i, (name, run) in enumerate(runs):
        p = run.prediction
        model = ctx.model(name)
        t = run.trajectory.time
        r = ctx.scenario._position(model, run.trajectory.qpos)
        exact = rot.drop_path(t, p["_field"], p["_rate_vec"], p["_r0"])
        fallen = p["_r0"][2] - r[:, 2]
        g = float(np.linalg.norm(p["_field"]))
        rate, lat = float(np.linalg.norm(p["_rate_vec"])), float(np.arctan2(p["_axis"][2], p["_axis"][1]))
        n3 = rate * g * t**3 * np.cos(lat) / 3
        step = max(1, len(t) // 40)
        ax.plot(fallen[::step], 1e3 * r[::step, 0], "o", ms=4, color=f"C{i}", label=f"MuJoCo: {name}")
        ax.plot(p["_r0"][2] - exact[:, 2], 1e3 * exact[:, 0], **THEORY_STYLE)
        ax.plot(fallen, 1e3 * n3, color=f"C{i}", lw=0.8, ls="--")
        res.semilogy(fallen[1:], np.maximum(np.linalg.norm(r - exact, axis=1)[1:], 1e-17), color=f"C{i}", lw=0.8)
    ax.plot([], [], label="exact (N1 in closed form)", **THEORY_STYLE)
    ax.plot([], [], color="0.4", ls="--", lw=0.8, label="N3: (1/3) Omega g t^3 cos(latitude)")
    ax.set_ylabel("East of the release (mm)")
    ax.legend(fontsize=8)
    res.set_xlabel("distance fallen (m)")
    res.set_ylabel("|MuJoCo - exact| (m)")
    return [
        Figure(
            "Eastward deflection along the fall",
            "The ball's eastward displacement relative to the platform against the distance it has fallen (markers), "
            "over the exact motion (black: N1 integrated in closed form, every order in Omega) and N3's first-order "
            "(1/3) Omega g t^3 cos(latitude) (dashed, in each case's colour), which differs from it by (Omega t)^2 "
            "terms. Underneath, the distance between MuJoCo and the exact motion: round-off (1e-13 m) under RK4. The "
            f"pole's ball falls straight. {settings_text(runs[0][1])}.",
            fig,
        )
    ]
