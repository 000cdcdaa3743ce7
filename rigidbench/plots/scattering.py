"""Figures of the scattering family: the deflection function of one collision against the impact parameter (the
soft-contact prediction MuJoCo simulates and the hard-sphere limit), its LAB angles, and the Monte Carlo beam's
angular distributions against a^2/4 (CM) and the LAB cross sections. Simulation (coloured markers) over theory
(black, the closed forms of `rigidbench.analytic.scattering`).

Extra simulations: the deflection functions get a few impact parameters beyond the cases (one collision each,
about 0.2 s); the cross sections reuse the cases' beams.
"""

from __future__ import annotations

import numpy as np

from rigidbench.analytic import scattering
from rigidbench.envs.cross_section import NBINS, distribution_bins
from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, measured_value, plot, settings_text, try_run

# The deflection function's extra points, b / a, and the cases (mass ratios) that get them.
EXTRA_B = (0.1, 0.25, 0.4, 0.55, 0.7, 0.85, 0.95)
RATIOS = (("light-projectile", "m1/m2 = 1/3"), ("equal-mass", "1"), ("heavy-projectile", "3"))


# ---- one collision: the deflection function (C2, C5, C8) --------------------------------------------------------


def _final_angles(ctx: PlotContext, case: str, state: np.ndarray, v0: np.ndarray) -> dict:
    """CM and LAB angles from a probe's final full-physics state row."""
    model = ctx.model(case)
    qpos, qvel = state[1 : 1 + model.nq], state[1 + model.nq : 1 + model.nq + model.nv]
    return ctx.scenario.outgoing(model, qpos, qvel, v0)


