"""Figures of the tops family: the heavy top's theta(t) and axis path, the asymmetric top's flip and polhodes,
the symmetric top's body cone. Simulation (markers or thin lines) over theory (the closed forms of
`rigidbench.analytic.tops`), with the residual underneath where the two would otherwise be indistinguishable.
"""

from __future__ import annotations

import numpy as np

from rigidbench import signals
from rigidbench.analytic import tops
from rigidbench.envs.rotor import free_body_motion
from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, plot, settings_text, thin

SIM = {"color": "C3", "lw": 0, "marker": "o", "ms": 2.5, "alpha": 0.8}


@plot("heavy-top")
def heavy_top(ctx: PlotContext) -> list[Figure]:
    figures = []
    for case in ("nutation", "looping"):
        run = ctx.run(case)
        if run.trajectory is None or run.diverged_at is not None:
            continue
        model = ctx.model(case)
        traj, top = run.trajectory, run.prediction["_theory"]
        m = ctx.scenario.motion(model, traj.time, traj.qpos, traj.qvel)
        e3 = m.e3_W
        theta = np.arctan2(np.hypot(e3[:, 0], e3[:, 1]), e3[:, 2])
        theory = np.array([top.theta_at_w(w) for w in top.w(traj.time)])
        u_dot = np.cross(m.omega_W, e3)[:, 2]
        t_max, th_max = signals.extrema(traj.time, theta, -u_dot, "max")
        t_min, th_min = signals.extrema(traj.time, theta, -u_dot, "min")
        fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1), figsize=(8, 5))
        k = thin(len(traj.time))
        ax.plot(traj.time, theory, label="theory: u = cos(theta) from the elliptic solution (T3)", **THEORY_STYLE)
        ax.plot(traj.time[k], theta[k], label=f"MuJoCo ({settings_text(run)})", **SIM)
        for value, name in ((top.theta_min, "theta_min = arccos u2"), (top.theta_max, "theta_max = arccos u1")):
            ax.axhline(value, color="0.5", ls="--", lw=0.8)
            ax.text(traj.time[-1], value, f" {name}", va="center", fontsize=8, color="0.3")
        ax.plot(t_max, th_max, "v", color="C0", ms=7, label="measured turning points")
        ax.plot(t_min, th_min, "^", color="C0", ms=7)
        ax.set_ylabel("theta (rad) from the upward vertical")
        ax.legend(fontsize=8, loc="lower right")
        ax.set_title(f"heavy-top:{case}: tilt theta(t) between the turning points of T2")
        res.plot(traj.time, theta - theory, color="C3", lw=0.8)
        res.set_ylabel("sim - theory (rad)")
        res.set_xlabel("t (s)")
        res.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
        figures.append(
            Figure(
                f"Heavy top, {case}: theta(t) and its turning points",
                f"Tilt of the symmetry axis from the upward vertical: MuJoCo (red dots) over the closed form of "
                f"docs/theory.md T3 (black), with the turning points theta_min and theta_max of T2 (dashed) and the "
                f"measured extrema (blue triangles). Lower panel: the difference, at the level of the "
                f"integration error ({settings_text(run)}).",
                fig,
            )
        )
    paths = [(c, ctx.run(c)) for c in ("nutation", "looping", "sleeping")]
    fig, axes = ctx.subplots(1, 3, figsize=(10, 3.6))
    for ax, (case, run) in zip(axes, paths, strict=True):
        if run.diverged_at is not None:
            continue
        traj, top = run.trajectory, run.prediction["_theory"]
        m = ctx.scenario.motion(ctx.model(case), traj.time, traj.qpos, traj.qvel)
        e3 = m.e3_W
        ax.plot(e3[:, 0], e3[:, 1], color="C3", lw=0.8, label="MuJoCo: axis e3 seen from above")
        ring = np.linspace(0, 2 * np.pi, 361)
        for value in (top.theta_min, top.theta_max):
            ax.plot(np.sin(value) * np.cos(ring), np.sin(value) * np.sin(ring), "k--", lw=0.7)
        ax.set_aspect("equal")
        ax.set_title(case, fontsize=10)
        ax.set_xlabel("e3_x")
        ax.set_ylabel("e3_y")
        lim = 1.08 * np.sin(max(top.theta_max, 1e-3))
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.locator_params(nbins=4)
    figures.append(
        Figure(
            "Heavy top: path of the symmetry axis",
            "Horizontal projection of the unit symmetry axis e3 (MuJoCo, red) between the circles sin(theta_min) "
            "and sin(theta_max) of the theory (dashed): cusps when the top is released at rest (nutation), loops "
            "when the initial precession opposes the gyroscopic one (looping), and the same cusps in a narrow band "
            "near the vertical for the sleeping top (note the axis scale).",
            fig,
        )
    )
    return figures


