"""Figures of the percussion family: the struck stick's cycloid, the cue ball's slip to rolling and its hops, the
cushion's no-skid height, the pivoted stick's sweet spot, the ball on the stick, the marble shot. Simulation
(coloured markers or thick lines) over theory (black, the closed forms of `rigidbench.analytic.percussion`);
where the two would be indistinguishable, the difference is drawn underneath.

Extra simulations: the cushion, the pivoted stick and the ball on the stick get a few parameter values beyond
their cases (each run well under a second) so that their theory curves have points along them.
"""

from __future__ import annotations

import numpy as np

from rigidbench import signals
from rigidbench.analytic import percussion
from rigidbench.envs.cue_strike import CueStrike
from rigidbench.envs.planar import free_body_motion
from rigidbench.plots import (
    THEORY_STYLE,
    Figure,
    PlotContext,
    measured_value,
    plot,
    pyplot,
    settings_text,
    simulated,
    thin,
    try_run,
)
from rigidbench.settings import profile

SIM = {"lw": 0, "marker": "o", "ms": 3.0, "alpha": 0.85}


def _expected(run, check: str) -> float:
    return next((o.expected for o in run.outcomes if o.check.name == check), float("nan"))


def _clean(x: float, scale: float) -> float:
    """`x`, or 0 where it is roundoff next to `scale` (for labels)."""
    return 0.0 if abs(x) <= 1e-12 * abs(scale) else x


# ---- struck stick: the centre of percussion's cycloid (P1-P3) -------------------------------------------------