@plot("hard-spheres")
def hard_spheres(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    pred = runs[0][1].prediction
    a, speed, spring = pred["_a"], pred["_speed"], pred["_spring"]
    elastic = pred["_elastic"]
    k = spring.stiffness
    # Points, grouped by mass ratio: every case, and more impact parameters for three of the ratios.
    points: dict[float, list] = {}
    for case, run in runs:
        points.setdefault(run.params["m1"] / run.params["m2"], []).append((case, run))
    for case, _color in RATIOS:
        for f in EXTRA_B:
            if (run := try_run(ctx, case, {"b": f * a})) is not None:
                points.setdefault(run.params["m1"] / run.params["m2"], []).append((case, run))
    colors = {x: f"C{i}" for i, x in enumerate(sorted(points))}
    b = np.linspace(0.0, 0.9999, 600) * a
    hard = scattering.hard_sphere_cm_angle(b, a)
    figures = []

    fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(2.2, 2), figsize=(8.0, 6.2))
    ax.plot(b / a, hard, label="hard spheres (C5): theta = 2 arccos(b/a)", **THEORY_STYLE)
    if elastic:
        soft = scattering.soft_sphere_cm_angle(b, a, k, speed)
        ax.plot(b / a, soft, color="C3", lw=1.0, ls="--", label=f"soft contact (C8), k = {k:.3g} 1/s^2")
        res.plot(b / a, hard - soft, color="C3", lw=1.0, label=f"C8 at k = {k:.3g} 1/s^2 (this contact)")
        soft16 = scattering.soft_sphere_cm_angle(b, a, k / 16, speed)
        res.plot(b / a, hard - soft16, color="C4", lw=1.0, label=f"C8 at k/16 = {k / 16:.3g} 1/s^2")
        res.plot(
            b / a,
            scattering.soft_sphere_shift_first_order(b, a, k, speed),
            color="0.5",
            lw=0.8,
            ls=":",
            label="first order: pi (b/a) u / (a sqrt(k))",
        )
    first = True
    for group in points.values():
        for case, run in group:
            bb = run.prediction["_b"] / a
            theta = measured_value(run, "cm-angle")
            ax.plot(bb, theta, "o", color="C3", ms=5, mec="k", label="MuJoCo" if first else None)
            res.plot(
                bb,
                run.prediction["cm-angle-hard"] - theta,
                "o",
                color="C3",
                ms=5,
                mec="k",
                label="MuJoCo at k" if first else None,
            )
            probe = run.trajectory.probes.get("softer")
            if probe is not None and np.isfinite(probe).all():
                theta16 = _final_angles(ctx, case, probe, run.trajectory.qvel[0, :3])["theta"]
                res.plot(
                    bb,
                    run.prediction["cm-angle-hard"] - theta16,
                    "s",
                    color="C4",
                    ms=5,
                    mec="k",
                    label="MuJoCo at k/16 (the scaling probe)" if first else None,
                )
            first = False
    ax.set_ylabel("CM scattering angle theta (rad)")
    ax.set_title(
        f"hard-spheres: deflection function, a = r1 + r2 = {a:g} m, u = {speed:g} m/s ({settings_text(runs[0][1])})",
        fontsize=9,
    )
    ax.legend(fontsize=8, loc="upper right")
    res.set_ylabel("theta_hard - theta (rad)")
    res.set_xlabel("impact parameter b / a")
    res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    res.legend(fontsize=7.5, loc="upper left")
    figures.append(
        Figure(
            "Hard spheres: scattering angle against the impact parameter",
            "CM deflection of one smooth elastic collision against b/a: the six cases and more impact parameters "
            "(the mass ratio does not change the CM angle, so all points share the curve). Top: the hard-sphere "
            "theta = 2 arccos(b/a) of docs/theory.md C5 "
            "(black) and the soft-contact prediction (red dashed, C8: MuJoCo's contact is the spring V = 1/2 mu "
            "k (a - r)^2) are indistinguishable at this scale, and MuJoCo's points lie on both. Bottom: the soft "
            "shift theta_hard - theta, which grows with b and scales as k^-1/2: the C8 curves at this stiffness "
            "and at k/16 (4x larger) with MuJoCo's points on them (circles; squares from the probe run at k/16), "
            "and the first-order estimate (dotted). Agreement: the points on the C8 curves, not on zero.",
            fig,
        )
    )

    fig, (ax, az) = ctx.subplots(1, 2, figsize=(10.5, 4.4))
    psi, zeta = scattering.lab_angles(hard, 1.0)
    az.plot(b / a, zeta, label="C2 + C5: zeta = arcsin(b/a), any m1/m2", **THEORY_STYLE)
    for x, group in sorted(points.items()):
        color = colors[x]
        psi, _ = scattering.lab_angles(hard, x)
        ax.plot(b / a, psi, color=color, lw=1.0, label=f"C2 + C5, m1/m2 = {x:.3g}")
        for j, (_case, run) in enumerate(group):
            bb = run.prediction["_b"] / a
            ax.plot(
                bb,
                measured_value(run, "projectile-lab-angle"),
                "o",
                color=color,
                ms=5,
                mec="k",
                label=f"MuJoCo, m1/m2 = {x:.3g}" if j == 0 else None,
            )
            az.plot(
                bb,
                measured_value(run, "target-lab-angle"),
                "o",
                color=color,
                ms=5,
                mec="k",
                label=f"MuJoCo, m1/m2 = {x:.3g}" if j == 0 else None,
            )
        if x > 1:
            b0 = scattering.critical_impact_parameter(a, x)
            top = scattering.max_lab_angle(x)
            ax.axhline(top, color=color, ls=":", lw=0.8)
            ax.text(
                0.02, top + 0.04, f"psi_max = arcsin(m2/m1), at b0 = {b0 / a:.3f} a (C3)", fontsize=7.5, color=color
            )
            case, run = group[0]
            probe = run.trajectory.probes.get("b0")
            if probe is not None and np.isfinite(probe).all():
                measured = _final_angles(ctx, case, probe, run.trajectory.qvel[0, :3])["psi"]
                ax.plot(b0 / a, measured, "*", color=color, ms=13, mec="k", label="MuJoCo at b0 (probe)")
    ax.set_xlabel("impact parameter b / a")
    ax.set_ylabel("projectile LAB angle psi (rad)")
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title("projectile", fontsize=9)
    az.set_xlabel("impact parameter b / a")
    az.set_ylabel("target recoil angle zeta (rad)")
    az.legend(fontsize=7, loc="lower right")
    az.set_title("target", fontsize=9)
    figures.append(
        Figure(
            "Hard spheres: LAB angles against the impact parameter",
            "LAB angles of the projectile (left) and the recoiling target (right), target initially at rest, for "
            "the cases' mass ratios (1/3, 1/2, 1, 3). Lines: docs/theory.md C2 applied to the hard-sphere CM angle "
            "(C5); points: MuJoCo. "
            "A light projectile can bounce back (psi up to pi); equal masses leave at psi = theta/2, at right "
            "angles to the target; a heavy projectile never turns by more than psi_max = arcsin(m2/m1) (dotted), "
            "reached at b0 (star: the probe run there), with two impact parameters for every smaller angle. The "
            "target recoils at zeta = arcsin(b/a) whatever the masses. Agreement: the points on their lines "
            "(the soft shift, ~1e-3 rad, is invisible here).",
            fig,
        )
    )
    return figures


# ---- the beam: cross sections (C5, C6) ---------------------------------------------------------------------------


def _histogram(counts: np.ndarray, edges: np.ndarray, n: int, beam_area: float) -> tuple[np.ndarray, np.ndarray]:
    """Differential cross section (m^2/sr) per bin from the bin `counts` of a beam of `n` collisions over
    `beam_area` (angle bins `edges`), and its Poisson standard error: sigma_beam (count / n) / (2 pi (cos lo - cos
    hi))."""
    counts = np.asarray(counts, dtype=float)
    solid = 2 * np.pi * (np.cos(edges[:-1]) - np.cos(edges[1:]))
    scale = beam_area / n / solid
    return counts * scale, np.sqrt(counts) * scale


