"""Figures of Rutherford scattering (`rigidbench.envs.rutherford`): the deflection function and LAB angles against
the impact parameter (every pair of the Monte Carlo beam is a point), the beam's histograms over Rutherford's
1/sin^4(theta/2) and the LAB cross sections, and the LAB and CM views of one orbit side by side (docs/theory.md C9: the
LAB path has no asymptote). Simulation (coloured markers) over theory (black, `rigidbench.analytic.coulomb`).

Extra simulations: none; the figures reuse the cases' runs (the beam's final states give its deflection function).
"""

from __future__ import annotations

import numpy as np

from rigidbench.analytic import coulomb, scattering
from rigidbench.envs.rutherford import beam_bins
from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, measured_value, plot, settings_text, try_run


@plot("rutherford")
def rutherford(ctx: PlotContext) -> list[Figure]:
    figures = []
    beam = try_run(ctx, "cross-section")
    singles = [(c, r) for c in ("equal-mass", "heavy-target", "light-target", "head-on") if (r := try_run(ctx, c))]
    if beam is not None:
        figures += _deflection(ctx, beam, singles)
        figures += _histograms(ctx, beam)
    orbit = try_run(ctx, "lab-orbit")
    if orbit is not None:
        figures.append(_orbits(ctx, orbit))
    return figures


def _beam_angles(ctx: PlotContext, run) -> dict:
    """Per pair of the beam: b / D and the measured theta, psi, zeta (from its final state)."""
    pred = run.prediction
    out = ctx.scenario.outgoing(pred, run.trajectory.qpos[-1], run.trajectory.qvel[-1])
    return {"b": pred["_b"] / pred["_distance"], **{k: out[k] for k in ("theta", "psi", "zeta")}}


def _deflection(ctx: PlotContext, beam, singles) -> list[Figure]:
    pred = beam.prediction
    pr = pred["_pairs"]
    x = pr["m1"] / pr["m2"]
    got = _beam_angles(ctx, beam)
    b = np.linspace(0.0, max(got["b"].max(), 4.0) * 1.02, 600)
    theta = coulomb.cm_angle(b, 1.0)
    fig, ((ax, lab), (res, _spare)) = ctx.subplots(2, 2, height_ratios=(2.2, 1.4), figsize=(10.5, 6.4))
    _spare.axis("off")
    res.sharex(ax)
    ax.plot(b, theta, label="C7: theta = 2 arctan(D / b)", **THEORY_STYLE)
    ax.plot(got["b"], got["theta"], ".", color="C0", ms=3, label=f"MuJoCo, the beam's {len(got['b'])} pairs")
    for i, (case, run) in enumerate(singles):
        bb = run.prediction["_b"][0] / run.prediction["_distance"]
        theta_i = ctx.scenario.outgoing(run.prediction, run.trajectory.qpos[-1], run.trajectory.qvel[-1])["theta"][0]
        ax.plot(bb, theta_i, "o", color=f"C{i + 1}", ms=6, mec="k", label=f"MuJoCo, {case}")
    ax.set_ylabel("CM scattering angle theta (rad)")
    ax.set_title(f"rutherford: deflection function ({settings_text(beam)})", fontsize=9)
    ax.legend(fontsize=8)
    res.plot(got["b"], got["theta"] - coulomb.cm_angle(pred["_b"], pred["_distance"]), ".", color="C0", ms=3)
    res.axhline(0.0, color="k", lw=0.8)
    tol = beam.outcomes[0].check.tolerance if beam.outcomes else 1e-7
    res.axhline(tol, color="0.5", ls=":", lw=0.8, label=f"tolerance +-{tol:g} rad")
    res.axhline(-tol, color="0.5", ls=":", lw=0.8)
    res.set_ylabel("theta - theory (rad)")
    res.set_xlabel("impact parameter b / D,  D = k / (mu v^2)")
    res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    res.legend(fontsize=8)
    psi, zeta = scattering.lab_angles(theta, x)
    lab.plot(b, psi, color="C0", lw=1.0, label=f"C2: projectile psi, m1/m2 = {x:.3g}")
    lab.plot(b, zeta, color="C3", lw=1.0, label="C2: target zeta = (pi - theta) / 2")
    lab.plot(got["b"], got["psi"], ".", color="C0", ms=3, label="MuJoCo psi (beam)")
    lab.plot(got["b"], got["zeta"], ".", color="C3", ms=3, label="MuJoCo zeta (beam)")
    lab.set_ylabel("LAB angle (rad)")
    lab.set_xlabel("impact parameter b / D")
    lab.legend(fontsize=8)
    lab.set_title(f"LAB angles of the beam (m2 = {pr['m2'] / pr['m1']:.3g} m1)", fontsize=9)
    return [
        Figure(
            "Rutherford: scattering angle against the impact parameter",
            "Left: the CM deflection of every pair of the Monte Carlo beam (one MuJoCo model of "
            f"{len(got['b'])} independent pairs) and of the single-collision cases, against tan(theta/2) = D / b "
            "(docs/theory.md C7, black); bottom, the residual against the RK4 tolerance. Right: the LAB angles of the "
            "projectile and of the recoiling target (C2). Agreement: the points on the curves and the residuals "
            "inside the dotted band (they are ~1e-8 rad, RK4 at 20 steps per passage).",
            fig,
        )
    ]