@plot("free-asymmetric-top")
def free_asymmetric_top(ctx: PlotContext) -> list[Figure]:
    figures = []
    run = ctx.run("intermediate-axis")
    model = ctx.model("intermediate-axis")
    if run.diverged_at is None:
        traj, top = run.trajectory, run.prediction["_theory"]
        m = free_body_motion(model, traj.time, traj.qpos, traj.qvel)
        theory = top.omega_body(traj.time)
        fig, (ax, res) = ctx.subplots(2, 1, sharex=True, height_ratios=(3, 1), figsize=(8, 5))
        k = thin(len(traj.time), 150)
        for i in range(3):
            ax.plot(traj.time, theory[:, i], color=f"C{i}", lw=1.0)
            ax.plot(traj.time[k], m.omega_B[k, i], "o", color=f"C{i}", ms=2.2, label=f"omega_{i + 1} (MuJoCo)")
        flips = signals.crossings(traj.time, m.omega_B[:, 1])
        for t in flips:
            ax.axvline(t, color="0.6", lw=0.7, ls=":")
        ax.set_ylabel("omega, body frame (rad/s)")
        ax.set_title(f"free-asymmetric-top:intermediate-axis: flips every 2K/s = {top.reversal_time:.4g} s")
        ax.set_ylim(top=1.35 * float(np.abs(m.omega_B).max()))
        ax.legend(fontsize=8, loc="upper center", ncols=3, frameon=False)
        err = np.linalg.norm(m.omega_B - theory, axis=1) / np.linalg.norm(m.omega_B[0])
        res.semilogy(traj.time, np.maximum(err, 1e-17), color="C3", lw=0.8)
        res.set_ylabel("|sim - theory| / |omega|")
        res.set_xlabel("t (s)")
        figures.append(
            Figure(
                "Asymmetric top: body-frame omega(t) through the flips",
                f"Spin started 0.02 rad off the intermediate axis (I = {', '.join(f'{x:g}' for x in top.inertia)} "
                f"kg m^2): omega_2 reverses every 2K(k)/s (dotted lines: measured sign changes of omega_2) while "
                f"omega_1 and omega_3 pulse. Dots: MuJoCo ({settings_text(run)}); lines: the Jacobi elliptic "
                "solution (docs/theory.md A2). Lower panel: the relative difference.",
                fig,
            )
        )
    figures.append(_polhodes(ctx, model))
    return figures