@plot("struck-stick")
def struck_stick(ctx: PlotContext) -> list[Figure]:
    cases = [c for c in ("quarter", "end", "near-centre") if try_run(ctx, c) is not None]
    if not cases:
        return []
    fig, axes = ctx.subplots(len(cases), 1, figsize=(9.0, 2.5 * len(cases) + 0.6), squeeze=False)
    res_fig, res = ctx.subplots(figsize=(8.0, 3.6))
    for ax, case in zip(axes[:, 0], cases, strict=True):
        run = ctx.run(case)
        model = ctx.model(case)
        traj, theory = run.trajectory, run.prediction["_theory"]
        tau = run.prediction["_tau"]
        p, length = theory.percussion_distance, float(run.params["length"])
        m = free_body_motion(model, traj, "stick")
        cop = m.point_W(np.array([0.0, -p, 0.0]))
        t = traj.time
        tp = np.maximum(t - tau / 2, 0.0)  # the pulse acts as an impulse at its centroid
        dense = np.linspace(0.0, tp[-1], 2000)
        ideal = theory.cycloid(dense)
        ax.plot(
            ideal[:, 0], ideal[:, 1], label="theory: cycloid x = p(th - sin th), y = -p cos th (P3)", **THEORY_STYLE
        )
        # Snapshots of the stick (grey), extended (dotted) to the centre of percussion when it lies off the stick.
        near, far = m.point_W(np.array([0.0, -length / 2, 0.0])), m.point_W(np.array([0.0, length / 2, 0.0]))
        for i in np.linspace(0, len(t) - 1, 7).astype(int):
            ax.plot([near[i, 0], far[i, 0]], [near[i, 1], far[i, 1]], color="0.6", lw=2.0, zorder=1)
            if p > length / 2:
                ax.plot([near[i, 0], cop[i, 0]], [near[i, 1], cop[i, 1]], color="0.7", lw=0.8, ls=":", zorder=1)
        k = thin(len(t), 120)
        ax.plot(
            cop[k, 0],
            cop[k, 1],
            color="C3",
            label=f"MuJoCo: body point s = -p ({settings_text(run)})",
            **{**SIM, "ms": 2.5},
        )
        n = np.arange(0, int(tp[-1] / theory.cusp_period) + 1)
        ax.plot(
            n * theory.cusp_spacing,
            np.full(n.shape, -p),
            "^",
            color="k",
            mfc="none",
            ms=10,
            mew=1.2,
            label="theory cusps, 2 pi p apart",
        )
        after = t > tau
        vel = m.point_velocity_W(np.array([0.0, -p, 0.0]))[after]
        acc = m.point_acceleration_W(np.array([0.0, -p, 0.0]))[after]
        cusps = signals.crossings(t[after], np.sum(vel * acc, axis=1), direction=1)
        if cusps.size:
            xc = signals.interpolate(t[after], cop[after, 0], cusps)
            yc = signals.interpolate(t[after], cop[after, 1], cusps)
            ax.plot(xc, yc, "x", color="C0", ms=9, mew=1.5, label="measured cusps (minima of |v|)")
        ax.set_aspect("equal")
        ax.set_ylabel("y (m)")
        ax.set_title(
            f"{case}: h = {run.params['offset']:.4g} m, p = I/(M h) = {p:.4g} m, cusp spacing 2 pi p = "
            f"{theory.cusp_spacing:.4g} m",
            fontsize=9,
        )
        ax.set_ylim(min(-1.25 * p, -0.6 * length), max(1.6 * p, 0.8 * length))
        err = np.linalg.norm(cop[:, :2] - theory.cycloid(tp), axis=1) / p
        res.semilogy(t[after], np.maximum(err[after], 1e-17), lw=0.8, label=f"{case} (p = {p:.3g} m)")
    axes[-1, 0].set_xlabel("x (m), along the blow")
    axes[0, 0].plot([], [], color="0.6", lw=2.0, label="the stick at 7 instants")
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside upper center", ncols=3, fontsize=7.5)
    res.set_xlabel("t (s)")
    res.set_ylabel("|r_sim - r_cycloid| / p")
    res.set_title("struck-stick: distance of the simulated point s = -p from the cycloid")
    res.legend(fontsize=8)
    return [
        Figure(
            "Struck stick: the centre of percussion traces a cycloid",
            "A free stick on frictionless ice struck along +x at h from its centre (three cases). Red dots: MuJoCo's "
            "path of the body point s = -p, the centre of percussion p = I/(M h) on the far side; black: the common "
            "cycloid of docs/theory.md P3, traced by a circle of radius p rolling along the CM's path. Agreement: the "
            "dots lie on the curve and the measured cusps (blue crosses, where the point is momentarily at rest) "
            "sit on the predicted ones (open triangles), 2 pi p apart. Grey: the stick at 7 instants (dotted "
            "extension to s = -p in the near-centre case, where the centre of percussion lies off the stick).",
            fig,
        ),
        Figure(
            "Struck stick: distance from the cycloid",
            "Distance of the simulated point s = -p from the cycloid at the same time (t' measured from the "
            "pulse's centroid), in units of p: the finite 0.1 ms pulse and the integration error, orders of "
            "magnitude below what the path figure can show.",
            res_fig,
        ),
    ]


# ---- cue strike and cushion: slip to rolling (B1, B2) ---------------------------------------------------------


