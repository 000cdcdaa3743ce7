"""The physics layer of `rigidbench.envs.rutherford`: where the pairs live in the model, how a pair is placed on its
hyperbola, how a beam of pairs is stepped in blocks, and what is read from the final states (outgoing asymptotes,
closest approaches, the LAB orbit's drift, the beam's distributions).

Split from the scenario file by concern (issue 34), as dm_control splits a domain's Physics from its Task: the
scenario (`Rutherford`) declares parameters, cases, checks and domains and predicts from the closed forms
(`rigidbench.analytic.coulomb`); `RutherfordPhysics` holds the model conventions and the measurement.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from rigidbench import forces, signals
from rigidbench.analytic import coulomb
from rigidbench.contract import Scenario
from rigidbench.envs.cross_section import bin_counts, chi_square_pvalue
from rigidbench.simulate import final_states, get_state, simulate

# 4.0); relative energy error 3.1e-8, 9.6e-10, 3.0e-11.
STEPS_PER_PASSAGE = 20
# Error budgets at STEPS_PER_PASSAGE, 9x the largest measured (48 census draws over every case's ranges: angles <=
# 1.1e-8 rad, 0.11 of the budget; energies <= 9.6e-10, 0.096 of it).
ANGLE_ERROR = 1e-7
ENERGY_ERROR = 1e-8
# The beam's goodness-of-fit tests: bins, significance (as `cross-section`).
NBINS = 20
ALPHA = 1e-3
# A beam's start and end: the head-on pair (closest of all, r_min = 2 D) at `separation` r_min.
BEAM_SINGLE = 1  # n = 1: one collision (plus a probe pair at b0 when m1 > m2)
# Pairs in a beam's model: a beam of n > BLOCK collisions runs in blocks of BLOCK pairs, each drawn from its own
# Generator (seed, block) and stepped on the same compiled model. MuJoCo 4.0 compiles a model of N free bodies in a
# time that grows as N^2 (0.23 s at 500 pairs, 1.1 s at 1000, measured), so one model of 1e5 pairs is out of reach.
BLOCK = 500
MIN_SPEED_FRACTION = 1e-3  # the projectile's LAB speed / u below which its LAB angle is set by the integration error


class RutherfordPhysics(Scenario):
    """The model conventions and measurements `Rutherford` builds on (module docstring). Not a scenario of its own
    (it has no slug)."""

    @staticmethod
    def pairs(model: mujoco.MjModel) -> dict[str, Any]:
        """Per pair: the qpos and qvel addresses of target (first) and projectile (second), masses and k."""
        law = forces.inverse_square(model)

        def adr(bodies, table):
            return np.array([int(table[model.body_jntadr[b]]) for b in bodies])

        return {
            "target_q": adr(law.first, model.jnt_qposadr),
            "projectile_q": adr(law.second, model.jnt_qposadr),
            "target_v": adr(law.first, model.jnt_dofadr),
            "projectile_v": adr(law.second, model.jnt_dofadr),
            "m1": float(model.body_mass[law.second[0]]),
            "m2": float(model.body_mass[law.first[0]]),
            "k": float(law.k[0]),
            "count": len(law.first),
        }

    @staticmethod
    def split(pairs: Mapping[str, Any], qpos: np.ndarray, qvel: np.ndarray) -> dict[str, np.ndarray]:
        """Positions and velocities (world frame) of every pair from state rows: x1, v1 (projectile), x2, v2
        (target), each shape (..., npair, 3)."""
        q3 = np.arange(3)
        return {
            "x1": qpos[..., pairs["projectile_q"][:, None] + q3],
            "x2": qpos[..., pairs["target_q"][:, None] + q3],
            "v1": qvel[..., pairs["projectile_v"][:, None] + q3],
            "v2": qvel[..., pairs["target_v"][:, None] + q3],
        }

    @staticmethod
    def is_beam(model: mujoco.MjModel) -> bool:
        """Whether the model is a beam's (more pairs than a collision and its probe). Not read from the ``samples``
        numeric, which the ``thorough`` profile raises in every case."""
        return RutherfordPhysics.pairs(model)["count"] > 2

    def _impacts(self, model: mujoco.MjModel, distance: float, block: int) -> tuple[np.ndarray, np.ndarray]:
        """Impact parameters (m) and azimuths (rad) of the model's pairs: block `block` of the beam, drawn from
        default_rng(seed) for block 0 and default_rng([seed, block]) after it; or the single collision's b (and the
        probe's b0)."""
        pr = self.pairs(model)
        count = pr["count"]
        if self.is_beam(model):
            seed = int(model.numeric("seed").data[0])
            rng = np.random.default_rng(seed if block == 0 else [seed, block])
            radius = coulomb.beam_radius(float(model.numeric("min_angle").data[0]), distance)
            b = radius * np.sqrt(rng.random(count))  # uniform over the disc
            return b, 2 * np.pi * rng.random(count)
        b = [float(model.numeric("b").data[0])]
        if count == 2:
            b.append(float(coulomb.impact_parameter(np.arccos(-pr["m2"] / pr["m1"]), distance)))
        return np.array(b), np.zeros(len(b))

    def place(self, model: mujoco.MjModel, data: mujoco.MjData, block: int) -> None:
        """Put every pair of `data` on its exact incoming orbit (`coulomb.relative_orbit`), from the compiled model's
        masses, k, speed and separation; a beam's impact points are block `block`'s."""
        pr = self.pairs(model)
        m1, m2, k = pr["m1"], pr["m2"], pr["k"]
        mass = m1 + m2
        u = float(model.numeric("speed").data[0])
        d = coulomb.distance_scale(k, m1 * m2 / mass, u)
        b, azimuth = self._impacts(model, d, block)
        # Every pair passes its closest approach at the same time, t_half after the start: the time the pair that
        # comes closest (a beam's head-on one) takes from `separation` r_min to r_min.
        b_close = 0.0 if self.is_beam(model) else float(b[0])
        rmin = float(coulomb.closest_approach(b_close, d))
        t_half = coulomb.time_at_separation(float(model.numeric("separation").data[0]) * rmin, b_close, d, u)
        data.qpos[:] = model.qpos0
        data.qvel[:] = 0.0
        x1, v1, x2, v2 = coulomb.lab_pair_states(-t_half, b, azimuth, (m1, m2), d, u)
        q3 = np.arange(3)
        data.qpos[pr["projectile_q"][:, None] + q3] = x1
        data.qpos[pr["target_q"][:, None] + q3] = x2
        data.qvel[pr["projectile_v"][:, None] + q3] = v1
        data.qvel[pr["target_v"][:, None] + q3] = v2

    @staticmethod
    def _drift_times(t_half: float, timestep: float) -> np.ndarray | None:
        """Times after the closest approach (s) of the C9 fit: the samples over the last 95 % of the run's second
        half (t from t_half / 20 to t_half); None for a run too short to have them."""
        return None if t_half < 40 * timestep else np.linspace(t_half / 20, t_half, 2000)

    def simulate(
        self, model: mujoco.MjModel, data: mujoco.MjData, duration: float, *, control: np.ndarray | None = None
    ):
        if not self.is_beam(model):
            return simulate(model, data, duration, control=control)
        nstep = round(duration / model.opt.timestep)
        count = self.pairs(model)["count"]
        n = int(model.numeric("samples").data[0])
        blocks = []
        for j in range(-(-n // count)):
            if j == 0:
                start = data  # the state the prediction was made from
            else:
                start = mujoco.MjData(model)
                self.place(model, start, j)
                mujoco.mj_forward(model, start)
            run = _march(model, start, nstep)
            blocks.append((run, min(count, n - j * count)))
            if run.diverged_at is not None:
                break
        first = blocks[0][0]
        bad = next((r.diverged_at for r, _ in blocks if r.diverged_at is not None), None)
        return Beam(first.time, first.qpos, first.qvel, bad, tuple(blocks))

    def outgoing(
        self, prediction: Mapping[str, Any], qpos: np.ndarray, qvel: np.ndarray, incoming: np.ndarray | None = None
    ) -> dict[str, np.ndarray]:
        """Per pair, from a state row (any time after the start): the CM angle theta between the asymptotes (the
        outgoing one read from the state's Runge-Lenz vector; the incoming one `incoming`, by default the
        prediction's, from the initial state), the LAB asymptotic velocities v1, v2 and their angles psi, zeta from
        the beam (+x), the outgoing direction, and the invariants (`_invariants`)."""
        pr = prediction["_pairs"]
        kappa = prediction["_kappa"]
        m1, m2 = pr["m1"], pr["m2"]
        inv = _invariants(self.split(pr, qpos, qvel), m1, m2, kappa)
        out_dir = coulomb.outgoing_direction(inv["r"], inv["rdot"], kappa)
        # LAB asymptotic velocities: the CM velocity and the asymptotic relative velocity (speed from the energy).
        cm_velocity = inv["momentum"] / (m1 + m2)
        rel = inv["speed"][:, None] * out_dir
        v1 = cm_velocity + (m2 / (m1 + m2)) * rel
        v2 = cm_velocity - (m1 / (m1 + m2)) * rel
        beam_axis = np.array([1.0, 0.0, 0.0])
        return {
            "theta": _angle(out_dir, prediction["_incoming"] if incoming is None else incoming),
            "psi": _angle(v1, beam_axis),
            "zeta": _angle(v2, beam_axis),
            "v1": v1,
            "v2": v2,
            "out": out_dir,
            "invariants": inv,
        }

    def _beam_result(self, model: mujoco.MjModel, traj: Beam, prediction: Mapping[str, Any]) -> dict[str, float]:
        """Every block of the beam: each pair's deflection against C7 from its own initial state, energy and momentum,
        and the goodness-of-fit tests over all the collisions."""
        pr, kappa = prediction["_pairs"], prediction["_kappa"]
        parts = {"theta": [], "psi": [], "zeta": [], "error": [], "energy": [], "momentum": []}
        for run, count in traj.blocks:
            inv0 = _invariants(self.split(pr, run.qpos[0], run.qvel[0]), pr["m1"], pr["m2"], kappa)
            incoming = coulomb.incoming_direction(inv0["r"], inv0["rdot"], kappa)
            out = self.outgoing(prediction, run.qpos[-1], run.qvel[-1], incoming)
            inv = out["invariants"]
            expected = coulomb.cm_angle(inv0["b"], inv0["distance"])
            for name in ("theta", "psi", "zeta"):
                parts[name].append(out[name][:count])
            parts["error"].append(np.abs(out["theta"] - expected)[:count])
            parts["energy"].append((np.abs(inv["energy"] - inv0["energy"]) / inv0["energy"])[:count])
            dp = np.linalg.norm(inv["momentum"] - inv0["momentum"], axis=-1)
            parts["momentum"].append((dp / np.linalg.norm(inv0["momentum"], axis=-1))[:count])
        cat = {k: np.concatenate(v) for k, v in parts.items()}
        return {
            "beam-cm-angle": float(cat["error"].max()),
            "energy": float(cat["energy"].max()),
            "momentum": float(cat["momentum"].max()),
            **self._distributions(model, prediction, cat["theta"], cat["psi"], cat["zeta"]),
        }

    @staticmethod
    def _closest(traj, pr: Mapping[str, Any]) -> float:
        s = RutherfordPhysics.split(pr, traj.qpos, traj.qvel)
        r = s["x1"][:, 0] - s["x2"][:, 0]
        v = s["v1"][:, 0] - s["v2"][:, 0]
        dist = np.linalg.norm(r, axis=1)
        _, values = signals.extrema(traj.time, dist, np.einsum("ij,ij->i", r, v) / dist, "min")
        return float(values.min()) if values.size else float(dist.min())

    def _drift(self, traj, pr, prediction, times, out_dir, speed) -> dict[str, float]:
        """C9: fit A + C ln t + B / t to the lateral offsets (LAB: the projectile from its asymptotic line; CM: the
        relative coordinate from its own), t from the closest approach, at `times`: the trajectory's samples linearly
        interpolated (from t >= 20 r_min / v on, the path bends by at most a dt^2 / 8 ~ 1e-6 D within a step, 1e-4
        of the drift tolerance)."""
        s = self.split(pr, traj.qpos, traj.qvel)
        t = traj.time - prediction["_t0"] - prediction["_t_half"]
        m1, m2 = pr["m1"], pr["m2"]
        mass = m1 + m2
        x1 = s["x1"][:, 0]
        r = x1 - s["x2"][:, 0]
        keep = t >= times[0] * 0.9
        x1i = np.stack([np.interp(times, t[keep], x1[keep, j]) for j in range(3)], axis=1)
        ri = np.stack([np.interp(times, t[keep], r[keep, j]) for j in range(3)], axis=1)
        # The frames: the plane of the orbit (normal h^) and the asymptotic directions measured from the run.
        p = m1 * s["v1"][-1, 0] + m2 * s["v2"][-1, 0]
        v1_inf = p / mass + (m2 / mass) * speed * out_dir
        h = np.cross(r[-1], s["v1"][-1, 0] - s["v2"][-1, 0])
        if not np.linalg.norm(h) > 0:  # head-on: no plane, no lateral offset
            return {}
        h_hat = h / np.linalg.norm(h)
        fit = _drift_fit(times, x1i, v1_inf, h_hat, ri, out_dir)
        return {"lab-log-drift": fit["lab"], "cm-log-drift": fit["cm"]}

    def _distributions(self, model, prediction, theta, psi, zeta) -> dict[str, float]:
        """The beam's goodness-of-fit p-values (Rutherford in the CM, C6 in the LAB)."""
        min_angle = float(model.numeric("min_angle").data[0])
        pr = prediction["_pairs"]
        x = pr["m1"] / pr["m2"]
        edges = beam_bins(min_angle, x)
        expected = {
            "cm": coulomb.cm_angle_probabilities(edges["cm"], min_angle),
            "projectile": coulomb.lab_angle_probabilities(edges["projectile"], min_angle, x),
            "target": coulomb.lab_angle_probabilities(edges["target"], min_angle, x, particle="target"),
        }
        samples = {"cm": theta, "projectile": psi, "target": zeta}
        return {
            f"{name}-distribution-pvalue": chi_square_pvalue(bin_counts(samples[name], edges[name]), expected[name])
            for name in samples
        }


def beam_bins(min_angle: float, mass_ratio: float) -> dict[str, np.ndarray]:
    """Bin edges (rad) of the beam's three goodness-of-fit tests, NBINS each (`coulomb.beam_bins`)."""
    return coulomb.beam_bins(min_angle, mass_ratio, NBINS)


def _invariants(s: Mapping[str, np.ndarray], m1: float, m2: float, kappa: float) -> dict[str, np.ndarray]:
    """Per pair, from its state (`Rutherford.split`): `coulomb.pair_invariants`."""
    return coulomb.pair_invariants(s["x1"], s["v1"], s["x2"], s["v2"], (m1, m2), kappa)


def _angle(v: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Angle (rad) between vectors (stacked rows), by atan2 of |v x w| and v . w (accurate near 0 and pi)."""
    w = np.broadcast_to(w, np.shape(v))
    cross = np.linalg.norm(np.cross(v, w), axis=-1)
    return np.arctan2(cross, np.einsum("...i,...i", v, w))


def _drift_fit(times, x1, v1_inf, h_hat, r, out_dir) -> dict[str, float]:
    """Coefficients of ln t of the lateral offsets (LAB projectile, CM relative), fitted with A + C ln t + B / t."""
    n_lab = np.cross(v1_inf / np.linalg.norm(v1_inf), h_hat)
    n_cm = np.cross(out_dir, h_hat)
    basis = np.stack([np.ones_like(times), np.log(times), 1.0 / times], axis=1)
    lab = np.linalg.lstsq(basis, x1 @ n_lab, rcond=None)[0][1]
    cm = np.linalg.lstsq(basis, r @ n_cm, rcond=None)[0][1]
    return {"lab": float(lab), "cm": float(cm)}


def _drift_fits(times, r, theta, m1, m2, speed) -> dict[str, float]:
    """`_drift_fit` on the exact orbit (LAB-aligned frame of `coulomb.relative_orbit`)."""
    mass = m1 + m2
    cm_velocity = np.array([m1 * speed / mass, 0.0, 0.0])
    out_dir = np.array([np.cos(theta), np.sin(theta), 0.0])
    x1 = cm_velocity * times[:, None] + (m2 / mass) * r
    v1_inf = cm_velocity + (m2 / mass) * speed * out_dir
    h_hat = np.array([0.0, 0.0, -1.0])  # r x rdot for an offset along +y and a beam along +x
    return _drift_fit(times, x1, v1_inf, h_hat, r, out_dir)


@dataclass(frozen=True)
class Beam:
    """A beam's run: the sample times of one block's run, the first block's first and last states (rows 0 and 1 of
    qpos, qvel), and every block's run with the number of its pairs that belong to the beam (the last block's
    surplus pairs are simulated, not counted)."""

    time: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    diverged_at: float | None
    blocks: tuple = ()


# Steps per rollout call of a beam: rollout records every step (nstep x nstate doubles), so a long run of a big
# model is stepped in stretches whose record stays small.
_STRETCH_BYTES = 32 * 1024**2


def _march(model: mujoco.MjModel, data: mujoco.MjData, nstep: int) -> Beam:
    """Step a beam's model `nstep` times, keeping only the first and last states (`final_states` in stretches)."""
    state0 = get_state(model, data)
    stretch = max(1, _STRETCH_BYTES // (8 * state0.size))
    state, done, diverged = state0[None], 0, False
    while done < nstep and not diverged:
        m = min(stretch, nstep - done)
        state, bad = final_states(model, state, m, nthread=1)
        diverged, done = bool(bad[0]), done + m
    time = data.time + model.opt.timestep * np.arange(nstep + 1)
    qpos = np.stack([state0[1 : 1 + model.nq], state[0, 1 : 1 + model.nq]])
    qvel = np.stack([state0[1 + model.nq : 1 + model.nq + model.nv], state[0, 1 + model.nq : 1 + model.nq + model.nv]])
    return Beam(time, qpos, qvel, float(time[done]) if diverged else None)
