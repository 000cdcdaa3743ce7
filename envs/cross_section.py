"""A uniform beam of hard-sphere collisions: angular distributions and the total cross section by Monte Carlo.

Theory: docs/theory.md C5 (dsigma/dOmega_CM = a^2/4, sigma_tot = pi a^2; Wilcox section 9.9) and C6 (LAB cross
sections, eqs 9.62 and 9.64, both branches for m1 > m2), in `rigidbench.analytic.scattering`. Model:
``models/cross_section.xml`` (the pair of ``hard_spheres.xml`` with a stiffer, shorter contact).

This is batch work: `n` independent collisions, each an initial state of the same two-sphere model, stepped
together in C by `rigidbench.simulate.final_states` (`mujoco.rollout`, one MjData per thread, chunks of
states); no Python loop per collision. The beam is cut into blocks of `BLOCK` collisions, each drawn by its own
numpy Generator seeded from `seed` and the block's index, simulated on its own and reduced to integer counts (a
`Tally`: hits and the three angle histograms), which add up exactly. A run is deterministic, and its result does not
depend on the number of threads, or on whether the blocks ran here or as shards on a Dask cluster
(`rigidbench.shards`, ``--cluster``).

There is no gymnasium env: a beam of independent collisions has no sequential decision to make, and one
collision is what `rigidbench/HardSpheres-v0` offers.
"""

from __future__ import annotations

import hashlib
import os
import pickle
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from rigidbench import shards
from rigidbench.analytic import scattering
from rigidbench.contact import MIN_STEPS, ContactSteps
from rigidbench.contract import UNRESOLVED_FRACTION, Case, Check, Scenario
from rigidbench.envs.hard_spheres import HardSpheres, stiffness_param
from rigidbench.params import Bound, Numeric, Param, Range
from rigidbench.simulate import STATE, final_states, get_state, initial_states

# Free flight before the contact (steps), so the kink of the force at entry falls on a step boundary.
LEAD_STEPS = 2
# Histogram bins of each goodness-of-fit test; bins with fewer expected counts are merged with a neighbour.
NBINS = 20
MIN_EXPECTED = 10.0
# Largest relative kinetic-energy error of a collision allowed for at 20 RK4 steps per contact (measured <= 8e-6
# over k = 1e8-1e11 at 20-80 steps, <= 1e-6 at the reference); RK4's error goes as the step^4, so at s steps per
# contact the budget is ENERGY_BUDGET (20 / s)^4 (measured 1.3e-3 at 4.2 steps, 6.3e-5 at 12: census, issue 13). It
# sets how far LAB angles may pass their kinematic limit.
ENERGY_BUDGET = 1e-5
BUDGET_STEPS = 20.0
# A contact that does not last a whole number of steps starts and ends inside a step, where RK4 integrates a force
# that switches on or off mid-step: a first-order error. Measured (census, issue 13): 1.3e-3 at 4.2 steps per
# contact, 1.1e-3 at 7.2, 5.4e-4 at 11.9, 5.3e-4 at 13.1, 2.6e-4 at 14.2; bounded by SWITCHING_BUDGET / steps.
SWITCHING_BUDGET = 1e-2
# Collisions per block of the beam (see the module's docstring): block 0 is drawn by default_rng(seed), so a beam of
# n <= BLOCK is the single Generator's draw it always was; block j >= 1 by default_rng([seed, j]). A block is also
# the unit of work of a cluster run (one shard each, ~3.5 s of one core at the reference settings).
BLOCK = 10_000
# Significance of the goodness-of-fit tests and the width of the cross-section band.
ALPHA = 1e-3
SIGMAS = 4.0