def _slip_panel(ctx: PlotContext, ax, res, cases, label) -> list[tuple[str, float, float]]:
    """Slip(t) of each case over B2's straight line, t_r marked; difference underneath. Returns what was drawn."""
    drawn = []
    for i, case in enumerate(cases):
        run = try_run(ctx, case)
        if run is None:
            continue
        model = ctx.model(case)
        traj, theory, tau = run.trajectory, run.prediction["_theory"], run.prediction["_tau"]
        m = free_body_motion(model, traj, "ball")
        slip = CueStrike.slip(model, m)
        t = traj.time
        _, _, u = theory.state(t)
        color = f"C{i}"
        ax.plot(t, slip, color=color, lw=3.0, alpha=0.45, label=label(run, theory))
        ax.plot(t, u, color="k", lw=0.9, ls="--")
        if abs(theory.slip) > 1e-9 * abs(theory.speed):
            ax.plot([theory.time_to_roll], [0.0], "v", color=color, ms=9, mec="k")
            ax.annotate(
                f"t_r = {theory.time_to_roll:.3f} s",
                (theory.time_to_roll, 0.0),
                xytext=(4, 8 if theory.slip > 0 else -14 - 10 * (i % 2)),
                textcoords="offset points",
                fontsize=8,
                color=color,
            )
        after = t >= tau
        diff = slip[after] - u[after]
        res.plot(t[after], diff, color=color, lw=0.5, alpha=0.25)
        window = max(1, int(round(1e-2 / traj.timestep)))  # 10 ms running mean: the touchdowns' average
        if len(diff) > 2 * window:
            mean = np.convolve(diff, np.ones(window) / window, mode="valid")
            res.plot(t[after][window // 2 : window // 2 + len(mean)], mean, color=color, lw=1.2)
        drawn.append((case, theory.slip, theory.time_to_roll))
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.plot([], [], color="k", lw=0.9, ls="--", label="theory (B2): u0 - (7/2) mu g t, then 0")
    ax.set_ylabel("contact-point slip u = v_x - R omega_y (m/s)")
    ax.legend(fontsize=7.5, loc="upper right")
    res.set_ylabel("sim - theory (m/s)")
    res.set_xlabel("t (s), from the start of the pulse")
    res.plot([], [], color="0.3", lw=1.2, label="10 ms running mean")
    res.plot([], [], color="0.3", lw=0.5, alpha=0.4, label="every step")
    res.legend(fontsize=7, loc="upper right", ncols=2)
    res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    return drawn


def _lift_panel(ctx: PlotContext, ax, settings, title: str) -> float | None:
    """Height of the ball above its resting height, over R, for each case; returns the largest (None: no case
    could be simulated under `settings`)."""
    top, curves = 0.0, []
    for i, case in enumerate(c.name for c in ctx.scenario.cases):
        if settings is None:
            run = try_run(ctx, case)
            if run is None:
                continue
            model = ctx.model(case)
        else:
            try:
                run = ctx.scenario.run(case, None, settings, keep_trajectory=True)
                model = ctx.scenario.build(ctx.scenario.resolve(ctx.scenario.case(case)), settings)
            except ValueError:
                continue
        if not simulated(run):
            continue
        m = free_body_motion(model, run.trajectory, "ball")
        radius = run.prediction["_theory"].radius
        lift = (m.com_W[:, 2] - run.prediction["_rest_height"]) / radius
        top = max(top, float(lift.max()))
        curves.append((float(lift.max()), i, case, run.trajectory.time, lift))
    for peak, i, case, t, lift in sorted(curves, key=lambda c: -c[0]):  # the largest first, the small ones on top
        ax.plot(t, lift, color=f"C{i}", lw=0.6, label=f"{case}: max {peak:.2g} R")
    ax.axhline(0.0, color="k", lw=0.9, ls="--")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("t (s)")
    if not curves:
        ax.text(0.5, 0.5, "not simulated under these settings", transform=ax.transAxes, ha="center", fontsize=9)
        return None
    ax.legend(fontsize=7.5, loc="upper right")
    return top


@plot("cue-strike")
def cue_strike(ctx: PlotContext) -> list[Figure]:
    figures = []
    fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1), figsize=(8.0, 5.6))

    def label(run, theory):
        h = run.params["height"] / theory.radius
        return f"{run.case}: h = {h:+.2f} R, u0 = {_clean(theory.slip, theory.speed):+.3g} m/s"

    drawn = _slip_panel(ctx, ax, res, [c.name for c in ctx.scenario.cases], label)
    if drawn:
        run0 = ctx.run(drawn[0][0])
        ax.set_title(f"cue-strike: slip of the contact point, skid to rolling ({settings_text(run0)})", fontsize=10)
        figures.append(
            Figure(
                "Cue ball: contact-point slip to rolling",
                "The cue leaves the ball with slip u0 = v0 (1 - 5h/(2R)) (docs/theory.md B1): positive for a centre "
                "shot or a draw (backspin), negative for topspin above the no-skid height 2R/5, zero at it. Sliding "
                "friction then reduces |u| along the straight line u0 - (7/2) mu g t of B2 (black dashed) to zero at "
                "t_r = 2|u0|/(7 mu g) (triangles), after which the ball rolls. Thick coloured lines: MuJoCo. "
                "Agreement: they lie on the lines and reach zero at the triangles. Lower panel: the difference, "
                "whose structure is MuJoCo's contact (friction in impulses at touchdowns, and a short exponential "
                "tail instead of the kink at t_r): the pale band is the step-by-step staircase of touchdown "
                "impulses, the solid line its 10 ms running mean (hops last up to ~2 ms), which follows B2's line "
                "closely.",
                fig,
            )
        )
    else:
        pyplot().close(fig)
    fig, axes = ctx.subplots(1, 2, figsize=(9.5, 3.8))
    here = _lift_panel(ctx, axes[0], None, "settings of this report")
    default = _lift_panel(ctx, axes[1], profile("mujoco-default"), "mujoco-default profile (Euler, 2 ms, soft contact)")
    axes[0].set_ylabel("(z - z_rest) / R")
    axes[0].ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    if here is None and default is None:
        pyplot().close(fig)
        return figures
    here_text = "not simulated under these settings" if here is None else f"{here:.2g} R"
    default_text = "could not be simulated" if default is None else f"reach {default:.2g} R"
    figures.append(
        Figure(
            "Cue ball: it hops (a MuJoCo finding)",
            "Height of the ball's centre above its resting height, in radii, while it skids and rolls. docs/theory.md "
            "B2 assumes it stays on the table (the black dashed zero). MuJoCo solves normal and friction rows as "
            "one soft constraint: while the ball slides, the friction demand pushes the normal force above M g and "
            f"kicks the ball off the cloth at each touchdown, so it hops along until it rolls (largest lift with "
            f"the report's settings: {here_text}; the tolerance at the reference settings is 1e-3 R). With "
            f"MuJoCo's default contact (right) the hops {default_text}. The rolling phase (and the no-skid shot) "
            "stays on the table.",
            fig,
        )
    )
    return figures


