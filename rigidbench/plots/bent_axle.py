"""Figures of the bent axle (docs/theory.md R8): the bearing torque turning with the rotor in space, MuJoCo's
sensors over the closed form of `rigidbench.analytic.bent_axle`, and the reaction of every case in the rotor's axes
against its round-off floor."""

from __future__ import annotations

import numpy as np

from rigidbench.analytic import bent_axle as ba
from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, plot, settings_text, thin, try_run

SIM = {"lw": 0, "marker": "o", "ms": 2.2, "alpha": 0.85}


@plot("bent-axle")
def bent_axle(ctx: PlotContext) -> list[Figure]:
    figures = []
    turning = [(case, run) for case in ("tilted-disc", "off-axle") if (run := try_run(ctx, case)) is not None]
    if turning:
        fig, axes = ctx.subplots(2, len(turning), sharex="col", height_ratios=(3, 1), figsize=(9, 5.2), squeeze=False)
        for col, (case, run) in enumerate(turning):
            traj, axle = run.trajectory, run.prediction["_theory"]
            t = traj.time
            measured = ba.rotate_about_axle(traj.torque_B, traj.qpos[:, 0])
            predicted = axle.torque_W(t)
            ax, res = axes[0, col], axes[1, col]
            k = thin(len(t), 150)
            for i, name in enumerate(("N_x", "N_y", "N_z")):
                ax.plot(t, predicted[:, i], **THEORY_STYLE)
                ax.plot(t[k], measured[k, i], color=f"C{i}", label=f"{name} (MuJoCo)", **SIM)
            ax.set_title(f"bent-axle:{case}: |N| = {axle.torque:.4g} N m", fontsize=10)
            ax.set_ylabel("torque on the rotor, space axes (N m)")
            ax.legend(fontsize=8, loc="upper right", ncols=3, frameon=False)
            ax.set_ylim(-1.45 * axle.torque, 1.45 * axle.torque)
            err = np.linalg.norm(measured - predicted, axis=1) / axle.torque
            res.semilogy(t, np.maximum(err, 1e-17), color="C3", lw=0.8)
            res.set_ylabel("|sim - R8| / |N|")
            res.set_xlabel("t (s)")
        figures.append(
            Figure(
                "Bent axle: the bearing torque turns with the rotor",
                "The torque the axle exerts on the rotor about O, in space axes, over the run (5 turns): MuJoCo's "
                "torque sensor at the bearing (dots) over N = omega x L = omega^2 (-I_yz, I_xz, 0) turned by omega t "
                "(docs/theory.md R8, black). N stays perpendicular to the axle (N_z = 0) and turns at the axle rate. "
                "Lower "
                f"panels: the relative difference ({settings_text(turning[0][1])}): round-off, growing only with "
                "the rotor's angle (theta = omega t is integrated exactly; qpos carries one rounding per step).",
                fig,
            )
        )
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if runs:
        fig, ax = ctx.subplots(figsize=(8, 4.2))
        labels, positions = [], []
        for j, (case, run) in enumerate(runs):
            traj, axle = run.trajectory, run.prediction["_theory"]
            torque = np.linalg.norm(traj.torque_B, axis=1) / axle.torque_scale
            force = np.linalg.norm(traj.force_B, axis=1) / axle.force_scale
            for i, (values, expected, name) in enumerate(
                (
                    (torque, axle.torque / axle.torque_scale, "|N| / (omega^2 |I_O|)"),
                    (force, axle.force / axle.force_scale, "|F| / (omega^2 sqrt(m |I_O|))"),
                )
            ):
                x = 3 * j + i
                floor = 1e-17
                ax.plot([x - 0.3, x + 0.3], [max(expected, floor)] * 2, **THEORY_STYLE)
                ax.plot(
                    np.full(2, x),
                    [max(values.min(), floor), max(values.max(), floor)],
                    color=f"C{i}",
                    lw=4,
                    marker="o",
                    ms=7,
                    alpha=0.8,
                    label=name if j == 0 else None,
                )
                labels.append(f"{case}\n{'torque' if i == 0 else 'force'}")
                positions.append(x)
        ax.axhline(1e-13, color="0.5", ls="--", lw=0.8)
        ax.text(positions[-1] + 0.5, 1e-13, " zero-check\n tolerance", va="center", fontsize=8, color="0.3")
        ax.set_yscale("log")
        ax.set_ylim(1e-18, 10)
        ax.set_xticks(positions, labels, fontsize=8)
        ax.set_xlabel("case and quantity")
        ax.set_ylabel("reaction in units of its scale")
        ax.set_title(f"bent-axle: torque and force of every case ({settings_text(runs[0][1])})", fontsize=10)
        ax.legend(fontsize=8, loc="upper right", frameon=False)
        figures.append(
            Figure(
                "Bent axle: the reaction of every case against R8",
                "Smallest and largest over the run of the bearing torque |N| and force |F| read from MuJoCo's sensors "
                "(dots; they coincide), in "
                "units of omega^2 |I_O| and omega^2 sqrt(m |I_O|), over R8's values (black ticks). The tilted disc "
                "needs a pure couple (no force: its dot sits on the plot's 1e-17 floor, i.e. exactly 0); the "
                "point mass off the axle needs both; the balanced rotor needs neither, and MuJoCo gives exactly 0, "
                "below the 1e-13 tolerance of the absolute checks (dashed).",
                fig,
            )
        )
    return figures