_GOF = (
    f"Pearson chi-square over {NBINS} bins (merged to >= {MIN_EXPECTED:g} expected), pass if p >= {ALPHA:g}: a "
    f"correct simulation fails one test with probability {ALPHA:g} over seeds (about 1 % for the 9 tests of a "
    "full run). Systematic shifts (soft contact <= pi u/(a sqrt(k)) = 3e-4 rad; RK4 at 20 steps per contact, the "
    "exit on a step boundary: <= 5e-6 rad, measured) move bin contents by < 1e-3 of n, below the statistical "
    "resolution 1/sqrt(n) up to n ~ 1e6"
)
CHECKS = (
    Check(
        "cm-distribution-pvalue",
        "1",
        1 - ALPHA,
        "abs",
        _GOF + "; bins equal in cos(theta)",
        "C5: dsigma/dOmega_CM = a^2/4 (isotropic), Wilcox section 9.9; measured = p-value, expected 1",
        false_alarm=ALPHA,
    ),
    Check(
        "projectile-distribution-pvalue",
        "1",
        1 - ALPHA,
        "abs",
        _GOF + "; bins equal in psi over [0, psi_max]; angles past psi_max by <= tan(psi_max) (1 + x) 1e-5 / 2 "
        "(the shift of the limit by a 1e-5 energy error; 7e-6 rad at x = 3; on float32, by the positions' "
        "rounding's energy floor instead, `precision_floor`) count in the top bin",
        "C6: sigma_lab(psi) = sum over branches sigma_CM (x cos psi +- s)^2 / s, eqs 9.62, 9.64; p-value",
        false_alarm=ALPHA,
    ),
    Check(
        "target-distribution-pvalue",
        "1",
        1 - ALPHA,
        "abs",
        _GOF + "; bins equal in zeta over [0, pi/2]",
        "C6: sigma_2(zeta) = a^2 cos(zeta); p-value",
        false_alarm=ALPHA,
    ),
    Check(
        "total-cross-section",
        "m^2",
        2.7e-3,
        "abs",
        f"{SIGMAS:g} binomial standard errors pi R^2 sqrt(f (1 - f) / n) of the hit fraction f in a beam of radius "
        f"R (two-sided false-failure rate 6e-5); set per run, listed for the default n = 1000",
        "C5: sigma_tot = pi a^2 (hits = collisions whose target moves)",
    ),
)
_ALL = tuple(c.name for c in CHECKS)


DISTRIBUTIONS = ("cm", "projectile", "target")


@dataclass(frozen=True)
class Tally:
    """What a part of the beam leaves to measure: integer counts, which add up exactly over parts (`+`).

    Attributes
    ----------
    collisions, hits, diverged : int
        Collisions simulated, those whose target moved, those that diverged.
    counts : dict of ndarray, shape (NBINS + 2,)
        Per distribution (`DISTRIBUTIONS`: cos theta in the CM, psi and zeta in the LAB, over the hits): the
        histogram over the test's bins (`distribution_bins`), then the count outside the bins and the count of
        non-finite angles (`bin_counts`).
    """

    collisions: int
    hits: int
    diverged: int
    counts: dict[str, np.ndarray] = field(compare=False)

    def __add__(self, other: Tally) -> Tally:
        return Tally(
            self.collisions + other.collisions,
            self.hits + other.hits,
            self.diverged + other.diverged,
            {k: self.counts[k] + other.counts[k] for k in DISTRIBUTIONS},
        )


@dataclass(frozen=True)
class Beam:
    """A simulated beam: its tally, and the final states of its first block (for plots and tests).

    Attributes
    ----------
    time : ndarray, shape (nstep + 1,)
        Sample times of one collision (s).
    tally : Tally
        Counts over the whole beam.
    qpos, qvel : ndarray, shape (m, nq), (m, nv)
        Final states of the first block's m = min(n, BLOCK) collisions.
    impact : ndarray, shape (m,)
        Their impact parameters b (m).
    diverged_at : float or None
        The end time if any collision diverged, else None.
    diverged : int
        Number of collisions that diverged.
    """

    time: np.ndarray
    tally: Tally
    qpos: np.ndarray
    qvel: np.ndarray
    impact: np.ndarray
    diverged_at: float | None
    diverged: int