@plot("cushion-rebound")
def cushion_rebound(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    model = ctx.model(runs[0][0])
    p = runs[0][1].params
    radius, mass, speed, e = p["radius"], p["mass"], p["speed"], p["restitution"]
    inertia = float(model.body("ball").inertia[1])

    def rebound_slip(height):  # B1: u' = (1 + e) v (M R (H - R) / I - 1), v the speed into the cushion
        return (1 + e) * speed * (mass * radius * (np.asarray(height) - radius) / inertia - 1)

    fig = pyplot().figure(figsize=(11.0, 4.8), layout="constrained")
    axd = fig.subplot_mosaic([["H", "u"], ["H", "r"]], width_ratios=(1, 1.2), height_ratios=(3, 1))
    ax, sl, res = axd["H"], axd["u"], axd["r"]
    sl.sharex(res)
    H = np.linspace(0.02, 1.98, 200) * radius
    ax.plot(H / (2 * radius), rebound_slip(H), label="theory (B1): (1 + e) v (5 (H - R)/(2R) - 1)", **THEORY_STYLE)
    ax.axvline(0.7, color="0.5", ls=":", lw=0.8)
    ax.text(0.7, rebound_slip(0.1 * radius), " H = 7/10 of the diameter", fontsize=8)
    ax.axhline(0.0, color="0.6", lw=0.6)
    for i, (case, run) in enumerate(runs):
        ax.plot(
            run.params["cushion_height"] / (2 * radius),
            measured_value(run, "rebound-slip"),
            "o",
            color=f"C{i}",
            ms=8,
            mec="k",
            label=f"MuJoCo: {case}",
        )
    extra = []
    for frac in (0.15, 0.3, 0.45, 0.55, 0.65, 0.75, 0.9):
        run = try_run(ctx, "low", {"cushion_height": 2 * frac * radius})
        if run is not None:
            extra.append((frac, measured_value(run, "rebound-slip")))
    if extra:
        ax.plot(*np.array(extra).T, "s", color="0.35", ms=5, label="MuJoCo: more cushion heights")
    ax.set_xlabel("cushion nose height H / (2R)")
    ax.set_ylabel("slip u' after the rebound (m/s)")
    ax.set_title(f"rebound slip vs cushion height (v = {speed:g} m/s, e = {e:g})", fontsize=9)
    ax.legend(fontsize=7.5, loc="upper left")

    def label(run, theory):
        height = run.params["cushion_height"] / (2 * radius)
        return f"{run.case}: H = {height:.2f} (2R), u' = {_clean(theory.slip, speed):+.3g} m/s"

    _slip_panel(ctx, sl, res, [c for c, _r in runs], label)
    sl.tick_params(labelbottom=False)
    sl.set_title("slip after the rebound, back to rolling (B2)", fontsize=9)
    sl.set_ylabel("slip u (m/s)")
    return [
        Figure(
            "Cushion rebound: no skid at 7/10 of the diameter",
            "A ball rolling at v into a cushion whose nose is at height H above the table. Left: the slip of the "
            "contact point the rebound leaves, against H: docs/theory.md B1's straight line (black), zero at H = 0.7 "
            "of "
            "the diameter, where the cushion's impulse passes through the ball's centre of percussion. Points: "
            "MuJoCo's measured slip (intercept of the sliding phase) for the four cases and further heights; "
            "agreement is the points on the line. Right: the slip after the rebound decaying to rolling along "
            "B2's lines (black dashed), MuJoCo thick, the difference underneath.",
            fig,
        )
    ]


# ---- pivoted stick: the sweet spot (P4) -------------------------------------------------------------------------


@plot("pivoted-stick")
def pivoted_stick(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    length = runs[0][1].params["length"]
    model = ctx.model(runs[0][0])
    body = model.body("stick")
    mass, d_cm = float(body.mass[0]), float(body.ipos[1])
    inertia_pivot = float(body.inertia[2]) + mass * d_cm**2
    sweet = percussion.sweet_spot(mass, inertia_pivot, d_cm)
    points = list(runs)
    for frac in (0.1, 0.4, 0.55, 0.8, 0.9):
        run = try_run(ctx, "end", {"strike": frac * length})
        if run is not None:
            points.append((None, run))
    fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1.2), figsize=(8.0, 5.6))
    d = np.linspace(0.0, length, 200)
    ax.plot(
        d / length,
        percussion.pivot_reaction_impulse(mass, inertia_pivot, d_cm, d, 1.0),
        label="theory (P4): J / Pi = M d_cm d / I_O - 1",
        **THEORY_STYLE,
    )
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.axvline(sweet / length, color="0.5", ls=":", lw=0.8)
    ax.text(sweet / length, -0.9, f" sweet spot d* = I_O/(M d_cm) = {sweet / length:.4g} L", fontsize=8)
    for i, (case, run) in enumerate(points):
        x = run.params["strike"] / length
        y, expected = measured_value(run, "reaction-impulse"), _expected(run, "reaction-impulse")
        if case is not None:
            ax.plot(x, y, "o", color=f"C{i}", ms=8, mec="k", label=f"MuJoCo: {case}")
            res.plot(x, y - expected, "o", color=f"C{i}", ms=6, mec="k")
        else:
            ax.plot(x, y, "s", color="0.35", ms=5, label="MuJoCo: more strike points" if i == len(runs) else None)
            res.plot(x, y - expected, "s", color="0.35", ms=4)
    tol = ctx.scenario.check("reaction-impulse").tolerance
    res.axhspan(-tol, tol, color="C2", alpha=0.15, label=f"tolerance +-{tol:g}")
    diffs = [abs(measured_value(r, "reaction-impulse") - _expected(r, "reaction-impulse")) for _c, r in points]
    biggest = max((d for d in diffs if np.isfinite(d)), default=tol)
    span = 1.5 * max(biggest, 0.05 * tol)  # the differences all visible, the band where it fits
    res.set_ylim(-span, span)
    res.axhline(0.0, color="k", lw=0.6)
    res.set_ylabel("sim - theory (Pi)")
    res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    res.legend(fontsize=7.5, loc="upper right")
    res.set_xlabel("strike distance from the pivot d / L")
    ax.set_ylabel("pivot reaction impulse J / Pi (along the blow)")
    ax.set_title(f"pivoted-stick: reaction impulse against strike distance ({settings_text(runs[0][1])})", fontsize=10)
    ax.legend(fontsize=7.5, loc="upper left")
    return [
        Figure(
            "Pivoted stick: pivot reaction impulse and the sweet spot",
            "A uniform stick pinned at one end, struck perpendicularly at distance d from the pin. The pin's "
            "reaction impulse J (in units of the blow Pi) is docs/theory.md P4's straight line (black): negative (the "
            "pin holds the stick back) for d < 2L/3, zero at the sweet spot d* = 2L/3 (the centre of percussion "
            "referred to the pivot), positive beyond. Points: MuJoCo's impulse from the stick's momentum, read "
            "once the soft pin has settled. Agreement: the points on the line; lower panel: their difference from "
            "the prediction for the instant read (which includes the small turn since the blow), inside the "
            "green tolerance band (the axis is scaled to the differences).",
            fig,
        )
    ]


