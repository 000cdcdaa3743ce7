"""Figures of the gyrocompass (docs/theory.md G1): the hunting of the spin axis about North in each case, and the
hunting period against amplitude. Simulation (coloured) over theory (black: the exact hunting equation of
`rigidbench.analytic.gyrocompass`, its quadrature period), with the differences underneath.

Extra simulations: three amplitudes of the large-hunting case beyond the cases (about 0.3 s each), so that the
period curve has points along it; everything else reuses the cases' runs.
"""

from __future__ import annotations

import numpy as np

from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, measured_value, plot, settings_text, thin, try_run


@plot("gyrocompass")
def gyrocompass(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    from rigidbench.envs.gyrocompass import _joints

    fig, axes = ctx.subplots(2, 2, height_ratios=(3, 1.4), figsize=(11.0, 6.2))
    (ax, per), (res, per_res) = axes
    worst = 0.0
    for i, (case, run) in enumerate(runs):
        pred, traj = run.prediction, run.trajectory
        g, theory = pred["_geometry"], pred["_theory"]
        model = ctx.model(case)
        j = _joints(model)
        t = traj.time
        alpha = traj.qpos[:, j.gimbal_q] - g.north
        exact = theory.azimuth(t, pred["_azimuth0"] - g.north, pred["_rate0"])
        scale = pred["_amplitude"]
        period = pred["hunting-period"]
        s = thin(len(t))
        label = f"{case} ({scale:.3g} rad, {np.degrees(g.latitude):.0f} deg)"
        ax.plot(t[s] / period, alpha[s] / scale, ".", color=f"C{i}", ms=3, label=label)
        ax.plot(t / period, exact / scale, **THEORY_STYLE, label="theory (G1)" if i == 0 else None)
        diff = np.abs(alpha - exact) / scale
        worst = max(worst, float(diff.max()))
        res.semilogy(t[s] / period, np.maximum(diff[s], 1e-17), color=f"C{i}", lw=1.0)
    ax.axhline(0.0, color="C3", lw=0.8, ls=":", label="North")
    ax.set_ylabel("azimuth alpha / amplitude")
    ax.set_title(f"gyrocompass: the spin axis hunts about North ({settings_text(runs[0][1])})", fontsize=10)
    ax.set_ylim(-1.75, 1.15)
    ax.legend(
        fontsize=7, loc="lower center", ncols=3, title="MuJoCo (dots): case (amplitude, latitude)", title_fontsize=7
    )
    res.set_xlabel("time / hunting period (quadrature)")
    res.set_ylabel("|alpha - alpha_theory| / a")

    # Period against amplitude at the large-hunting case's parameters.
    base = next((r for c, r in runs if c == "large-hunting"), runs[0][1])
    theory = base.prediction["_theory"]
    t0 = 2 * np.pi / theory.hunting_frequency
    a = np.linspace(1e-3, 3.0, 300)
    per.plot(a, [theory.period(x) / t0 for x in a], **THEORY_STYLE, label="quadrature (G1)")
    per.plot(
        a,
        1 + np.array([theory.small_amplitude_shift(x) for x in a]),
        color="C1",
        lw=1.0,
        ls="--",
        label="1 + ((A - 4B)/(A - B)) a^2/16",
    )
    points = [(c, r) for c, r in runs if c != "high-latitude"]
    for amplitude in (0.5, 1.5, 2.9):
        if (r := try_run(ctx, "large-hunting", {"amplitude": amplitude})) is not None:
            points.append(("more amplitudes", r))
    shown = set()
    for case, run in points:
        p = run.prediction
        # each run over its own T0 (H, hence omega_g, moves by ~Omega_perp / chi' with the release azimuth)
        x, measured = p["_amplitude"], measured_value(run, "hunting-period")
        own_t0 = 2 * np.pi / p["_theory"].hunting_frequency
        marker, color = ("s", "0.35") if case == "more amplitudes" else ("o", "C2")
        label = None if case in shown else f"MuJoCo: {case}"
        per.plot(x, measured / own_t0, marker, color=color, ms=6, mec="k", label=label)
        shown.add(case)
        per_res.semilogy(x, max(abs(measured / p["hunting-period"] - 1), 1e-16), marker, color=color, ms=6, mec="k")
    simple = abs(theory.hunting_frequency / theory.simple_frequency - 1)
    per_res.axhline(simple, color="0.5", lw=0.8, ls="--", label=f"fast-rotor form's error {simple:.1e}")
    tol = ctx.scenario.check("hunting-period").tolerance
    per_res.axhline(tol, color="C3", lw=0.8, ls=":", label=f"tolerance {tol:g}")
    per.set_ylabel("hunting period T / T0,  T0 = 2 pi / omega_g")
    per.set_title("period against amplitude (large-hunting's parameters)", fontsize=10)
    per.legend(fontsize=7, loc="upper left")
    per_res.set_xlabel("amplitude a (rad), released at rest relative to the platform")
    per_res.set_ylabel("|T / T_quadrature - 1|")
    per_res.set_ylim(1e-13, 1e-2)
    per_res.legend(fontsize=7, loc="upper left", ncols=2)
    return [
        Figure(
            "Gyrocompass: hunting about North, and its period against amplitude",
            "Left: the azimuth of the spin axis (from North towards East), over its amplitude, against time in hunting "
            "periods, for each case: MuJoCo (dots) over the exact hunting equation of docs/theory.md G1 integrated "
            "from the simulated initial state (black). The axis swings symmetrically about North (dotted): the "
            "north-seeking equilibrium. Agreement: the dots on the black curves; the lower panel gives the "
            f"difference over the amplitude (worst {worst:.1e}). Right: the period against amplitude, in units of "
            "the small-amplitude period 2 pi / omega_g: black the quadrature, orange dashed the leading a^2 term. "
            "Points: MuJoCo's period from the zero crossings (circles: the cases; squares: more amplitudes); lower "
            "panel their relative error against the quadrature, below the tolerance (dotted) and far below the error "
            "of the fast-rotor form sqrt(H Omega_perp / (I_t + I_g)) that drops the I_t Omega_perp^2 term (dashed): "
            "MuJoCo resolves that term.",
            fig,
        )
    ]