@dataclass(frozen=True)
class BeamShard:
    """One block of a beam as a self-contained call (`tally_block`): the compiled model (which carries n, seed and
    margin), the representative start state, the block, the steps, and the engine in effect."""

    model: mujoco.MjModel
    state: np.ndarray
    block: int
    nstep: int
    nthread: int | None
    engine: Any = None
    keep: bool = False

    def record(self) -> dict[str, Any]:
        """What the call computes (a cluster keys it by a hash of this)."""
        return {
            "model": hashlib.sha1(pickle.dumps(self.model)).hexdigest(),
            "state": hashlib.sha1(np.ascontiguousarray(self.state).tobytes()).hexdigest(),
            "block": self.block,
            "nstep": self.nstep,
            "engine": self.engine.record() if self.engine is not None else None,
            "keep": self.keep,
        }


def tally_block(shard: BeamShard) -> tuple[Tally, tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
    """Simulate one block of the beam and count it; with ``shard.keep`` also return its final qpos, qvel and impact
    parameters. Runs anywhere: in this process, or on a cluster's worker (where the worker's threads step it)."""
    from rigidbench import engines

    model = shard.model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, shard.state, STATE)
    mujoco.mj_forward(model, data)
    nthread = shard.nthread or _worker_threads() or os.cpu_count() or 1
    with engines.use(shard.engine):
        states0, impact = CrossSection.block(model, data, shard.block)
        states, diverged = final_states(model, states0, shard.nstep, nthread=nthread)
    qpos = states[:, 1 : 1 + model.nq]
    qvel = states[:, 1 + model.nq : 1 + model.nq + model.nv]
    floor = precision_floor(model, data, shard.engine.precision if shard.engine is not None else "float64")
    return tally(model, qpos, qvel, diverged, floor), ((qpos, qvel, impact) if shard.keep else None)


def precision_floor(model: mujoco.MjModel, data: mujoco.MjData, precision: str) -> float:
    """The relative energy error that positions stored in `precision` put into the collisions that reach the
    projectile's kinematic limit, at b0 (`hard_spheres.contact_floor`: the penetration's rounding, or a steady
    heavy projectile's quantised advance); 0 on float64, where RK4's `ENERGY_BUDGET` stands."""
    m1, m2, a = HardSpheres._geometry(model)
    if precision == "float64" or m1 <= m2:
        return 0.0
    return _contact_floor(model, data, precision, scattering.critical_impact_parameter(a, m1 / m2))


def _contact_floor(model: mujoco.MjModel, data: mujoco.MjData, precision: str, impact: float) -> float:
    """`hard_spheres.contact_floor` of the beam's collision at impact parameter `impact` (m), at `precision`."""
    from rigidbench.envs.hard_spheres import contact_floor

    m1, m2, a = HardSpheres._geometry(model)
    state = HardSpheres._state(model, data.qpos, data.qvel)
    speed = float(np.linalg.norm(state["v1"]))
    depth = speed * np.sqrt(1.0 - (impact / a) ** 2) / np.sqrt(HardSpheres()._spring(model).stiffness)
    extent = max(float(np.abs(state["x1"]).max()), float(np.abs(state["x2"]).max()) + a)
    steady = (speed * model.opt.timestep, extent, 2 * m2 / (m1 + m2))
    return contact_floor(float(np.finfo(np.dtype(precision)).eps), a, depth, steady)


def _worker_threads() -> int | None:
    """The threads of the Dask worker running this call (None outside one)."""
    try:
        from distributed import get_worker

        return int(get_worker().state.nthreads)
    except (ImportError, ValueError, AttributeError):
        return None


def distribution_bins(model: mujoco.MjModel, energy_floor: float = 0.0) -> dict[str, tuple[np.ndarray, float]]:
    """Each distribution's test bins and slack (`goodness_of_fit`), from the model's masses and contact, and the
    engine precision's energy floor (`precision_floor`)."""
    m1, m2, _ = HardSpheres._geometry(model)
    x = m1 / m2
    psi_top = scattering.max_lab_angle(x) if x > 1 else (np.pi / 2 if x == 1 else np.pi)
    steps = HardSpheres()._contact_time(model) / model.opt.timestep
    return {
        "cm": (np.linspace(-1.0, 1.0, NBINS + 1), 0.0),
        "projectile": (np.linspace(0.0, psi_top, NBINS + 1), limit_slack(psi_top, x, steps, energy_floor)),
        "target": (np.linspace(0.0, np.pi / 2, NBINS + 1), 0.0),
    }