# ---- ball on the stick (P5) --------------------------------------------------------------------------------------


@plot("ball-stick")
def ball_stick(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    p = runs[0][1].params
    mass, length, offset, u = p["mass"], p["length"], p["offset"], p["ball_speed"]
    inertia = float(ctx.model(runs[0][0]).body("stick").inertia[2])
    m_eff = 1.0 / (1.0 / mass + offset**2 / inertia)
    points = list(runs)
    for ball_mass in (0.02, 0.05, 0.25, 0.5, 3.0):
        run = try_run(ctx, "light-ball", {"ball_mass": ball_mass})
        if run is not None:
            points.append((None, run))
    ms = np.geomspace(0.05 * m_eff, 30 * m_eff, 300)
    curves = [percussion.ball_on_stick(mass, inertia, offset, m, u) for m in ms]
    quantities = (
        ("ball u'/u", lambda th: th.ball_velocity / u, "ball-velocity", lambda v: v / u),
        ("stick V/u", lambda th: th.stick.com_velocity / u, "stick-velocity", lambda v: v / u),
        (
            "stick -omega h/u",
            lambda th: -th.stick.angular_velocity * offset / u,
            "stick-angular-velocity",
            lambda v: -v * offset / u,
        ),
    )
    fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1.2), figsize=(8.0, 5.8))
    for i, (name, curve, check, scale) in enumerate(quantities):
        color = f"C{i}"
        ax.semilogx(ms / m_eff, [curve(th) for th in curves], color=color, lw=1.0, label=f"theory (P5): {name}")
        for case, run in points:
            x = run.params["ball_mass"] / m_eff
            y = scale(measured_value(run, check))
            marker = "o" if case is not None else "s"
            ax.plot(x, y, marker, color=color, ms=7 if case else 5, mec="k")
            res.semilogx(x, y - scale(_expected(run, check)), marker, color=color, ms=5 if case else 4, mec="k")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.axvline(1.0, color="0.5", ls=":", lw=0.8)
    ax.text(1.0, 0.03, " m = M_eff: the ball stops", fontsize=8, transform=ax.get_xaxis_transform())
    for case, run in runs:
        x = run.params["ball_mass"] / m_eff
        ax.annotate(
            case,
            (x, measured_value(run, "ball-velocity") / u),
            xytext=(8, -12),
            textcoords="offset points",
            fontsize=7.5,
            color="C0",
        )
    ax.plot([], [], "o", color="0.6", mec="k", label="MuJoCo: the cases")
    ax.plot([], [], "s", color="0.6", mec="k", ms=5, label="MuJoCo: more ball masses")
    ax.margins(y=0.12)
    ax.set_ylabel("velocity after the impact / u")
    ax.set_title(
        f"ball-stick: elastic impact at h = {offset:g} m on a {mass:g} kg, {length:g} m stick, M_eff = {m_eff:.4g} kg",
        fontsize=10,
    )
    ax.legend(fontsize=7.5, loc="upper left")
    res.axhline(0.0, color="k", lw=0.6)
    res.set_ylabel("sim - theory (u)")
    res.set_xlabel("ball mass m / M_eff,  M_eff = (1/M + h^2/I)^-1")
    res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    return [
        Figure(
            "Ball on a free stick: velocities after the impact against the ball's mass",
            "A ball of mass m at speed u hits a resting free stick elastically at h from its centre (a real MuJoCo "
            "contact). Lines: docs/theory.md P5 with the stick's effective mass M_eff = (1/M + h^2/I)^-1 at the struck "
            "point: the ball's velocity u' = u (m - M_eff)/(m + M_eff) (it stops at m = M_eff, bounces back "
            "below), the stick's CM velocity V = Pi/M and the rotational speed -omega h it gives the struck "
            "point (P1). Circles: the three cases (labelled at the ball's point); squares: further ball masses. "
            "Agreement: the markers on the lines; lower panel: the differences, set by the contact's finite "
            "duration (the stick turns under the ball).",
            fig,
        )
    ]


