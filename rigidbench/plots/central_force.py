"""Figures of the central power-law forces (docs/theory.md K2, K5, K6): the near-circular orbits' apsides against
pi / sqrt(3 - n), the unstable circular orbit's offset against cosh(lambda t), and the perturbed Kepler orbit's
pericentre advance against 2 pi eps per orbit, with the Runge-Lenz vector of the pure inverse square. Simulation
(coloured) over theory (black, `rigidbench.analytic.central_force`). No extra simulations: the figures reuse the
cases' runs.
"""

from __future__ import annotations

import math

import numpy as np

from rigidbench import signals
from rigidbench.analytic import central_force as cf
from rigidbench.plots import THEORY_STYLE, Figure, PlotContext, measured_value, plot, settings_text, thin, try_run

NEAR_CIRCULAR = ("constant-force", "log-potential", "steep")
SIM = {"lw": 0, "marker": "o", "ms": 2.5, "alpha": 0.8}


def _polar(run) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Time, positions (n, 3), velocities (n, 3), distance and unwrapped azimuth of a run."""
    traj = run.trajectory
    t = np.asarray(traj.time)
    r = np.column_stack([traj.qpos[:, :2], np.zeros(len(t))])
    v = np.column_stack([traj.qvel[:, :2], np.zeros(len(t))])
    return t, r, v, np.hypot(r[:, 0], r[:, 1]), np.unwrap(np.arctan2(r[:, 1], r[:, 0]))


def _apsides(t, r, v, phase) -> tuple[np.ndarray, np.ndarray]:
    """Times and azimuths (rad, unwrapped) of the apsides, r.v = 0 (cubic-interpolated), the start included (the
    scenario's `measure`)."""
    rv = np.einsum("ij,ij->i", r, v)
    events = np.sort(np.concatenate([[0.0], signals.crossings(t, rv, +1), signals.crossings(t, rv, -1)]))
    return events, signals.interpolate(t, phase, events)


def _near_circular(ctx: PlotContext) -> Figure | None:
    runs = [(c, run) for c in NEAR_CIRCULAR if (run := try_run(ctx, c)) is not None]
    if not runs:
        return None
    fig, axes = ctx.subplots(2, len(runs), figsize=(4.0 * len(runs), 7.6), squeeze=False, height_ratios=(1.2, 1))
    for k, (case, run) in enumerate(runs):
        path, radial = axes[0, k], axes[1, k]
        pred = run.prediction
        t, r, v, dist, phase = _polar(run)
        n, e = pred["_law"].n[0], pred["_apsides"].eccentricity
        first = cf.apsidal_angle_first_order(n)
        r0 = float(np.linalg.norm(pred["_r0"]))
        ref, _ = cf.trajectory(pred["_mu"], pred["_law"], pred["_r0"], pred["_v0"], t)
        every = thin(len(t), 250)
        color = f"C{k}"
        path.plot(ref[:, 0], ref[:, 1], **THEORY_STYLE, label="theory (equations of motion)")
        path.plot(r[every, 0], r[every, 1], color=color, **SIM, label="MuJoCo")
        events, angles = _apsides(t, r, v, phase)
        reach = 1.15 * float(dist.max())
        for j, a in enumerate(first * np.arange(len(events))):
            path.plot(
                [0, reach * math.cos(a)],
                [0, reach * math.sin(a)],
                color="k",
                lw=0.7,
                ls="--",
                zorder=1,
                label="predicted apsides j pi / sqrt(3 - n)" if j == 0 else None,
            )
        d_ev = signals.interpolate(t, dist, events)
        peri = np.arange(len(events)) % 2 == 0
        for mask, marker, label in ((peri, "v", "measured pericentres"), (~peri, "^", "measured apocentres")):
            path.plot(
                d_ev[mask] * np.cos(angles[mask]),
                d_ev[mask] * np.sin(angles[mask]),
                marker,
                color="C3",
                ms=7,
                mec="k",
                lw=0,
                label=label,
            )
        path.plot([0], [0], "+", color="k", ms=10, mew=1.5)
        path.set_aspect("equal", adjustable="datalim")
        path.set_xlabel("x (m)")
        path.set_ylabel("y (m)")
        path.set_title(f"{case}: F = -k / r^{n:g}, e = {e:.3f}", fontsize=9)
        deg = np.degrees(phase)
        radial.plot(np.degrees(phase), (np.hypot(ref[:, 0], ref[:, 1]) - r0) / r0, **THEORY_STYLE, label="theory")
        radial.plot(deg[every], (dist[every] - r0) / r0, color=color, **SIM, label="MuJoCo")
        for j in range(len(events)):
            radial.axvline(math.degrees(j * first), color="k", lw=0.7, ls="--")
        radial.plot(
            np.degrees(angles),
            (d_ev - r0) / r0,
            "o",
            color="C3",
            ms=6,
            mfc="none",
            mew=1.3,
            label="measured apsides (r.v = 0)",
        )
        measured = np.diff(angles)
        worst = measured[np.argmax(np.abs(measured - first))]
        radial.set_title(
            f"pi / sqrt(3 - n) = {math.degrees(first):.3f} deg; measured {math.degrees(worst):.3f} deg\n"
            f"(exact Binet {math.degrees(pred['apsidal-angle']):.3f} deg)",
            fontsize=8.5,
        )
        radial.set_xlabel("azimuth phi (deg)")
        radial.set_ylabel("(r - r0) / r0")
        radial.set_ylim(top=1.15 * float(np.max((dist - r0) / r0)))
    handles = [h for h, label in zip(*axes[0, 0].get_legend_handles_labels(), strict=True) if label != "MuJoCo"]
    labels = [label for label in axes[0, 0].get_legend_handles_labels()[1] if label != "MuJoCo"]
    handles.insert(1, axes[0, 0].plot([], [], color="0.4", **SIM)[0])
    labels.insert(1, "MuJoCo (one colour per case)")
    handles.append(axes[1, 0].get_legend_handles_labels()[0][-1])
    labels.append("measured apsides (r.v = 0), on the radial offset")
    fig.legend(handles, labels, loc="outside lower center", ncols=3, fontsize=7.5)
    fig.suptitle(f"Near-circular orbits, the apsidal angle pi / sqrt(3 - n) ({settings_text(runs[0][1])})", fontsize=10)
    return Figure(
        "Central force: near-circular orbits and their apsidal angle",
        "Three power laws F = -k / r^n (n = 0, 1, 2.5), each started at its pericentre a few per cent above the "
        "circular speed. Top: the orbit in the plane (MuJoCo, coloured dots, over the integrated equations of "
        "motion, black), the measured apsides (r.v = 0; triangles) and the rays at the predicted apsidal angles "
        "j pi / sqrt(3 - n) (dashed, docs/theory.md K5): the orbit does not close, and agreement is every measured "
        "apsis on its ray. Bottom: the radial offset (r - r0) / r0 against the azimuth, its extrema falling on the "
        "dashed lines; the titles give the closed form, the measured angle farthest from it and the exact "
        "(Binet-integrated) value, which differ by the closed form's own second-order term in e.",
        fig,
    )


def _unstable(ctx: PlotContext) -> Figure | None:
    run = try_run(ctx, "unstable")
    if run is None:
        return None
    pred = run.prediction
    t, _, _, dist, _ = _polar(run)
    r_star, offset, rate = pred["_r_star"], pred["_offset"], pred["growth-rate"]
    fig, ax = ctx.subplots()
    sim = np.abs(dist - r_star) / r_star
    every = thin(len(t), 400)
    ax.semilogy(t[every], np.maximum(sim[every], 1e-17), color="C0", **SIM, label="MuJoCo |r - r*| / r*")
    ax.semilogy(t, abs(offset) / r_star * np.cosh(rate * t), **THEORY_STYLE, label="theory dr(0) cosh(lambda t) (K5)")
    ax.semilogy(
        t, abs(offset) / r_star * 0.5 * np.exp(rate * t), color="0.5", ls="--", lw=1.0, label="dr(0) exp(lambda t) / 2"
    )
    measured = measured_value(run, "growth-rate")
    t100 = math.acosh(100.0) / measured if measured > 0 else math.nan
    ax.axhline(100 * abs(offset) / r_star, color="C3", lw=0.8, ls=":", label="100 dr(0): where the rate is read")
    if math.isfinite(t100):
        ax.axvline(t100, color="C3", lw=0.8, ls=":")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("|r - r*| / r*  (r* the circular radius)")
    n = pred["_law"].n[0]
    ax.set_title(
        f"unstable: F = -k / r^{n:g}, lambda = {rate:.6g} 1/s predicted, {measured:.8g} measured "
        f"(relative error {abs(measured - rate) / rate:.1e})\n{settings_text(run)}",
        fontsize=9,
    )
    ax.legend(fontsize=7.5, loc="upper left")
    return Figure(
        "Central force: an unstable circular orbit (n = 4)",
        "In F = -k / r^4 circular orbits are unstable (docs/theory.md K5): a start 1e-8 above the circular speed "
        "puts the planet dr(0) off the circular radius r*, and the offset grows as dr(0) cosh(lambda t), "
        "lambda = sqrt((n - 3) k / (mu r*^(n + 1))), predicted from the compiled model. On the log axis the "
        "theory becomes a straight line of slope lambda (the dashed exp(lambda t) / 2 it joins). Agreement: the "
        "simulated offset (dots) lies on the black curve up to the hundredfold growth where the growth-rate check "
        "reads it (dotted) and beyond, until the offset stops being small.",
        fig,
    )


def _perihelion(ctx: PlotContext) -> Figure | None:
    peri_run, kepler_run = try_run(ctx, "perihelion"), try_run(ctx, "kepler")
    if peri_run is None and kepler_run is None:
        return None
    fig, (adv, lenz) = ctx.subplots(1, 2, figsize=(10.0, 4.3))
    if peri_run is not None:
        pred = peri_run.prediction
        t, r, v, _, phase = _polar(peri_run)
        period = 2 * pred["_apsides"].time
        mu, law, ell = pred["_mu"], pred["_law"], pred["_l"]
        eps = mu * mu * law.k[0] * law.k[1] / ell**4
        rv = np.einsum("ij,ij->i", r, v)
        peri = signals.crossings(t, rv, +1)
        swept = signals.interpolate(t, phase, peri) - phase[0]
        orbit = np.arange(1, len(peri) + 1)
        advance = swept - 2 * math.pi * orbit
        span = np.linspace(0.0, orbit[-1] + 0.25 if orbit.size else 1.0, 50)
        adv.plot(span, 2 * math.pi * eps * span * 1e3, **THEORY_STYLE, label="theory 2 pi eps per orbit (K6)")
        exact = 2 * pred["apsidal-angle"] - 2 * math.pi
        adv.plot(span, exact * span * 1e3, color="0.5", ls="--", lw=1.0, label="exact (Binet) per orbit")
        # The Runge-Lenz vector's direction: at each pericentre it points at the planet (A is along r there).
        big_a = cf.runge_lenz(mu, law.k[0], r, v)
        angle = np.unwrap(np.arctan2(big_a[:, 1], big_a[:, 0])) - math.atan2(big_a[0, 1], big_a[0, 0])
        every = thin(len(t), 600)
        adv.plot(
            t[every] / period, angle[every] * 1e3, color="C1", lw=0.8, alpha=0.7, label="Runge-Lenz direction (MuJoCo)"
        )
        adv.plot(orbit, advance * 1e3, "o", color="C3", ms=7, mec="k", label="pericentre azimuth - 2 pi j (MuJoCo)")
        adv.set_xlabel("t / T (radial periods)")
        adv.set_ylabel("pericentre advance (mrad)")
        measured = advance[-1] / orbit[-1] if orbit.size else math.nan
        adv.set_title(
            f"perihelion: eps = {eps:.3g}, 2 pi eps = {2e3 * math.pi * eps:.4f} mrad/orbit,\n"
            f"measured {1e3 * measured:.4f}, exact {1e3 * exact:.4f} ({settings_text(peri_run)})",
            fontsize=8.5,
        )
        adv.legend(fontsize=7, loc="upper left")
    if kepler_run is not None:
        pred = kepler_run.prediction
        t, r, v, _, _ = _polar(kepler_run)
        big_a = cf.runge_lenz(pred["_mu"], pred["_law"].k[0], r, v)
        drift = np.linalg.norm(big_a - big_a[0], axis=1) / (pred["_mu"] * pred["_law"].k[0])
        every = thin(len(t), 2000)
        period = 2 * pred["_apsides"].time
        lenz.semilogy(
            t[every] / period,
            np.maximum(drift[every], 1e-17),
            color="C0",
            lw=0.8,
            label="MuJoCo |A(t) - A(0)| / (mu k)",
        )
        tolerance = ctx.scenario.check("runge-lenz-drift").tolerance
        lenz.axhline(tolerance, color="k", ls="--", lw=0.8, label=f"runge-lenz-drift tolerance {tolerance:g}")
        lenz.set_xlabel("t / T (periods)")
        lenz.set_ylabel("|A(t) - A(0)| / (mu k)")
        lenz.set_title(f"kepler (e = {pred['_apsides'].eccentricity:.2f}): theory A constant (K2)", fontsize=8.5)
        lenz.legend(fontsize=7, loc="lower right")
    return Figure(
        "Central force: the pericentre advance and the Runge-Lenz vector",
        "Left: the inverse square plus a small -k4 / r^4 (eps = mu^2 k k4 / l^4 = 1e-3, e = 0.44). Red: the "
        "simulated pericentre's azimuth after j orbits minus 2 pi j; black: the first-order advance 2 pi eps per "
        "orbit (docs/theory.md K6, the general-relativistic 6 pi GM / (c^2 a (1 - e^2))); grey dashed: the exact "
        "advance from Binet's equation. Agreement: the points on the grey line and within the second-order term "
        "2 pi eps^2 (5/2 + 5 e^2 / 12) (0.26 % here, invisible) of the black one. Orange: the direction of the "
        "Runge-Lenz vector A = p x L - mu k r_hat, which is no longer constant: it "
        "advances along the same line, swinging about it within each orbit and meets it at every apsis "
        "(where A lies along r). Right: for the pure inverse square A is constant (K2); MuJoCo's drift of it, in "
        "units of mu k, stays "
        "under the check's tolerance (dashed), growing with RK4's orientation error.",
        fig,
    )


@plot("central-force")
def central_force(ctx: PlotContext) -> list[Figure]:
    return [f for f in (_near_circular(ctx), _unstable(ctx), _perihelion(ctx)) if f is not None]