def tally(
    model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray, diverged: np.ndarray, energy_floor: float = 0.0
) -> Tally:
    """Count a batch of finished collisions (final states) into the tests' bins (their slack from `energy_floor`,
    the engine precision's, `precision_floor`)."""
    out = HardSpheres().outgoing(model, qpos, qvel, np.array([1.0, 0.0, 0.0]))  # beam along +x
    hit = np.linalg.norm(out["v2"], axis=1) > 0
    samples = {"cm": np.cos(out["theta"][hit]), "projectile": out["psi"][hit], "target": out["zeta"][hit]}
    bins = distribution_bins(model, energy_floor)
    counts = {k: bin_counts(samples[k], *bins[k]) for k in DISTRIBUTIONS}
    return Tally(len(qpos), int(np.count_nonzero(hit)), int(np.count_nonzero(diverged)), counts)


# Fewest expected hits n / (1 + margin)^2 of a beam: the angle histograms need them for their goodness-of-fit.
MIN_HITS = 50

_HARD = {p.name: p for p in HardSpheres.params}


# The seed of a beam's impact points (the custom numeric ``seed``), shared by the Monte Carlo scenarios.
BEAM_SEED = Param(
    "seed",
    "1",
    "seed of the numpy Generator drawing the beam's impact points",
    Range(0, 2**53),
    Numeric("seed"),
    integer=True,
)


