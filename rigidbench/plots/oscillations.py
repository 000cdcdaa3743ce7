"""Figures of the oscillation family: the pendulum's period against amplitude and its elliptic motion, the coupled
pendulums' beats, the chain's mode frequencies and shapes, the double pendulum's normal modes. Simulation
(coloured markers or thick lines) over theory (black, the closed forms of `rigidbench.analytic.oscillations`),
with the difference underneath where the two would otherwise be indistinguishable.

Extra simulations: the pendulum gets four amplitudes beyond its cases (about 0.2 s each) so that the period
curve has points along it; everything else reuses the cases' runs.
"""

from __future__ import annotations

import numpy as np

from rigidbench.analytic import oscillations as osc
from rigidbench.envs import pendulums
from rigidbench.envs.coupled_pendulums import transfer_time
from rigidbench.envs.double_pendulum import absolute
from rigidbench.plots import (
    THEORY_STYLE,
    Figure,
    PlotContext,
    measured_value,
    plot,
    settings_text,
    thin,
    try_run,
)

# ---- the pendulum (O1, O2) -------------------------------------------------------------------------------------


@plot("pendulum")
def pendulum(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    figures = []
    pred = runs[0][1].prediction
    length_eq, g = pred["_length_eq"], pred["_g"]
    t0 = osc.small_amplitude_period(length_eq, g)
    extra = []
    for amplitude in (0.5, 1.5, 2.0, 2.8):
        if (run := try_run(ctx, "one-radian", {"amplitude": amplitude})) is not None:
            extra.append(run)
    a = np.linspace(1e-3, 3.1, 400)
    exact = np.array([osc.pendulum_period(length_eq, g, x) for x in a])
    series = np.array([osc.pendulum_period_series(length_eq, g, x) for x in a])
    fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1.6), figsize=(8.0, 5.8))
    ax.plot(a, exact / t0, label="exact (O1): 4 sqrt(l/g) K(sin(a/2))", **THEORY_STYLE)
    ax.plot(a, series / t0, color="C1", lw=1.0, ls="--", label="series: 1 + a^2/16 + 11 a^4/3072")
    res.semilogy(a, np.abs(series / exact - 1), color="C1", lw=1.0, ls="--", label="series vs exact")
    for i, (case, run) in enumerate(runs):
        x, period = run.params["amplitude"], measured_value(run, "period")
        expected = osc.pendulum_period(length_eq, g, x)
        ax.plot(x, period / t0, "o", color=f"C{i + 2}", ms=8, mec="k", label=f"MuJoCo: {case}")
        res.semilogy(x, max(abs(period / expected - 1), 1e-16), "o", color=f"C{i + 2}", ms=7, mec="k")
    for j, run in enumerate(extra):
        x, period = run.params["amplitude"], measured_value(run, "period")
        expected = osc.pendulum_period(length_eq, g, x)
        ax.plot(x, period / t0, "s", color="0.35", ms=5, label="MuJoCo: more amplitudes" if j == 0 else None)
        res.semilogy(x, max(abs(period / expected - 1), 1e-16), "s", color="0.35", ms=5)
    tol = ctx.scenario.check("period").tolerance
    res.axhline(tol, color="C3", lw=0.8, ls=":", label=f"tolerance {tol:g}")
    ax.set_ylabel("period T / T0,  T0 = 2 pi sqrt(l/g)")
    ax.set_title(f"pendulum: period against amplitude ({settings_text(runs[0][1])})", fontsize=10)
    ax.legend(fontsize=7.5, loc="upper left")
    res.set_ylabel("|T / T_exact - 1|")
    res.set_xlabel("amplitude a (rad), released from rest")
    res.legend(fontsize=7.5, loc="lower right", ncols=2)
    figures.append(
        Figure(
            "Pendulum: period against amplitude",
            "Period of a simple pendulum released from rest at amplitude a, in units of the small-angle period "
            "T0. Black: the exact period 4 sqrt(l/g) K(sin(a/2)) of docs/theory.md O1, which diverges as a -> pi; "
            "orange dashed: the two-term series, good to 2.4e-4 at 1 rad and 7 % at 2.5 rad. Points: MuJoCo's "
            "period measured from 40 zero crossings (circles: the cases; squares: more amplitudes). Agreement: "
            "the points on the black curve at every amplitude. Lower panel: relative errors, the simulation's "
            "orders of magnitude below the tolerance (dotted) and below the series'.",
            fig,
        )
    )
    shown = [(c, r) for c, r in runs if c in ("one-radian", "large-amplitude", "near-inverted")]
    if shown:
        fig, axes = ctx.subplots(
            2, len(shown), sharex="col", height_ratios=(3, 1.2), figsize=(11.0, 5.0), squeeze=False
        )
        for col, (case, run) in enumerate(shown):
            ax, res = axes[0, col], axes[1, col]
            traj, pred = run.trajectory, run.prediction
            window = traj.time <= 3.0 * run.prediction["period"]
            t = traj.time[window]
            theta = traj.qpos[window, 0]
            theory = osc.pendulum_angle(t, pred["_length_eq"], pred["_g"], pred["_amplitude"])
            small = pred["_amplitude"] * np.cos(2 * np.pi * t / t0)
            ax.plot(t, small, color="0.6", lw=0.8, ls=":", label="small-angle: a cos(2 pi t / T0)")
            ax.plot(t, theta, color="C3", lw=3.0, alpha=0.5, label="MuJoCo")
            ax.plot(t, theory, label="exact (O1): 2 arcsin(k cd(omega0 t, k))", **THEORY_STYLE)
            ax.set_title(f"{case}: a = {pred['_amplitude']:g} rad, T = {pred['period'] / t0:.3f} T0", fontsize=9)
            res.plot(t, theta - theory, color="C3", lw=0.8)
            res.set_xlabel("t (s)")
            res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
            ax.set_xlim(0, t[-1])
        axes[0, 0].set_ylabel("angle from the downward vertical (rad)")
        axes[1, 0].set_ylabel("sim - exact (rad)")
        fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside upper center", ncols=3, fontsize=8)
        figures.append(
            Figure(
                "Pendulum: the large-amplitude motion",
                "The angle over the first three periods (of the 20 simulated): "
                "MuJoCo (thick red) on the exact elliptic solution of docs/theory.md O1 (black), which flattens at the "
                "turning points and lags the small-angle cosine (grey dotted) more and more as the amplitude "
                "approaches pi. Lower panels: the difference, a few parts in 1e9 of the amplitude (the integrator's "
                "phase error, oscillating at the turning points).",
                fig,
            )
        )
    return figures