def _polhodes(ctx: PlotContext, model) -> Figure:
    """Polhodes on the unit angular-momentum sphere: the theory's family and the simulated cases."""
    inertia = np.array(model.body_inertia[1])
    fig = ctx.subplots(figsize=(6.4, 6.0), subplot_kw={"projection": "3d"})[0]
    ax = fig.axes[0]
    u, v = np.mgrid[0 : 2 * np.pi : 40j, 0 : np.pi : 20j]
    x, y, z = np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)
    ax.plot_wireframe(x, y, z, color="0.9", lw=0.3, rstride=2, cstride=2)
    # Theory: the polhodes L_B(t)/|L| of a family of motions with |L| = 1 (closed form, one period each).
    for axis, angles in ((2, np.linspace(0.15, 1.35, 5)), (0, np.linspace(0.15, 1.25, 4))):
        for a in angles:
            for sign in (1, -1):
                L = np.zeros(3)
                L[axis] = sign * np.cos(a)
                L[1] = np.sin(a)
                top = tops.asymmetric_top(tuple(inertia), L / inertia)
                t = np.linspace(0, top.period, 400)
                Lb = top.omega_body(t) * inertia
                Lb /= np.linalg.norm(Lb, axis=1, keepdims=True)
                ax.plot(*Lb.T, color="k", lw=0.6)
    # The separatrix: L^2 = 2 E I2 on the sphere is the pair of great circles
    # L1 sqrt(1/I1 - 1/I2) = +-L3 sqrt(1/I2 - 1/I3) through the intermediate axis.
    c1, c3 = np.sqrt(1 / inertia[0] - 1 / inertia[1]), np.sqrt(1 / inertia[1] - 1 / inertia[2])
    s = np.linspace(0, 2 * np.pi, 400)
    for sign in (1, -1):
        n = np.array([c1, 0.0, -sign * c3])
        n /= np.linalg.norm(n)
        a = np.array([0.0, 1.0, 0.0])
        b = np.cross(n, a)
        circle = np.outer(np.cos(s), a) + np.outer(np.sin(s), b)
        ax.plot(*circle.T, color="C1", lw=1.0, ls="--")
    for i, case in enumerate(c.name for c in ctx.scenario.cases):
        run = ctx.run(case)
        if run.diverged_at is not None:
            continue
        traj = run.trajectory
        m = free_body_motion(model, traj.time, traj.qpos, traj.qvel)
        Lb = m.L_B / np.linalg.norm(m.L_B, axis=1, keepdims=True)
        k = thin(len(traj.time), 300)
        ax.plot(*Lb[k].T, "-o", lw=2.0, ms=2.0, color=f"C{i + 2}", label=f"MuJoCo: {case}", zorder=5)
    ax.set_xlabel("L1/|L|")
    ax.set_ylabel("L2/|L|")
    ax.set_zlabel("L3/|L|")
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=22, azim=35)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title("Polhodes on the angular-momentum sphere")
    return Figure(
        "Asymmetric top: polhodes on the angular-momentum sphere",
        "Body-frame angular momentum L_B/|L| on the unit sphere. Black: closed-form polhodes (intersections with "
        "the energy ellipsoid) circling the largest (L3) and smallest (L1) axes; orange dashed: the separatrix "
        "L^2 = 2 E I2, two great circles through the intermediate axis. Dots: MuJoCo's three cases lying on their "
        "polhodes; the intermediate-axis case runs along the separatrix from one pole of L2 to the other.",
        fig,
    )


@plot("free-symmetric-top")
def free_symmetric_top(ctx: PlotContext) -> list[Figure]:
    fig, axes = ctx.subplots(1, 2, figsize=(9, 4.2))
    for ax, case in zip(axes, ("prolate", "oblate"), strict=True):
        run = ctx.run(case)
        if run.diverged_at is not None:
            continue
        traj, top = run.trajectory, run.prediction["_theory"]
        m = free_body_motion(ctx.model(case), traj.time, traj.qpos, traj.qvel)
        theory = top.omega_body(traj.time)
        ax.plot(theory[:, 0], theory[:, 1], color="k", lw=1.0, label="theory: circle at Omega_b (S1)")
        # One turn of the body cone, sampled 60 times (a longer window aliases with the sampling).
        turn = int(np.searchsorted(traj.time, 2 * np.pi / abs(top.body_rate)))
        k = slice(0, turn, max(1, turn // 60))
        ax.plot(m.omega_B[k, 0], m.omega_B[k, 1], "o", color="C3", ms=4, label="MuJoCo (one turn)")
        ax.annotate(
            "",
            xy=m.omega_B[max(1, turn // 12), :2],
            xytext=m.omega_B[0, :2],
            arrowprops={"arrowstyle": "-|>", "color": "C0", "lw": 2.0, "mutation_scale": 18},
        )
        ax.set_aspect("equal")
        ax.set_xlabel("omega_1 (rad/s)")
        ax.set_ylabel("omega_2 (rad/s)")
        ax.set_title(f"{case}: Omega_b = {top.body_rate:+.4g} rad/s", fontsize=10)
        ax.legend(fontsize=8, loc="lower right")
    return [
        Figure(
            "Symmetric top: the body cone",
            "Transverse body-frame angular velocity (omega_1, omega_2): it circles the symmetry axis at "
            "Omega_b = (I3 - I1) omega_3 / I1 (Wilcox eq. 11.42), clockwise for the prolate top (Omega_b < 0) "
            "and counter-clockwise for the oblate one (arrow: direction of motion). MuJoCo's dots lie on the "
            "theory's circle.",
            fig,
        )
    ]