class CrossSection(Scenario):
    """A uniform beam of `n` smooth elastic sphere collisions: CM and LAB angular distributions as
    goodness-of-fit tests, and the total cross section from the hit fraction (docs/theory.md C5, C6)."""

    slug = "cross-section"
    title = "Hard-sphere cross sections by Monte Carlo (uniform beam)"
    env_id = None
    # Threads for the batch (None: one per CPU). Results do not depend on it.
    nthread: int | None = None
    sharded = True  # the beam's blocks run as shards on a cluster (`rigidbench.shards`)
    # The pair's masses, radii, speed and contact are the hard-spheres scenario's parameters (one definition).
    params = (
        *(_HARD[name] for name in ("m1", "m2", "r1", "r2", "speed")),
        stiffness_param(0.01, "the histograms compare with hard spheres"),
        Param(
            "contact_steps",
            "1",
            "RK4 timesteps per contact pi/sqrt(k): the timestep follows the stiffness; a whole number ends the contact "
            "on a step boundary (CM angles to ~5e-6 rad at 20 steps; ~1e-4 rad when the end falls inside a step)",
            Range(MIN_STEPS, 1e4),
            ContactSteps("projectile"),
            budget=True,
        ),
        Param(
            "n",
            "1",
            "number of collisions in the beam",
            Range(100, 1e7),
            Numeric("samples"),
            integer=True,
            budget=True,
        ),
        BEAM_SEED,
        Param(
            "margin",
            "1",
            "beam radius / (r1 + r2) - 1: the beam overfills the target so the hit fraction measures pi a^2",
            Range(0.0, 10.0),
            Numeric("margin"),
            within=Bound(
                f"[0, sqrt(n / {MIN_HITS}) - 1]: at least {MIN_HITS} of the n collisions hit (n / (1 + margin)^2), "
                "enough for the angle histograms' goodness-of-fit tests",
                lambda p: Range(0.0, max(0.0, np.sqrt(p["n"] / MIN_HITS) - 1.0)),
                ("n",),
            ),
        ),
    )
    cases = (
        Case("equal-mass", "m1 = m2: sigma_lab = a^2 cos(psi), psi < pi/2", {"m1": 1.0, "m2": 1.0}, _ALL),
        Case("light-projectile", "m1/m2 = 1/3: one branch, psi over [0, pi]", {"m1": 1.0, "m2": 3.0}, _ALL),
        Case(
            "heavy-projectile",
            "m1/m2 = 3: two branches below psi_max = arcsin(1/3), an integrable singularity there",
            {"m1": 3.0, "m2": 1.0},
            _ALL,
        ),
    )
    checks = CHECKS

    def check_model(self, model: mujoco.MjModel) -> None:
        HardSpheres().check_model(model)

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        # The representative state: a head-on collision; the beam's states are drawn in `simulate`.
        _, _, a = HardSpheres._geometry(model)
        pos, vel = HardSpheres.place(a, 0.0, params["speed"], LEAD_STEPS * model.opt.timestep)
        s = HardSpheres._state(model, data.qpos, data.qvel)
        s["x1"][:], s["v1"][:], s["x2"][:], s["v2"][:] = pos, vel, 0.0, 0.0

    def precision_domain(
        self, model: mujoco.MjModel, data: mujoco.MjData, prediction: Mapping[str, Any], precision: str
    ) -> str | None:
        """Refused where even the head-on collision, the beam's deepest, has a contact floor
        (`hard_spheres.contact_floor`) of `UNRESOLVED_FRACTION` or more: every collision's energy is then that far
        off (a Warp float32 census draw at k = 1.8e15, 0.54 um deep at 0.29 m from the origin: floor 0.65, its
        angles NaN and its cross section a tenth of pi a^2)."""
        floor = _contact_floor(model, data, precision, 0.0)
        if floor < UNRESOLVED_FRACTION:
            return None
        return (
            f"the head-on collision's contact floor (`hard_spheres.contact_floor`: the penetration read from positions "
            f"rounded to {precision}, or the approach's quantised advance) is {floor:.3g} of its energy (resolvable: "
            f"below {UNRESOLVED_FRACTION:g})"
        )

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        m1, m2, a = HardSpheres._geometry(model)
        n = int(model.numeric("samples").data[0])
        radius = a * (1 + float(model.numeric("margin").data[0]))
        f = (a / radius) ** 2  # expected hit fraction
        area = np.pi * radius**2
        return {
            "_a": a,
            "_x": m1 / m2,
            "_n": n,
            "_beam_radius": radius,
            "_duration": self._nstep(model) * model.opt.timestep,
            "cm-distribution-pvalue": 1.0,
            "projectile-distribution-pvalue": 1.0,
            "target-distribution-pvalue": 1.0,
            "total-cross-section": np.pi * a * a,
            "_tolerance": {"total-cross-section": SIGMAS * area * np.sqrt(f * (1 - f) / n)},
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return prediction["_duration"]

    @staticmethod
    def _nstep(model: mujoco.MjModel) -> int:
        contact = HardSpheres()._contact_time(model)
        # An oblique contact lasts a little longer than pi/sqrt(k) (the normal turns by ~ u pi/(a sqrt(k)) = 3e-4
        # rad during it); 1.15x is ample, and self-checked: a hit that has not separated has NaN angles, and the
        # tests then fail.
        return 2 * LEAD_STEPS + int(np.ceil(1.15 * contact / model.opt.timestep))

    @staticmethod
    def blocks(model: mujoco.MjModel) -> int:
        """The number of blocks of the model's beam (`BLOCK`)."""
        return -(-int(model.numeric("samples").data[0]) // BLOCK)

    @staticmethod
    def block(model: mujoco.MjModel, data: mujoco.MjData, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Block `j` of the beam: its initial states and impact parameters, drawn from the model's seed.

        Returns
        -------
        states : ndarray, shape (m, nstate), m = min(BLOCK, n - j BLOCK)
        impact : ndarray, shape (m,)
        """
        _, _, a = HardSpheres._geometry(model)
        n = int(model.numeric("samples").data[0])
        count = min(BLOCK, n - j * BLOCK)
        if not 0 <= j or count <= 0:
            raise ValueError(f"block {j} is outside the beam's {CrossSection.blocks(model)} blocks")
        seed = int(model.numeric("seed").data[0])
        radius = a * (1 + float(model.numeric("margin").data[0]))
        speed = float(np.linalg.norm(HardSpheres._state(model, data.qpos, data.qvel)["v1"]))
        rng = np.random.default_rng(seed if j == 0 else [seed, j])
        impact = radius * np.sqrt(rng.random(count))  # uniform over the disc: P(b < r) = r^2 / R^2
        azimuth = 2 * np.pi * rng.random(count)
        qpos = np.repeat(data.qpos[None], count, axis=0)
        qvel = np.repeat(data.qvel[None], count, axis=0)
        pos, vel = HardSpheres.place(a, impact, speed, LEAD_STEPS * model.opt.timestep, azimuth)
        st = HardSpheres._state(model, qpos, qvel)
        st["x1"][:], st["v1"][:] = pos, vel
        return initial_states(model, data, qpos, qvel), impact

    def beam(self, model: mujoco.MjModel, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """The whole beam's initial states and impact parameters: its blocks in order (`block`)."""
        parts = [self.block(model, data, j) for j in range(self.blocks(model))]
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])

    def simulate(
        self, model: mujoco.MjModel, data: mujoco.MjData, duration: float, *, control: np.ndarray | None = None
    ) -> Beam:
        from rigidbench import engines

        nstep = round(duration / model.opt.timestep)
        state = get_state(model, data)
        calls = [
            (BeamShard(model, state, j, nstep, self.nthread, engines.current(), keep=j == 0),)
            for j in range(self.blocks(model))
        ]
        total, first = None, None
        for j, (part, kept) in shards.map(tally_block, calls):  # here, or as shards on a cluster (--cluster)
            total = part if total is None else total + part
            if j == 0:
                first = kept
        qpos, qvel, impact = first
        time = data.time + model.opt.timestep * np.arange(nstep + 1)
        bad = total.diverged
        return Beam(time, total, qpos, qvel, impact, float(time[-1]) if bad else None, bad)

    def measure(self, model: mujoco.MjModel, traj: Beam, prediction: Mapping[str, Any]) -> dict[str, float]:
        a, x = prediction["_a"], prediction["_x"]
        t = traj.tally
        sigma = np.pi * prediction["_beam_radius"] ** 2 * t.hits / t.collisions
        bins = distribution_bins(model)
        # CM: sigma_CM = a^2/4 is uniform in solid angle, i.e. in cos(theta): equal probabilities.
        expected = {
            "cm": np.full(NBINS, 1.0 / NBINS),
            "projectile": scattering.lab_angle_probabilities(bins["projectile"][0], a, x),
            "target": scattering.lab_angle_probabilities(bins["target"][0], a, x, particle="target"),
        }
        p = {k: chi_square_pvalue(t.counts[k], expected[k]) for k in DISTRIBUTIONS}
        return {
            "cm-distribution-pvalue": p["cm"],
            "projectile-distribution-pvalue": p["projectile"],
            "target-distribution-pvalue": p["target"],
            "total-cross-section": float(sigma),
        }


def limit_slack(psi_limit: float, x: float, contact_steps: float = BUDGET_STEPS, energy_floor: float = 0.0) -> float:
    """How far (rad) simulated LAB angles of the projectile may pass the kinematic limit `psi_limit`, psi_max =
    arcsin(1/x) for x = m1/m2 > 1; 0 otherwise.

    The limit holds for an exactly elastic collision. A relative energy error eps of the collision changes the
    projectile's CM speed by (1 + x) eps / 2 relatively, which moves the limit by tan(psi_limit) (1 + x) eps / 2.
    Near the limit psi is stationary in b, so with enough samples some land on it, and an energy error too small
    to matter anywhere else puts them beyond it: measured up to 59 of 2e4 hits beyond psi_max by up to 2.4e-6 rad
    (x = 3, k = 1e8 to 1e11, 20 to 80 RK4 steps per contact, energy errors <= 8e-6). `ENERGY_BUDGET` bounds eps
    at 20 steps per contact, and (20 / contact_steps)^4 times it at fewer (RK4's order); a contact of a fractional
    number of steps switches mid-step, a first-order error bounded by `SWITCHING_BUDGET` / contact_steps. On a
    float32 engine the positions' rounding bounds it instead where larger (`energy_floor`, `precision_floor`).
    Equal masses (limit pi/2, reached head-on, where the projectile stops) and x < 1 (range up to pi) get none:
    no sample has passed pi/2 in any run so far, and one that does fails the test.
    """
    if x <= 1:
        return 0.0
    budget = ENERGY_BUDGET * max(1.0, (BUDGET_STEPS / contact_steps) ** 4)
    if abs(contact_steps - round(contact_steps)) > 1e-6:  # the contact switches mid-step: first order
        budget = max(budget, SWITCHING_BUDGET / contact_steps)
    budget = max(budget, energy_floor)
    return float(np.tan(psi_limit) * (1 + x) * budget / 2)


def goodness_of_fit(samples: np.ndarray, edges: np.ndarray, probabilities: np.ndarray, *, slack: float = 0.0) -> float:
    """p-value of Pearson's chi-square test of `samples` against bin `probabilities` (NaN if any sample is NaN):
    `chi_square_pvalue` of `bin_counts`.

    Parameters
    ----------
    samples : ndarray, shape (m,)
    edges : ndarray, shape (nbin + 1,)
    probabilities : ndarray, shape (nbin,)
    slack : float
    """
    return chi_square_pvalue(bin_counts(samples, edges, slack), probabilities)


def bin_counts(samples: np.ndarray, edges: np.ndarray, slack: float = 0.0) -> np.ndarray:
    """The counts a goodness-of-fit test needs, which add up over parts of a sample: the histogram over `edges`
    (bins close on the right at the top edge, so a sample exactly at psi_max or pi/2 counts), then the number of
    finite samples outside the edges, then the number of non-finite samples. Samples at most `slack` above the top
    edge (a kinematic limit passed by the integration error, `limit_slack`) count in the top bin.

    Returns
    -------
    ndarray of int64, shape (nbin + 2,)
    """
    samples = np.asarray(samples, dtype=float)
    finite = samples[np.isfinite(samples)]
    top = edges[-1]
    finite = np.where((finite > top) & (finite <= top + slack), top, finite)  # `slack`: see `limit_slack`
    observed = np.histogram(finite, edges)[0].astype(np.int64)
    return np.concatenate([observed, [finite.size - observed.sum(), samples.size - finite.size]])


def chi_square_pvalue(counts: np.ndarray, probabilities: np.ndarray) -> float:
    """p-value of Pearson's chi-square test of binned `counts` (`bin_counts`) against bin `probabilities`; NaN
    for no samples or any non-finite one.

    Samples outside the edges count in the end bins' complement: they are added as one extra bin with its
    expected probability 1 - sum(probabilities) (zero for a complete set of bins, so any sample outside fails).
    Adjacent bins are merged until each expects at least `MIN_EXPECTED` samples.
    """
    counts = np.asarray(counts)
    observed, outside, nonfinite = counts[:-2].astype(float), float(counts[-2]), int(counts[-1])
    size = observed.sum() + outside
    if size == 0 or nonfinite:
        return float("nan")
    expected = size * np.asarray(probabilities, dtype=float)
    rest = size - expected.sum()
    if outside > 0 and rest < MIN_EXPECTED:
        return 0.0  # samples where theory puts (almost) none
    obs, exp = [], []
    acc_o = acc_e = 0.0
    for o, e in zip(observed, expected, strict=True):
        acc_o += o
        acc_e += e
        if acc_e >= MIN_EXPECTED:
            obs.append(acc_o)
            exp.append(acc_e)
            acc_o = acc_e = 0.0
    if acc_e > 0 or acc_o > 0:
        obs[-1] += acc_o
        exp[-1] += acc_e
    if rest >= MIN_EXPECTED:
        obs.append(outside)
        exp.append(rest)
    obs, exp = np.array(obs), np.array(exp)
    exp *= obs.sum() / exp.sum()  # the quadrature's last digits, so the totals agree exactly
    from scipy import stats  # here, not at the top: scipy.stats adds ~0.3 s to every `import rigidbench`

    return float(stats.chisquare(obs, exp).pvalue)