# ---- coupled pendulums: beats (O3, O4) --------------------------------------------------------------------------


@plot("coupled-pendulums")
def coupled_pendulums(ctx: PlotContext) -> list[Figure]:
    figures = []
    for case in ("beats", "weak-coupling"):
        run = try_run(ctx, case)
        if run is None:
            continue
        traj, pred = run.trajectory, run.prediction
        beats: osc.Beats = pred["_beats"]
        t, theta = traj.time, traj.qpos
        amp = beats.amplitude
        theory = beats.angles(t)
        fig, axes = ctx.subplots(3, 1, sharex=True, height_ratios=(2, 2, 1.2), figsize=(9.0, 6.4))
        env = (amp * np.abs(np.cos(beats.beat * t)), amp * np.abs(np.sin(beats.beat * t)))
        for i, ax in enumerate(axes[:2]):
            ax.plot(t, theta[:, i] / amp, color=f"C{i}", lw=1.6, alpha=0.6, label=f"MuJoCo theta_{i + 1}")
            ax.plot(
                t,
                theory[:, i] / amp,
                color="k",
                lw=0.5,
                label="O4: A cos(w0 t) cos(wb t)" if i == 0 else "O4: A sin(w0 t) sin(wb t)",
            )
            ax.plot(t, env[i] / amp, color="C3", lw=1.2, ls="--", label="envelope")
            ax.plot(t, -env[i] / amp, color="C3", lw=1.2, ls="--")
            ax.set_ylabel(f"theta_{i + 1} / A")
            ax.set_ylim(-1.15, 1.6)
            ax.legend(fontsize=7.5, loc="upper right", ncols=3)
        measured = transfer_time(t, theta[:, 1], traj.qvel[:, 1], before=2 * beats.transfer_time)
        for ax in axes:
            for n in range(1, int(t[-1] / beats.transfer_time) + 1):
                ax.axvline(n * beats.transfer_time, color="0.4", lw=0.8, ls=":")
        axes[1].annotate(
            f"T_x = pi/(w_a - w_s) = {beats.transfer_time:.4g} s (measured {measured:.6g} s)",
            (beats.transfer_time, 1.05),
            xytext=(4, 0),
            textcoords="offset points",
            fontsize=8,
        )
        axes[0].set_title(
            f"coupled-pendulums:{case}: w_s = {beats.omega_s:.5g}, w_a = {beats.omega_a:.5g} rad/s, "
            f"A = {amp:g} rad ({settings_text(run)})",
            fontsize=9,
        )
        res = axes[2]
        for i in range(2):
            res.plot(t, (theta[:, i] - theory[:, i]) / amp, color=f"C{i}", lw=0.6, label=f"theta_{i + 1}")
        res.set_ylabel("(sim - O4) / A")
        res.set_xlabel("t (s)")
        res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
        res.legend(fontsize=7.5, loc="upper left")
        figures.append(
            Figure(
                f"Coupled pendulums, {case}: beats and energy transfer",
                "Pendulum 1 released at A, pendulum 2 at rest: the motion is the sum of the in-phase and "
                "anti-phase normal modes (docs/theory.md O3), so each pendulum swings at the mean frequency w0 inside "
                "an envelope A |cos(wb t)| or A |sin(wb t)| (red dashed, O4) and the energy passes completely to "
                "pendulum 2 at T_x = pi/(w_a - w_s) (dotted lines at its multiples), and back. Thick coloured "
                "lines: MuJoCo; thin black: the O4 solution. Agreement: the swing fills the envelope and "
                "pendulum 1 comes to rest at T_x. Lower panel: the difference, growing with time from the small "
                "nonlinear frequency shift at this amplitude (docs/theory.md O4 is the linear solution).",
                fig,
            )
        )
    return figures