def _histograms(ctx: PlotContext, beam) -> list[Figure]:
    pred = beam.prediction
    pr = pred["_pairs"]
    x = pr["m1"] / pr["m2"]
    model = ctx.model("cross-section")
    min_angle = float(model.numeric("min_angle").data[0])
    got = _beam_angles(ctx, beam)
    n = len(got["theta"])
    d = pred["_distance"]
    area = np.pi * coulomb.beam_radius(min_angle, d) ** 2
    edges = beam_bins(min_angle, x)
    fig, (ax, lab, tgt) = ctx.subplots(1, 3, figsize=(14.0, 4.4))
    # CM: dsigma/dOmega per bin = (count / n) area / (2 pi (cos lo - cos hi)), against Rutherford's curve.
    e = edges["cm"]
    counts = np.histogram(got["theta"], e)[0]
    solid = 2 * np.pi * (np.cos(e[:-1]) - np.cos(e[1:]))
    mid = 0.5 * (e[:-1] + e[1:])
    sigma = counts / n * area / solid
    err = np.sqrt(np.maximum(counts, 1)) / n * area / solid
    t = np.linspace(min_angle, np.pi, 400)
    ax.semilogy(t, coulomb.cm_cross_section(t, d), label="C7: (k/4E)^2 / sin^4(theta/2)", **THEORY_STYLE)
    ax.errorbar(mid, sigma, yerr=err, fmt="o", color="C0", ms=4, mec="k", label=f"MuJoCo beam, n = {n} (+-1 sigma)")
    ax.axvline(min_angle, color="0.5", ls=":", lw=0.8, label=f"cut theta_min = {min_angle:g} rad")
    ax.set_xlabel("CM angle theta (rad)")
    ax.set_ylabel("dsigma/dOmega (m^2/sr)")
    ax.set_title(f"CM cross section, p = {measured_value(beam, 'cm-distribution-pvalue'):.2f}", fontsize=9)
    ax.legend(fontsize=8)
    # LAB: counts per bin against n times the C6 probabilities.
    e = edges["projectile"]
    counts = np.histogram(np.minimum(got["psi"], e[-1]), e)[0]
    expected = n * coulomb.lab_angle_probabilities(e, min_angle, x)
    mid = 0.5 * (e[:-1] + e[1:])
    width = e[1] - e[0]
    lab.bar(mid, counts, width=0.9 * width, color="C0", alpha=0.6, label="MuJoCo: projectile")
    lab.step(e, np.append(expected, expected[-1]), where="post", label="C6: n P(bin)", **THEORY_STYLE)
    e = edges["target"]
    counts = np.histogram(got["zeta"], e)[0]
    expected = n * coulomb.lab_angle_probabilities(e, min_angle, x, particle="target")
    tgt.bar(0.5 * (e[:-1] + e[1:]), counts, width=0.9 * (e[1] - e[0]), color="C3", alpha=0.6, label="MuJoCo: target")
    tgt.step(e, np.append(expected, expected[-1]), where="post", label="C6: n P(bin)", **THEORY_STYLE)
    for axis, name, label in ((lab, "projectile", "psi (projectile)"), (tgt, "target", "zeta (target)")):
        axis.set_yscale("log")
        axis.set_xlabel(f"LAB angle {label} (rad)")
        axis.set_ylabel("collisions per bin")
        axis.set_title(
            f"LAB {name}, m1/m2 = {x:.3g}: p = {measured_value(beam, f'{name}-distribution-pvalue'):.2f}", fontsize=9
        )
        axis.legend(fontsize=8)
    return [
        Figure(
            "Rutherford: the Monte Carlo cross section over 1/sin^4(theta/2)",
            f"A uniform beam of {n} collisions over a disc of radius b_max = D cot(theta_min / 2) (the finite-b cut: "
            "Rutherford's total cross section is infinite). Left: dsigma/dOmega from the CM-angle histogram (bins of "
            "equal expected count) against (k/4E)^2 / sin^4(theta/2) (docs/theory.md C7), with Poisson error bars. "
            "Right: "
            "the LAB angles of the projectile and of the target against the C6 cross sections (black and red steps). "
            "Agreement: points within their error bars, the goodness-of-fit p-values in the titles above 1e-3.",
            fig,
        )
    ]


