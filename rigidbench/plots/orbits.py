"""Figures of the two-body orbits: the LAB and CM views side by side, as in Harter's CoulIt pictures (seed 001), for
the Kepler and the Hooke orbit, and the orbit error of every case against time. Simulation (coloured) over theory
(black, the closed forms of `rigidbench.analytic.orbits`). No extra simulations: the figures reuse the cases' runs.
"""

from __future__ import annotations

import numpy as np

from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, plot, settings_text, thin, try_run

# The LAB/CM pairs drawn: (case, what its LAB view shows).
VIEWS = (
    ("kepler-eccentric", "Kepler, e = 0.69, body 2 starting at rest"),
    ("hooke", "Hooke, body 2 starting at rest"),
)


def _lab_cm(ctx: PlotContext, case: str, label: str) -> Figure | None:
    run = try_run(ctx, case)
    if run is None:
        return None
    scenario, pred, traj = ctx.scenario, run.prediction, run.trajectory
    model = ctx.model(case)
    view = scenario.cm_frame(model, traj, pred)
    orbit = pred["_theory"]
    t = np.asarray(traj.time)
    rel, _ = orbit.position(t)
    every = thin(len(t), 300)
    fig, (lab, cm) = ctx.subplots(1, 2, figsize=(10.0, 4.8))
    for i, color in ((1, "C1"), (2, "C0")):
        body = pred["_bodies"][i - 1]
        x = view[f"x{i}"]
        lab.plot(x[every, 0], x[every, 1], ".", color=color, ms=3, label=f"body {i} (MuJoCo)")
        theory_lab = view["centre"] + body.scale * rel
        lab.plot(theory_lab[:, 0], theory_lab[:, 1], **THEORY_STYLE, label="theory" if i == 1 else None)
        r = view[f"r{i}"]
        cm.plot(r[every, 0], r[every, 1], ".", color=color, ms=3, label=f"body {i}: a_{i} = {body.semi_major:.3g} m")
        cm.plot(body.scale * rel[:, 0], body.scale * rel[:, 1], **THEORY_STYLE, label="theory (K3)" if i == 1 else None)
    lab.plot(view["cm"][every, 0], view["cm"][every, 1], ".", color="C2", ms=2, label="CM (MuJoCo)")
    lab.plot(view["centre"][:, 0], view["centre"][:, 1], ls="--", color="k", lw=0.8, label="R0 + V0 t")
    cm.plot([0.0], [0.0], "+", color="C2", ms=12, mew=2, label="CM")
    for ax, title in ((lab, "LAB frame"), (cm, "CM frame")):
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(title)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(f"{label}: {settings_text(run)}", fontsize=10)
    shared = "share a focus at the CM" if orbit.law == "kepler" else "share their centre at the CM"
    return Figure(
        f"Two-body orbit, LAB and CM views ({case})",
        f"{label}. Left, the LAB frame: each body's path (coloured dots, MuJoCo) over the theory (black), the CM "
        "moving uniformly along R0 + V0 t. Right, the CM frame: the two orbits are mass-scaled copies of the "
        f"relative orbit (docs/theory.md K3, r1' = (m2/M) r, r2' = -(m1/M) r) and {shared}; agreement is the dots on "
        "the "
        "black curves.",
        fig,
    )


@plot("two-body-orbit")
def two_body_orbit(ctx: PlotContext) -> list[Figure]:
    figures = [f for case, label in VIEWS if (f := _lab_cm(ctx, case, label)) is not None]
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if runs:
        fig, ax = ctx.subplots()
        for k, (case, run) in enumerate(runs):
            pred, traj = run.prediction, run.trajectory
            view = ctx.scenario.cm_frame(ctx.model(case), traj, pred)
            t = np.asarray(traj.time)
            rel, _ = pred["_theory"].position(t)
            body = pred["_bodies"][0]
            err = np.linalg.norm(view["r1"] - body.scale * rel, axis=1) / body.semi_major
            every = thin(len(t), 2000)
            shown = np.maximum(err[every], 1e-17)  # the first sample is exact
            ax.semilogy(t[every] / pred["_theory"].period, shown, color=f"C{k}", lw=1, label=case)
        tolerance = ctx.scenario.check("orbit-1").tolerance
        ax.axhline(tolerance, color="k", ls="--", lw=0.8, label=f"orbit-1 tolerance {tolerance:g}")
        ax.set_xlabel("t / T (periods)")
        ax.set_ylabel("|r1'(t) - r1'_theory(t)| / a_1")
        ax.set_title(f"Body 1's CM-frame orbit against K2/K3 ({settings_text(runs[0][1])})", fontsize=10)
        ax.legend(fontsize=7)
        figures.append(
            Figure(
                "Two-body orbit error against time",
                "Distance between body 1's simulated CM-frame position and the closed form (Kepler's equation, or the "
                "isotropic oscillator), in units of its semi-major axis, for every case: it grows along the run "
                "(RK4's phase error), and under reference settings stays far below the orbit checks' tolerance "
                "(dashed).",
                fig,
            )
        )
    return figures