# ---- the chain (O5, O7) ------------------------------------------------------------------------------------------


def _chain_omegas(run) -> np.ndarray:
    """Measured mode frequencies of a chain run: zero crossings of each normal coordinate (as the checks do)."""
    modes: osc.NormalModes = run.prediction["_modes"]
    q = modes.coordinates(run.trajectory.qpos)
    return np.array([pendulums.frequency(run.trajectory.time, q[:, r]) for r in range(q.shape[1])])


@plot("pendulum-chain")
def pendulum_chain(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    figures = []
    fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1.6), figsize=(8.0, 5.8))
    for i, (case, run) in enumerate(runs):
        pred = run.prediction
        o5, o7 = pred["_omega_O5"], pred["_omega_O7"]
        n = len(o7)
        sim = _chain_omegas(run)
        r = np.arange(n)
        rr = np.linspace(0, n - 1, 200)
        w0sq = o5[0] ** 2
        kappa4 = (o5[-1] ** 2 - w0sq) / np.sin((n - 1) * np.pi / (2 * n)) ** 2
        color = f"C{i}"
        ax.plot(
            rr,
            np.sqrt(w0sq + kappa4 * np.sin(rr * np.pi / (2 * n)) ** 2),
            color=color,
            lw=0.8,
            ls="--",
            label=f"{case}: O5 dispersion w^2 = g/l + 4 kappa sin^2(r pi / 2N)",
        )
        ax.plot(r, o7, "o", color="k", mfc="none", ms=11, mew=1.0, label="O7 eigenvalues" if i == 0 else None)
        ax.plot(r, sim, "o", color=color, ms=6, mec="k", label=f"{case}: MuJoCo (normal coordinates)")
        res.semilogy(
            r - 0.06 + 0.12 * i,
            np.maximum(np.abs(sim / o7 - 1), 1e-16),
            "o",
            color=color,
            ms=6,
            mec="k",
            label=f"{case}: vs O7",
        )
        res.semilogy(
            r - 0.06 + 0.12 * i, np.maximum(np.abs(sim / o5 - 1), 1e-16), "x", color=color, ms=7, label=f"{case}: vs O5"
        )
    tol = ctx.scenario.check("mode-frequencies").tolerance
    res.axhline(tol, color="C3", lw=0.8, ls=":", label=f"tolerance {tol:g}")
    n = len(runs[0][1].prediction["_omega_O7"])
    ax.set_ylabel("mode frequency w_r (rad/s)")
    ax.set_title(f"pendulum-chain: the N = {n} normal modes ({settings_text(runs[0][1])})", fontsize=10)
    ax.legend(fontsize=7.5, loc="upper left")
    res.set_ylabel("|w_sim / w_theory - 1|")
    res.set_xlabel("mode number r (r = 0: all in phase)")
    res.set_xticks(range(n))
    low = min((v for line in res.get_lines() for v in np.atleast_1d(line.get_ydata()) if v > 0), default=tol)
    res.set_ylim(low / 5, 300 * tol)
    res.legend(fontsize=7, loc="upper center", ncols=3)
    figures.append(
        Figure(
            "Pendulum chain: mode frequencies",
            "A row of N identical pendulums with springs between neighbours, one end pendulum released: every "
            "mode is excited. Coloured dots: the frequency of each normal coordinate of MuJoCo's motion (the "
            "modal filter of docs/theory.md O7, zero crossings over 30 periods); open circles: the eigenvalues of O7; "
            "dashed: O5's closed-form dispersion relation through them. Agreement: each dot inside its circle, "
            "on the curve. Lower panel: relative differences per mode from O7 (dots) and O5 (crosses, hidden behind "
            "the dots: O5 and O7 agree to roundoff), against the tolerance.",
            fig,
        )
    )
    case, run = runs[0]
    pred = run.prediction
    n = len(pred["_omega_O7"])
    sim = _chain_omegas(run)
    if np.isfinite(sim).all():
        z = pendulums.modal_amplitudes(run.trajectory.time, run.trajectory.qpos, sim)
        fig, axes = ctx.subplots(1, n, sharey=True, figsize=(min(2.2 * n, 12.0), 3.2), squeeze=False)
        j = np.arange(n)
        jj = np.linspace(-0.5, n - 0.5, 200)
        for r, ax in enumerate(axes[0]):
            shape = pendulums.mode_shape(z[:, r])
            shape = shape / np.abs(shape).max()
            theory = np.cos(r * np.pi * (jj + 0.5) / n)
            sign = np.sign(np.cos(r * np.pi * 0.5 / n))  # the fitted shape is normalised to th_1 > 0
            ax.plot(jj + 1, sign * theory / np.abs(np.cos(r * np.pi * (j + 0.5) / n)).max(), **THEORY_STYLE)
            ax.plot(j + 1, shape, "o", color="C3", ms=7, mec="k")
            ax.axhline(0, color="0.7", lw=0.6)
            ax.set_title(f"r = {r}: w = {sim[r]:.4g} rad/s", fontsize=8.5)
            ax.set_xticks(j + 1)
            ax.set_xlabel("pendulum j")
        axes[0, 0].set_ylabel("amplitude in the mode (max = 1)")
        figures.append(
            Figure(
                f"Pendulum chain, {case}: mode shapes",
                "Each mode's shape: the amplitude of every pendulum in a least-squares fit of the whole record "
                "by sinusoids at the measured mode frequencies (red dots, normalised to the largest), over O5's "
                "standing wave cos(r pi (j - 1/2) / N) (black, drawn through the pendulums j = 1 ... N). Agreement: "
                "the dots on the curves; mode 0 is the whole row swinging together, springs unstretched.",
                fig,
            )
        )
    return figures