def _orbits(ctx: PlotContext, run) -> Figure:
    pred = run.prediction
    pr = pred["_pairs"]
    traj = run.trajectory
    s = ctx.scenario.split(pr, traj.qpos, traj.qvel)
    x1, x2 = s["x1"][:, 0, :2], s["x2"][:, 0, :2]
    m1, m2 = pr["m1"], pr["m2"]
    mass = m1 + m2
    d = pred["_distance"]
    centre = (m1 * x1 + m2 * x2) / mass
    fig, (cm, lab, drift) = ctx.subplots(1, 3, figsize=(13.0, 4.4))
    # The close passage: |t| < 15 r_min / v around the closest approach.
    t = traj.time - pred["_t0"] - pred["_t_half"]
    rmin = pred["closest-approach"]
    near = np.abs(t) < 15 * rmin / pred["_speed"]
    for ax, a, b, title in (
        (cm, x1 - centre, x2 - centre, "CM frame: hyperbolas with asymptotes"),
        (lab, x1, x2, "LAB frame"),
    ):
        ax.plot(a[near, 0] / d, a[near, 1] / d, color="C1", lw=1.2, label="projectile (m1)")
        ax.plot(b[near, 0] / d, b[near, 1] / d, color="C0", lw=1.2, label="target (m2)")
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("x / D")
        ax.set_ylabel("y / D")
        ax.set_title(title, fontsize=9)
    theta = pred["cm-angle"]
    out = np.array([np.cos(theta), np.sin(theta)])
    for body, frac, color in ((cm, m2 / mass, "C1"), (cm, -m1 / mass, "C0")):
        # The CM-frame asymptotes: the exact orbit's straight lines, r_i' = (m_j / M) r, through its far points.
        r_far, _ = coulomb.relative_orbit(np.array([-1e4, 1e4]) * rmin / pred["_speed"], pred["_b"][0], d, 1.0)
        for sign, rr in zip((-1, 1), r_far, strict=True):
            direction = np.array([1.0, 0.0]) if sign < 0 else out
            p0 = frac * rr[:2] / d
            span = np.linspace(-1e4, 1e4, 2) * abs(frac) * rmin / d
            body.plot(p0[0] + span * direction[0], p0[1] + span * direction[1], color=color, ls=":", lw=0.8)
    cm.set_xlim(-6 * rmin / d, 6 * rmin / d)
    cm.set_ylim(-6 * rmin / d, 6 * rmin / d)
    cm.legend(fontsize=8)
    lab.legend(fontsize=8)
    # C9: the lateral offsets against ln t after the closest approach.
    late = t > 2 * rmin / pred["_speed"]
    out_dir = ctx.scenario.outgoing(pred, traj.qpos[-1], traj.qvel[-1])
    v1 = out_dir["v1"][0]
    h = np.cross(s["x1"][-1, 0] - s["x2"][-1, 0], s["v1"][-1, 0] - s["v2"][-1, 0])
    h_hat = h / np.linalg.norm(h)
    n_lab = np.cross(v1 / np.linalg.norm(v1), h_hat)
    n_cm = np.cross(out_dir["out"][0], h_hat)
    lat_lab = s["x1"][late, 0] @ n_lab
    lat_cm = (s["x1"][late, 0] - s["x2"][late, 0]) @ n_cm
    tt = t[late]
    c = pred["lab-log-drift"]
    drift.semilogx(tt, (lat_lab - lat_lab[-1]) / d, color="C1", lw=1.4, label="MuJoCo: projectile, LAB")
    drift.semilogx(
        tt,
        c * np.log(tt / tt[-1]) / d,
        label=f"C9: C ln t, C = -(m2/M) D sin(theta - psi)\n= {c / d:.4f} D",
        **THEORY_STYLE,
    )
    drift.semilogx(tt, (lat_cm - lat_cm[-1]) / d, color="C2", lw=1.4, label="MuJoCo: relative coordinate, CM frame")
    drift.set_xlabel("time after the closest approach (s)")
    drift.set_ylabel("lateral offset - its final value (D)")
    drift.set_title(
        f"C9: fitted C = {measured_value(run, 'lab-log-drift') / d:.4f} D (LAB), "
        f"{measured_value(run, 'cm-log-drift') / d:.1e} D (CM)",
        fontsize=9,
    )
    drift.legend(fontsize=8)
    return Figure(
        "Rutherford: the orbit in the CM and LAB frames (no LAB asymptote)",
        "One collision (lab-orbit case, m1 = m2, b = D). Left: in the CM frame both bodies follow hyperbolas, "
        "mass-scaled copies with straight asymptotes (dotted). Middle: the LAB paths near the collision. Right: the "
        "lateral offset of the projectile's LAB path from its asymptotic direction keeps growing as C ln t "
        "(docs/theory.md C9; black: the predicted slope), because the relative coordinate's Coulomb lag D ln t "
        "points along the CM direction, not the LAB velocity; the CM-frame offset (green) settles. Agreement: the "
        "orange curve parallel to the black line on the log axis, the green one flat.",
        fig,
    )