# ---- marble shot (P6) ----------------------------------------------------------------------------------------------


@plot("marble-shot")
def marble_shot(ctx: PlotContext) -> list[Figure]:
    cases = [c.name for c in ctx.scenario.cases if try_run(ctx, c.name) is not None]
    if not cases:
        return []
    fig, axes = ctx.subplots(1, len(cases), figsize=(5.0 * len(cases), 4.2), squeeze=False, sharey=True)
    for ax, case in zip(axes[0], cases, strict=True):
        run = ctx.run(case)
        model = ctx.model(case)
        traj = run.trajectory
        t_ms = traj.time * 1e3
        k = traj.time > 0
        for name, color, check in (("marble_a", "C0", "marble-a-speed"), ("marble_c", "C3", "marble-c-speed")):
            speed = np.linalg.norm(free_body_motion(model, traj, name).v_W, axis=1)
            label = name.replace("marble_", "marble ").upper().replace("MARBLE", "marble")
            ax.plot(t_ms[k], speed[k], color=color, lw=2.5, alpha=0.6, label=f"MuJoCo: {label}")
            expected = run.prediction[check]
            ax.axhline(expected, color=color, ls="--", lw=1.0)
            ax.text(t_ms[-1], expected, f"theory {expected:.4g} m/s", ha="right", va="bottom", fontsize=8, color=color)
        stick = free_body_motion(model, traj, "stick")
        at_a = stick.point_velocity_W(np.array([0.0, run.prediction["_s_a"], 0.0]))[:, 0]
        ax.plot(t_ms[k], at_a[k], color="0.2", lw=1.0, ls=":", label="stick point at A's end (v_x)")
        ax.axvline(run.prediction["_t_first_hit"] * 1e3, color="0.6", lw=0.6)
        ax.set_xscale("log")
        ax.set_xlabel("t (ms) after the start of the blow")
        ax.set_title(
            f"{case}: h = {run.params['offset']:.3g} m; measured A {measured_value(run, 'marble-a-speed'):.4g}, "
            f"C {measured_value(run, 'marble-c-speed'):.4g} m/s",
            fontsize=9,
        )
        ax.legend(fontsize=7.5, loc="upper left")
    axes[0, 0].set_ylabel("speed (m/s)")
    return [
        Figure(
            "Marble shot: the marbles' speeds",
            "The meter stick on ice between marble A (one end) and marble C (the other), struck toward them. Thick "
            "lines: MuJoCo's marble speeds; dashed: docs/theory.md P6 + P5, following the events in order (the blow, "
            "then the faster-approached marble, then the other with the stick's velocities after the first "
            "collision). Struck at h = L/6 (cop-at-a) the centre of percussion is at A's end: right after the blow "
            "that end is at rest (dotted: the stick point's velocity, zero until C is hit; grey line: the "
            "predicted first hit) and C flies off; but C's recoil then sets A's end moving and A is pushed after "
            "all, at the predicted speed. Struck nearer the centre, A's end moves from the start. Agreement: "
            "each thick line ends on its dashed line.",
            fig,
        )
    ]