# ---- the double pendulum (O6, O7) --------------------------------------------------------------------------------


@plot("double-pendulum")
def double_pendulum(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    figures = []
    fig, axes = ctx.subplots(1, len(runs), figsize=(3.0 * len(runs) + 0.5, 3.7), squeeze=False)
    for ax, (case, run) in zip(axes[0], runs, strict=True):
        pred = run.prediction
        modes: osc.NormalModes = pred["_modes"]
        theta = absolute(run.trajectory.qpos) * 1e3
        scale = 1.15 * np.abs(theta).max()
        x = np.array([-scale, scale])
        ax.plot(theta[:, 0], theta[:, 1], color="C3", lw=1.2, alpha=0.5, label="MuJoCo")
        text = []
        for r, (name, color) in enumerate((("slow", "C0"), ("fast", "C1"))):
            ratio = modes.shape_ratios()[1, r]
            ax.plot(x, ratio * x, color=color, lw=0.9, ls="--", label=f"{name}-mode line (O6/O7)")
            text.append(f"{name}: {ratio:+.3f}")
        ax.text(0.03, 0.03, "theta2/theta1\n" + "\n".join(text), transform=ax.transAxes, fontsize=7, va="bottom")
        ax.set_xlim(-scale, scale)
        ax.set_ylim(-scale, scale)
        ax.set_aspect("equal")
        ax.set_title(case, fontsize=9)
        ax.set_xlabel("theta1 (mrad)")
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside upper center", ncols=3, fontsize=8)
    axes[0, 0].set_ylabel("theta2 (mrad), absolute")
    figures.append(
        Figure(
            "Double pendulum: trajectories in the (theta1, theta2) plane",
            "The absolute rod angles of MuJoCo's motion (red) with the two normal-mode lines of docs/theory.md O6/O7 "
            "(dashed; theta2/theta1 = +-sqrt 2 for equal masses and lengths). Released in a mode's shape, the "
            "motion stays on that line (slow-mode, fast-mode); released with rod 2 hanging (released, unequal), "
            "it is the sum of both modes, a Lissajous figure inside a parallelogram whose sides are parallel to the "
            "mode lines (the unequal case has its own mode lines, from the general O6 quartic). "
            "Agreement: the single-mode traces do not leave their lines.",
            fig,
        )
    )
    both = [(c, r) for c, r in runs if c in ("released", "unequal")]
    if both:
        fig, axes = ctx.subplots(3, len(both), height_ratios=(2, 2, 1.4), figsize=(10.5, 6.6), squeeze=False)
        for col, (case, run) in enumerate(both):
            pred = run.prediction
            modes = pred["_modes"]
            t = run.trajectory.time
            q = modes.coordinates(absolute(run.trajectory.qpos))
            q0 = modes.coordinates(pred["_angles0"])
            theory = q0 * np.cos(modes.frequencies * t[:, None])
            window = t <= 3 * 2 * np.pi / modes.frequencies[0]
            res = axes[2, col]
            k = thin(len(t), 3000)
            for r, (name, color) in enumerate((("slow", "C0"), ("fast", "C1"))):
                ax = axes[r, col]
                ax.plot(t[window], q[window, r] / q0[r], color=color, lw=3.0, alpha=0.5, label=f"MuJoCo q_{name}")
                ax.plot(t[window], theory[window, r] / q0[r], color="k", lw=0.8, label="theory: q_r(0) cos(w_r t)")
                ax.set_ylabel(f"q_{name} / q_{name}(0)")
                ax.set_ylim(-1.15, 1.6)
                ax.set_title(f"{case}: {name} mode, w = {modes.frequencies[r]:.5g} rad/s (O7)", fontsize=8.5)
                ax.legend(fontsize=7, loc="upper right", ncols=2)
                res.plot(t[k], (q[k, r] - theory[k, r]) / np.abs(q0).max(), color=color, lw=0.7, label=name)
            axes[1, col].set_xlabel("t (s)")
            res.set_xlabel("t (s), the whole run")
            res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
            res.legend(fontsize=7, loc="upper left")
        axes[2, 0].set_ylabel("(sim - theory) / max |q(0)|")
        fig.suptitle("double-pendulum: normal coordinates q_r = a_r^T T theta of the simulated motion", fontsize=10)
        figures.append(
            Figure(
                "Double pendulum: the motion projected on the normal modes",
                "MuJoCo's motion with both modes excited, projected on the mode vectors a_r of docs/theory.md O7 "
                "(q_r = a_r^T T theta, with T the kinetic-energy matrix): each projection is a single cosine at "
                "its own mode frequency, as the normal-mode theorem says (upper rows: the first three slow periods, "
                "MuJoCo thick coloured, black q_r(0) cos(w_r t)). Agreement: each projection is one clean "
                "cosine on the black one, no beating from the other mode. Bottom: the difference over the whole "
                "run, relative to the larger mode amplitude, a slow phase drift from the fast mode's nonlinear "
                "frequency shift at this amplitude (docs/theory.md O6 is linear).",
                fig,
            )
        )
    return figures