@plot("cross-section")
def cross_section(ctx: PlotContext) -> list[Figure]:
    runs = [(c.name, r) for c in ctx.scenario.cases if (r := try_run(ctx, c.name)) is not None]
    if not runs:
        return []
    fig, axes = ctx.subplots(len(runs), 3, figsize=(12.0, 3.1 * len(runs) + 0.4), squeeze=False)
    for row, (case, run) in enumerate(runs):
        pred = run.prediction
        a, x, n = pred["_a"], pred["_x"], pred["_n"]
        beam_area = np.pi * pred["_beam_radius"] ** 2
        model = ctx.model(case)
        tally = run.trajectory.tally  # the counts the checks tested, over the whole beam
        bins = distribution_bins(model)
        sigma = measured_value(run, "total-cross-section")
        # The checks' bins: cos(theta) ascending is theta descending, so the CM counts are reversed.
        cos_edges = bins["cm"][0]
        counts = {
            "theta": tally.counts["cm"][:NBINS][::-1],
            "psi": tally.counts["projectile"][:NBINS],
            "zeta": tally.counts["target"][:NBINS],
        }
        panels = (
            (
                "theta",
                "CM angle theta",
                np.arccos(cos_edges[::-1]),
                "C5: a^2/4",
                lambda t, a=a: np.full_like(t, a * a / 4),
                "cm-distribution-pvalue",
            ),
            (
                "psi",
                "projectile LAB angle psi",
                bins["projectile"][0],
                "C6: sum over branches (a^2/4)(x cos psi +- s)^2/s",
                lambda p, a=a, x=x: scattering.lab_cross_section_projectile(p, a, x),
                "projectile-distribution-pvalue",
            ),
            (
                "zeta",
                "target LAB angle zeta",
                bins["target"][0],
                "C6: a^2 cos(zeta)",
                lambda z, a=a: scattering.lab_cross_section_target(z, a),
                "target-distribution-pvalue",
            ),
        )
        for col, (key, name, edges, label, curve, check) in enumerate(panels):
            ax = axes[row, col]
            value, err = _histogram(counts[key], edges, n, beam_area)
            mid = 0.5 * (edges[1:] + edges[:-1])
            fine = np.linspace(edges[0], edges[-1], 400)[1:-1]
            ax.plot(fine, curve(fine) * 1e4, label=label, **THEORY_STYLE)
            avg = None
            if key != "theta":  # bin averages of the theory: what a histogram estimates (matters near psi_max)
                particle = "projectile" if key == "psi" else "target"
                prob = scattering.lab_angle_probabilities(edges, a, x, particle=particle)
                avg = prob * np.pi * a * a / (2 * np.pi * (np.cos(edges[:-1]) - np.cos(edges[1:])))
                ax.stairs(avg * 1e4, edges, color="0.5", lw=0.8, ls="--", baseline=None, label="theory, bin averages")
            ax.errorbar(
                mid,
                value * 1e4,
                yerr=err * 1e4,
                fmt="o",
                color="C3",
                ms=4,
                mec="k",
                capsize=2,
                label=f"MuJoCo, {tally.hits} hits of {n}",
            )
            ax.set_xlabel(f"{name} (rad)")
            reference = avg if key != "theta" else np.array([a * a / 4])
            top = np.nanmax(np.concatenate([value + err, reference])) * 1e4
            ax.set_ylim(0, 1.35 * top)
            ax.set_title(f"{case} (m1/m2 = {x:.3g}): chi-square p = {measured_value(run, check):.2f}", fontsize=8.5)
            ax.legend(fontsize=6.5, loc="upper right")
        axes[row, 0].set_ylabel("dsigma/dOmega (cm^2/sr)")
        axes[row, 0].text(
            0.03,
            0.05,
            f"sigma_tot = {sigma * 1e4:.4g} cm^2\n(pi a^2 = {np.pi * a * a * 1e4:.4g} cm^2)",
            transform=axes[row, 0].transAxes,
            fontsize=7.5,
        )
    return [
        Figure(
            "Cross sections: histograms of a uniform beam against C5 and C6",
            "A beam of collisions with impact points uniform over a disc larger than the target (MuJoCo, batched), one "
            "row per mass ratio. Each histogram (the checks' own bins and counts over the whole beam) is converted "
            "to a differential cross section (counts / n times the beam area, over the bin's solid angle; error bars: "
            "Poisson). Left: the CM angle, isotropic at a^2/4 (docs/theory.md C5). Middle: the projectile's LAB angle "
            "against C6's sum over branches (a^2 cos(psi) for equal masses, one branch over [0, pi] for a light "
            "projectile, two branches piling up below psi_max with an integrable singularity for a heavy one; dashed: "
            "the theory's bin averages, what the histogram estimates). Right: the target's recoil, a^2 cos(zeta) for "
            "every mass ratio. The beams of the three rows share their seed, hence their impact points: the CM and "
            "recoil angles do not depend on the masses, so those histograms repeat row to row. Agreement: the points "
            "within their error bars of the curves (the titles give the chi-square p-values of the checks), and the "
            "total cross section close to pi a^2.",
            fig,
        )
    ]
