"""Derivatives under the same theory (issue 37): MuJoCo's Jacobians scored against the linearised closed forms.

For each smooth scenario (pendulum, coupled pendulums, pendulum chain, double pendulum, free symmetric top) and each
of its cases, one
`rigidbench.harness.CaseRun` whose rows have the format of ``rigidbench run`` (`rigidbench.results.rows_of`):

- ``transition-map``: the one-step Jacobian ``d x_{k+1} / d x_k`` at the lower equilibrium (state ``x = (q, v)``),
  from ``mujoco.mjd_transitionFD`` (centred, `EPS`) for the Euler family and ``discrete``, and from centred
  differences of ``mj_step`` for RK4 (``mjd_transitionFD`` refuses RK4), against the integrator's own map of
  ``T q'' + V q = 0`` (`rigidbench.analytic.linearised.transition_map`), T and V built from the parameters read
  back from the compiled model. The error is ``|A - A_theory|_F / |A_theory - 1|_F``: relative to what the step
  changes (the map is the identity plus O(h)), so a 1e-6 error in a force constant moves it by ~1e-6.
- ``transition-flow`` (RK4): the same Jacobian against the exact flow ``exp(J h)``: a fourth-order map is the flow
  to ``(omega h)^4 / 120`` of the step's change (the Euler family's O(omega h) is not scored against it).
- ``transition-map-at-start`` (pendulum): the same at the case's release state (amplitude a, at rest), against
  the exact Jacobian of the integrator's map of the nonlinear pendulum (``omega0^2 cos a``).
- ``map-omega`` / ``map-omega-slowest`` / ``map-omega-fastest``: the angle per step of the map's eigenvalues over
  h, against O1-O7's frequencies carried through the integrator's map (`linearised.map_frequency`).
- ``map-mode-shapes``: the eigenvectors' angle parts against O3-O7's shapes (unit length, up to sign); where the
  modes are closer than the map's error resolves (`SHAPES_UNRESOLVED`), the row is reported unresolved.
- ``inverse-omega*`` and ``inverse-mass``: normal-mode frequencies from ``mjd_inverseFD``'s stiffness ``df/dq``
  and mass ``df/da`` (generalised eigenproblem; no integrator in it), and ``df/da`` against T.
- ``period-amplitude-slope`` (pendulum): dT/da by centred differences of the scenario's own period measurement
  over two rollouts at a +- `AMPLITUDE_STEP`, against O1's own centred difference over the same +- da.
- ``rotation-map`` and ``map-body-rate`` (free symmetric top): the body-frame rates' rows of the one-step Jacobian
  against Euler's equations through the integrator's map (`linearised.rotation_map`), and the angle per step of
  their eigenvalues about a steady spin against S1's body-frame precession rate.

Floors scale with `geometry_factor` (positions' rounding against the lengths that make them angles); a census of
random valid sets (`census`, ``rigidbench derivatives --census N``) has 0 failed and 0 crashed.

``perturb`` edits a copy of the compiled model that is differentiated and simulated, while the theory keeps the
unperturbed one (as `rigidbench.power` does): tests/test_derivatives.py shows each check catching a 1e-6 error.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from rigidbench import registry
from rigidbench.analytic import linearised as lin
from rigidbench.analytic import oscillations as osc
from rigidbench.envs import pendulums
from rigidbench.harness import CaseRun, Outcome, settings_record
from rigidbench.params import Range
from rigidbench.scenario import Check, Scenario
from rigidbench.settings import INTEGRATORS, Settings

EPS = 1e-6  # finite-difference step of the state (rad, rad/s) and of mjd_inverseFD
AMPLITUDE_STEP = 1e-2  # rad: the centred difference of the period over two rollouts
# transition-map's worst error with margin: an eigenvector moves by the map's error over its eigenvalue's relative gap
SHAPE_MAP_ERROR = 1e-9
SHAPES_UNRESOLVED = 0.1  # a shape floor this large: the modes are degenerate to the map's precision
SCENARIOS = ("pendulum", "coupled-pendulums", "pendulum-chain", "double-pendulum", "free-symmetric-top")
TOPS = ("free-symmetric-top",)
# the rates' finite-difference step for a spinning body (rad/s): Euler's equations are quadratic in the rates, so
# centred differences are exact for the Euler family's map and O(eps^2 h^2) for RK4's; a larger step than EPS
# keeps the rounding u |omega| / eps below 1e-8 of the step's change h |J| (~1e-3)
EPS_RATES = 1e-4
# The cases whose period slope is scored (where a +- da lies in the amplitude's range: `_slope_inside`): the
# small-amplitude case's slope a T0 / 8 is below what two rollouts resolve, the near-inverted one's a + da leaves it.
SLOPE_CASES = ("one-radian", "large-amplitude")

_FD = (
    f"centred differences of step {EPS:g}: truncation eps^2 |f'''| / 6 ~ 1e-12 (the map is linear at the "
    f"equilibrium to O(eps^2)), round-off u |x_(k+1)| / eps ~ 2.2e-16 x 1 m / {EPS:g} = 2.2e-10 of each column"
)

CHECKS: dict[str, Check] = {
    c.name: c
    for c in (
        Check(
            "transition-map",
            "1",
            1e-9,
            "abs",
            f"{_FD}; measured <= 3.5e-11 at the cases under RK4 and the Euler family, <= 1.1e-10 x geometry over "
            "a census (seeds 1-3, 20 sets per scenario); 1e-9, times the geometry "
            "factor max(1, extent / scale) where positions of size extent (the farthest body or site) are rounded "
            "against the smallest length that turns them into angles (rod length, spring height: "
            "`geometry_factor`, 1 at the defaults)",
            "O7: x_(k+1) = A x_k, A the integrator's map of T q'' + V q = 0 (analytic/linearised.py)",
        ),
        Check(
            "transition-flow",
            "1",
            1e-9,
            "abs",
            "RK4 only: its map is exp(J h) but for the Taylor terms from (J h)^5 / 120 on, (omega_max h)^4 / 120 of "
            "the step's change; the row's tolerance is (1e-9 + that) times transition-map's geometry factor "
            "(measured 1e-12..9e-11 at the cases, against 1e-9..2.9e-9)",
            "O7: the exact flow exp(J h) of T q'' + V q = 0, J = [[0, 1], [-T^-1 V, 0]]",
        ),
        Check(
            "rotation-map",
            "1",
            1e-9,
            "abs",
            f"centred differences of the rates, step {EPS_RATES:g} rad/s: exact for the Euler family's quadratic "
            "map, O(eps^2 h^2) for RK4's; the rounding of the new rates, 4 u |omega| / (eps |B - 1|_F), is added "
            "in each row (7e-9 at the cases, measured <= 3e-10)",
            "S1: Euler's equations omega' = I^-1 ((I omega) x omega) through the integrator's map "
            "(analytic/linearised.py rotation_map: Euler 1 + h J; implicit, implicitfast and discrete (1 - h J)^-1 "
            "(measured: they keep the gyroscopic derivative); RK4 on the variational equations); no dependence on "
            "the orientation without torques",
        ),
        Check(
            "map-body-rate",
            "rad/s",
            1e-8,
            "rel",
            "the eigenvalues of the rates' map about a steady spin carry its error (rotation-map's floor) into the "
            "angle per step",
            "S1: body-frame precession Omega = (I3 - I1) omega3 / I1 (Wilcox eq. 11.42), through the map: "
            "atan(Omega h) / h (Euler family), arg R(i Omega h) / h (RK4)",
        ),
        Check(
            "transition-map-at-start",
            "1",
            1e-8,
            "abs",
            f"{_FD}; plus, at the release state, the rounding of the new state, u |q| per evaluation: the row adds "
            "4 u max(|q|, |v| h) / (eps |A - 1|_F) (1.4e-7 at 2.5 rad, where 3.1e-8 is measured)",
            "O1: the integrator's map of q'' = -omega0^2 sin q, Jacobian with omega0^2 cos a (analytic/linearised.py)",
        ),
        Check(
            "map-omega",
            "rad/s",
            1e-9,
            "rel",
            "the eigenvalues of the map carry the centred differences' error (transition-map's floor) into the "
            "angle per step; measured <= 7.7e-12 at the cases, <= 8.2e-11 x geometry over a census; 1e-9 times "
            "transition-map's geometry factor",
            "O1/O3/O5/O7: omega of the linearised theory through the integrator's map, theta = 2 asin(omega h/2) "
            "(Euler family), arg R(i omega h) (RK4)",
        ),
        Check(
            "map-mode-shapes",
            "1",
            1e-7,
            "abs",
            "an eigenvector moves by (error of the map) / (relative gap of its eigenvalues): the row's tolerance is "
            "1e-7 + 1e-9 x geometry / gap (1e-9: transition-map's base; geometry as there); measured <= 4.4e-10 at "
            "the cases; unresolved (not scored) where the second term reaches 0.1: modes degenerate to the map's "
            "precision",
            "O3/O5/O7: mode shapes a_r of det(V - omega^2 T) = 0 (joint coordinates)",
        ),
        Check(
            "inverse-omega",
            "rad/s",
            1e-9,
            "rel",
            f"mjd_inverseFD's centred differences of step {EPS:g}: the forces' round-off u |x| / (scale eps) ~ "
            "2.2e-10 of the stiffness, half of it in omega; measured <= 6.6e-12 at the cases, <= 6.6e-11 x "
            "geometry over a census; 1e-9 times transition-map's geometry factor",
            "O1/O3/O5/O7: omega^2 = eigenvalues of V against T, V = df/dq, T = df/da (no integrator)",
        ),
        Check(
            "inverse-mass",
            "1",
            1e-9,
            "abs",
            "df/da of inverse dynamics is linear in qacc: centred differences are exact up to round-off u |M| / eps "
            "~ 2e-10 (measured <= 1e-11); |df/da - T|_F / |T|_F",
            "O7: T, the kinetic-energy matrix (I_cm + m l^2 ... in joint coordinates); `discrete`: M + h D, D = 0 "
            "without dampers",
        ),
        Check(
            "period-amplitude-slope",
            "s/rad",
            1e-9,
            "rel",
            f"expected is O1's own centred difference over a +- {AMPLITUDE_STEP:g} rad (no truncation between them); "
            "the rollouts' period errors e+, e- bound the difference: the row's tolerance is 1e-9 + "
            "(|e+| + |e-|) / (2 da |dT/da|), with |e| = (omega_max h)^4 / 120 T under RK4 (its order; measured "
            "4e-11..6e-11 against 1e-8) and the rollouts' errors against O1 under the Euler family "
            "((omega h)^2 / 24 ~ 1.6e-6 of T: measured 6e-7..1e-5 against 7e-5..7e-4)",
            "O1: dT/da = 4 sqrt(l/g) dK/dm sin(a)/2, dK/dm = (E - (1 - m) K) / (2 m (1 - m)), m = sin^2(a/2)",
        ),
    )
}


def _named(base: str, n: int) -> list[str]:
    """Row names of per-mode checks: ``base`` for one mode, ``base-slowest`` and ``base-fastest`` for more."""
    return [base] if n == 1 else [f"{base}-slowest", f"{base}-fastest"]


def _check(name: str, **replace: Any) -> Check:
    base = CHECKS[name.removesuffix("-slowest").removesuffix("-fastest")]
    return dataclasses.replace(base, name=name, **replace)


# ---- the theory, from the compiled model ------------------------------------------------------------------------


@dataclass(frozen=True)
class Theory:
    """The linearised theory of a compiled model in MuJoCo's joint coordinates q (``absolute = S q``).

    Attributes
    ----------
    inertia, stiffness, springs : ndarray, shape (n, n)
        T, V and the springs' share V_s of V (joint coordinates).
    omegas : ndarray, shape (n,)
        Closed-form mode frequencies (rad/s), ascending (O1, O3, O5 or O7).
    shapes : ndarray, shape (n, n)
        Column r: mode r's shape in joint coordinates, scaled to its largest entry.
    spring_share : ndarray, shape (n,)
        Each mode's omega_s^2 = a_r^T V_s a_r (a_r normalised a^T T a = 1).
    theory : str
        The IDs behind it.
    """

    inertia: np.ndarray
    stiffness: np.ndarray
    springs: np.ndarray
    omegas: np.ndarray
    shapes: np.ndarray
    spring_share: np.ndarray
    theory: str


def absolute_map(model: mujoco.MjModel) -> np.ndarray:
    """S with absolute rod angles = S q: a hinge turns its body and every body below it (planar chains, one axis)."""
    n = model.njnt
    S = np.zeros((n, n))
    for i in range(n):
        body = model.jnt_bodyid[i]
        for j in range(n):
            b = body
            while b > 0:
                if b == model.jnt_bodyid[j]:
                    S[i, j] = 1.0
                    break
                b = model.body_parentid[b]
    return S


def theory(slug: str, model: mujoco.MjModel) -> Theory:
    """The linearised theory of scenario `slug`'s compiled `model` (parameters read back from it)."""
    pend = pendulums.pendulums(model)
    g = pendulums.gravity(model)
    n = len(pend)
    Vs_abs = np.zeros((n, n))
    if slug == "double-pendulum":
        p1, p2 = pend
        T_abs, V_abs = osc.double_pendulum_matrices(
            p1.mass, p2.mass, p1.length, p2.length, g, p1.inertia_cm, p2.inertia_cm
        )
        modes, ids = osc.normal_modes(T_abs, V_abs), "O6/O7"
    else:
        p = pend[0]
        mgl = p.mass * g * p.length
        if slug == "pendulum":
            T_abs, V_abs = np.array([[p.inertia_pivot]]), np.array([[mgl]])
            modes, ids = osc.normal_modes(T_abs, V_abs), "O1/O2 (small amplitude)"
        else:
            sp = pendulums.springs(model)
            k = float(sp.stiffness[0])
            T_abs, V_abs = osc.spring_chain_matrices(n, p.inertia_pivot, mgl, k, sp.height)
            Vs_abs = osc.spring_chain_matrices(n, p.inertia_pivot, 0.0, k, sp.height)[1]
            if slug == "coupled-pendulums":
                modes, ids = osc.coupled_modes(p.inertia_pivot, mgl, k, sp.height), "O3"
            else:
                modes, ids = osc.chain_modes(n, p.inertia_pivot, mgl, k, sp.height), "O5"
    S = absolute_map(model)
    shapes = np.linalg.solve(S, modes.shapes)
    share = np.einsum("ir,ij,jr->r", modes.shapes, Vs_abs, modes.shapes)
    return Theory(
        inertia=S.T @ T_abs @ S,
        stiffness=S.T @ V_abs @ S,
        springs=S.T @ Vs_abs @ S,
        omegas=np.asarray(modes.frequencies, dtype=float),
        shapes=shapes,
        spring_share=share,
        theory=ids,
    )


def _largest(vectors: np.ndarray) -> np.ndarray:
    """Each column's entry of largest magnitude (a column divided by it is real and has largest entry 1)."""
    idx = np.argmax(np.abs(vectors), axis=0)
    return vectors[idx, np.arange(vectors.shape[1])]


# ---- what MuJoCo gives --------------------------------------------------------------------------------------------


def transition(model: mujoco.MjModel, data: mujoco.MjData, eps: float = EPS) -> np.ndarray:
    """``d x_{k+1} / d x_k`` (2 nv x 2 nv) at `data`'s state: ``mjd_transitionFD`` (centred), or for RK4, which it
    refuses, centred differences of ``mj_step`` in the same tangent coordinates (qpos through mj_integratePos)."""
    nv = model.nv
    if model.opt.integrator != mujoco.mjtIntegrator.mjINT_RK4:
        A = np.zeros((2 * nv + model.na, 2 * nv + model.na))
        mujoco.mjd_transitionFD(model, data, eps, True, A, None, None, None)
        return A[: 2 * nv, : 2 * nv]
    qpos0, qvel0 = data.qpos.copy(), data.qvel.copy()
    work = mujoco.MjData(model)

    def step(dx: np.ndarray) -> np.ndarray:
        mujoco.mj_resetData(model, work)
        work.qpos[:] = qpos0
        mujoco.mj_integratePos(model, work.qpos, dx[:nv].copy(), 1.0)
        work.qvel[:] = qvel0 + dx[nv:]
        mujoco.mj_step(model, work)
        out = np.empty(2 * nv)
        mujoco.mj_differentiatePos(model, out[:nv], 1.0, qpos0, work.qpos)
        out[nv:] = work.qvel
        return out

    A = np.empty((2 * nv, 2 * nv))
    for i in range(2 * nv):
        dx = np.zeros(2 * nv)
        dx[i] = eps
        A[:, i] = (step(dx) - step(-dx)) / (2 * eps)
    return A


def inverse(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
    """``(df/dq, df/da)`` of inverse dynamics (``mjd_inverseFD``, centred) at `data`'s state. It refuses RK4; inverse
    dynamics do not depend on the integrator (``discrete`` aside: df/da = M + h D), so RK4 is evaluated with Euler."""
    nv = model.nv
    if model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4:
        model = copy.copy(model)
        model.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    DfDq, DfDa = np.zeros((nv, nv)), np.zeros((nv, nv))
    mujoco.mjd_inverseFD(model, data, EPS, True, DfDq, None, DfDa, None, None, None, None)
    return DfDq, DfDa


def map_modes(A: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """(theta / h ascending, shapes) of a map's oscillating eigenvalues ``|lambda| e^(+-i theta)``: one of each
    conjugate pair (theta > 0); shapes are the q parts of the eigenvectors, each scaled to its largest entry (real:
    an undamped mode's q part is a real vector times a phase)."""
    n = len(A) // 2
    lam, vec = np.linalg.eig(A)
    keep = np.flatnonzero(np.angle(lam) > 0)
    order = keep[np.argsort(np.angle(lam[keep]))]
    shapes = vec[:n, order]
    return np.angle(lam[order]) / h, (shapes / _largest(shapes)).real


def geometry_factor(model: mujoco.MjModel) -> float:
    """max(1, extent / scale): the positions' rounding u |x| is an error of u |x| / scale in the angles they give,
    scale the smallest length that turns positions into angles (a rod's length, the springs' height d) and extent
    the farthest body or site from the origin at the equilibrium. Centred differences of step eps see it over eps,
    so the floors of the rows that read MuJoCo's forces scale with it (1 at the defaults, up to 1e5 where a census
    draws a millimetre pendulum metres from the origin)."""
    data = _equilibrium(model)
    extent = max(float(np.abs(data.xpos).max()), float(np.abs(data.site_xpos).max()) if model.nsite else 0.0)
    lengths = [p.length for p in pendulums.pendulums(model)]
    if model.ntendon:
        lengths.append(pendulums.springs(model).height)
    return max(1.0, extent / min(lengths))


def _equilibrium(model: mujoco.MjModel) -> mujoco.MjData:
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    mujoco.mj_forward(model, data)
    return data


def _shape_error(measured: np.ndarray, expected: np.ndarray) -> float:
    """The largest distance between a measured and an expected mode shape, both of unit length, up to sign."""
    if measured.shape != expected.shape:
        return math.inf
    u = measured / np.linalg.norm(measured, axis=0)
    v = expected / np.linalg.norm(expected, axis=0)
    return float(np.max(np.minimum(np.linalg.norm(u - v, axis=0), np.linalg.norm(u + v, axis=0))))


# ---- a case -------------------------------------------------------------------------------------------------------


def run_case(
    scenario: Scenario,
    case: str | None = None,
    overrides: Mapping[str, object] | None = None,
    settings: Settings | None = None,
    *,
    perturb: Callable[[mujoco.MjModel], None] | None = None,
) -> CaseRun:
    """Differentiate one case and score every derivative check (module docstring): a `CaseRun` for
    `rigidbench.results.rows_of`. `perturb` edits a copy of the compiled model, the theory keeps the original."""
    t0 = time.perf_counter()
    prep = scenario.prepare(case, overrides, settings)
    model = prep.model
    integrator = _integrator(model)
    simulated = model
    if perturb is not None:
        simulated = copy.copy(model)
        perturb(simulated)
    h = float(model.opt.timestep)
    if scenario.slug in TOPS:
        return _case_run(scenario, prep, settings, _top_outcomes(prep, simulated, integrator), t0)
    th = theory(scenario.slug, model)
    n = len(th.omegas)
    outcomes: list[Outcome] = []

    geometry = geometry_factor(model)

    def scaled(check: Check, factor: float = 1.0) -> Check:
        return dataclasses.replace(check, tolerance=check.tolerance * geometry * factor)

    A = transition(simulated, _equilibrium(simulated))
    A_th = lin.transition_map(integrator, th.inertia, th.stiffness, h, th.springs)
    change = np.linalg.norm(A_th - np.eye(len(A_th)))
    outcomes.append(Outcome(scaled(CHECKS["transition-map"]), float(np.linalg.norm(A - A_th) / change), 0.0))
    if integrator == "RK4":  # a 4th-order map is the exact flow to (omega h)^4 / 120 of the step's change
        flow = lin.flow_map(th.inertia, th.stiffness, h)
        order = (float(th.omegas.max()) * h) ** 4 / 120
        outcomes.append(
            Outcome(scaled(CHECKS["transition-flow"], 1 + order / 1e-9), float(np.linalg.norm(A - flow) / change), 0.0)
        )

    if scenario.slug == "pendulum":
        start = mujoco.MjData(simulated)
        start.qpos[:], start.qvel[:] = prep.data.qpos, prep.data.qvel
        mujoco.mj_forward(simulated, start)
        omega0_sq = float(th.stiffness[0, 0] / th.inertia[0, 0])
        P = lin.pendulum_transition(integrator, omega0_sq, float(start.qpos[0]), float(start.qvel[0]), h)
        change = np.linalg.norm(P - np.eye(2))
        err = np.linalg.norm(transition(simulated, start) - P) / change
        check = CHECKS["transition-map-at-start"]
        size = max(abs(float(start.qpos[0])), abs(float(start.qvel[0])) * h)
        floor = 4 * np.finfo(float).eps * size / (EPS * change)  # the new state's rounding, over the step's change
        outcomes.append(Outcome(dataclasses.replace(check, tolerance=check.tolerance + floor), float(err), 0.0))

    theta, shapes = map_modes(A, h)
    expected = lin.map_frequency(integrator, th.omegas, h, th.spring_share)
    measured = theta if len(theta) == n else np.full(n, math.nan)
    for name, i in zip(_named("map-omega", n), (0, -1), strict=False):
        outcomes.append(Outcome(scaled(_check(name)), float(measured[i]), float(expected[i])))
    if n > 1:
        w = th.omegas
        gap = min(abs(w[r] - w[s]) for r in range(n) for s in range(n) if r != s) / w.max()
        spread = SHAPE_MAP_ERROR * geometry / gap if gap > 0 else math.inf
        shape_check = dataclasses.replace(
            CHECKS["map-mode-shapes"], tolerance=CHECKS["map-mode-shapes"].tolerance + spread
        )
        # modes closer than the map's error resolves: their shapes mix freely, reported, not scored
        unresolved = spread >= SHAPES_UNRESOLVED
        outcomes.append(Outcome(shape_check, _shape_error(shapes, th.shapes), 0.0, unresolved))

    DfDq, DfDa = inverse(simulated, _equilibrium(simulated))
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(DfDa, DfDq)).real)
    omegas = np.sqrt(np.clip(w2, 0.0, None))
    for name, i in zip(_named("inverse-omega", n), (0, -1), strict=False):
        outcomes.append(Outcome(scaled(_check(name)), float(omegas[i]), float(th.omegas[i])))
    mass_err = np.linalg.norm(DfDa - th.inertia) / np.linalg.norm(th.inertia)
    outcomes.append(Outcome(CHECKS["inverse-mass"], float(mass_err), 0.0))

    if scenario.slug == "pendulum" and prep.case.name in SLOPE_CASES and _slope_inside(scenario, prep):
        outcomes.append(_slope(scenario, prep, overrides, settings, perturb, integrator))
    return _case_run(scenario, prep, settings, outcomes, t0)


def _case_run(scenario: Scenario, prep: Any, settings: Settings | None, outcomes: list[Outcome], t0: float) -> CaseRun:
    return CaseRun(
        scenario=scenario.slug,
        case=prep.case.name,
        params=prep.params,
        settings=settings_record(prep.model, settings),
        outcomes=outcomes,
        diverged_at=None,
        duration=float(prep.model.opt.timestep),
        nstep=1,
        wall_time=time.perf_counter() - t0,
    )


def _top_outcomes(prep: Any, simulated: mujoco.MjModel, integrator: str) -> list[Outcome]:
    """A free body's body-frame rates: their one-step Jacobian at the case's release state (rows of the rates against
    the orientation and the rates) against `linearised.rotation_map` (zero against the orientation), and the angle
    per step of its eigenvalues about a steady spin at the same axial rate against S1's body-frame precession rate
    through the integrator's map. The moments are read back from the compiled model."""
    model, h = prep.model, float(prep.model.opt.timestep)
    body = int(model.jnt_bodyid[0])
    if not np.allclose(model.body_iquat[body], [1, 0, 0, 0]):
        raise ValueError("derivatives: the free body's principal axes must be its body axes")
    inertia = model.body_inertia[body].copy()
    outcomes = []
    rows, cols = slice(9, 12), [3, 4, 5, 9, 10, 11]  # rates' rows; orientation and rates columns (tangent space)
    for name, omega in (("rotation-map", prep.data.qvel[3:6].copy()), (None, np.array([0, 0, prep.data.qvel[5]]))):
        data = mujoco.MjData(simulated)
        data.qpos[:] = prep.data.qpos
        data.qvel[:] = 0.0
        data.qvel[3:6] = omega
        mujoco.mj_forward(simulated, data)
        A = transition(simulated, data, EPS_RATES)[rows][:, cols]
        B = np.hstack([np.zeros((3, 3)), lin.rotation_map(integrator, inertia, omega, h)])
        change = np.linalg.norm(B[:, 3:] - np.eye(3))
        if name is not None:
            check = CHECKS["rotation-map"]
            floor = 4 * np.finfo(float).eps * float(np.abs(omega).max()) / (EPS_RATES * change)
            err = float(np.linalg.norm(A - B) / change)
            outcomes.append(Outcome(dataclasses.replace(check, tolerance=check.tolerance + floor), err, 0.0))
            continue
        lam = np.linalg.eigvals(A[:, 3:])
        measured = float(np.abs(np.angle(lam)).max() / h)
        rate = (inertia[2] - inertia[0]) * float(omega[2]) / inertia[0]  # S1: body-frame precession rate
        expected = abs(lin.rotation_map_rate(integrator, rate, h))
        outcomes.append(Outcome(CHECKS["map-body-rate"], measured, expected))
    return outcomes


def _integrator(model: mujoco.MjModel) -> str:
    """The MJCF name of the model's integrator (`rigidbench.settings.INTEGRATORS`)."""
    return next(name for name, value in INTEGRATORS.items() if value == model.opt.integrator)


def _slope_inside(scenario: Scenario, prep: Any) -> bool:
    """Whether a +- da lies inside the amplitude's range (a census draws amplitudes down to its floor)."""
    a = float(prep.params["amplitude"])
    ranges = [scenario.param("amplitude").valid, prep.case.ranges.get("amplitude")]
    return (
        all(
            r is None or (not isinstance(r, Range)) or (a - AMPLITUDE_STEP in r and a + AMPLITUDE_STEP in r)
            for r in ranges
        )
        and abs(a) > 2 * AMPLITUDE_STEP
    )


def _slope(
    scenario: Scenario,
    prep: Any,
    overrides: Mapping[str, object] | None,
    settings: Settings | None,
    perturb: Callable[[mujoco.MjModel], None] | None,
    integrator: str,
) -> Outcome:
    """dT/da from the scenario's own period measurement at a +- da, against O1's centred difference over the same
    +- da: the same quotient, so no truncation lies between them (it differs from the exact dT/da,
    `linearised.period_amplitude_slope`, by (da^2 / 6) T''' / T', 1e-5 at 1 rad). The rollouts' period errors
    are smooth in a and largely cancel; the row's tolerance adds a bound on their difference: under RK4 twice its
    relative period error (omega h)^4 / 120 at the fastest rate, under the Euler family (no such bound at hand) the
    sum of the two rollouts' errors against O1, as the period check scores them."""
    from rigidbench.analytic.pendulum import pendulum_period

    a = abs(float(prep.params["amplitude"]))
    length, g = float(prep.prediction["_length_eq"]), float(prep.prediction["_g"])
    da = AMPLITUDE_STEP
    measured_periods, errors = [], []
    for sign in (1, -1):
        values = {**(overrides or {}), "amplitude": float(np.sign(prep.params["amplitude"])) * (a + sign * da)}
        run = scenario.run(prep.case.name, values, settings, perturb=perturb)
        period = next(o for o in run.outcomes if o.check.name == "period")
        measured_periods.append(period.measured)
        errors.append(abs(period.measured - period.expected))
    measured = (measured_periods[0] - measured_periods[1]) / (2 * da)
    expected = (pendulum_period(length, g, a + da) - pendulum_period(length, g, a - da)) / (2 * da)
    check = CHECKS["period-amplitude-slope"]
    if integrator == "RK4":  # RK4's relative period error (omega h)^4 / 120 at the fastest rate, at both ends
        h = float(prep.model.opt.timestep)
        rate = np.sqrt(g / length) * max(1.0, 2 * np.sin(a / 2))
        bound = 2 * (rate * h) ** 4 / 120 * pendulum_period(length, g, a) / (2 * da * abs(expected))
    else:  # the rollouts' own period errors against O1, whose difference their sum bounds
        bound = (errors[0] + errors[1]) / (2 * da * abs(expected))
    check = dataclasses.replace(check, tolerance=check.tolerance + bound)
    return Outcome(check, float(measured), float(expected))


# ---- planning -----------------------------------------------------------------------------------------------------


def plan(targets: Sequence[str]) -> list[tuple[Scenario, str]]:
    """(scenario, case) pairs of `targets` (``scenario`` or ``scenario:case``; default: every smooth scenario).

    Raises
    ------
    ValueError
        For an unknown scenario or case, or one without derivative checks.
    """
    pairs = []
    for target in targets or SCENARIOS:
        scenario, cases = registry.parse_target(target)
        if scenario.slug not in SCENARIOS:
            raise ValueError(f"no derivative checks for scenario '{scenario.slug}' (have: {', '.join(SCENARIOS)})")
        pairs += [(scenario, c) for c in cases]
    return pairs


def census(targets: Sequence[str], *, n: int, seed: int, settings: Settings | None) -> list[Any]:
    """The derivative checks at `n` random valid parameter sets per scenario, drawn as `rigidbench census` draws them
    (`rigidbench.census.plan`: the same ranges, regimes and seeds): its `Draw`\\ s, each settled (passed, failed,
    refused before differentiating, or crashed). A clean census has 0 failed and 0 crashed (`census.clean`).

    Raises
    ------
    ValueError
        For an unknown scenario or case, one without derivative checks, or n < 1.
    """
    from types import SimpleNamespace

    from rigidbench import census as cen
    from rigidbench.results import ERROR

    plan(targets)  # refuse what has no derivative checks
    draws, jobs = cen.plan(list(targets or SCENARIOS), n=n, seed=seed, settings=settings)
    rows: dict[str, list[dict[str, Any]]] = {}
    for job in jobs:
        try:
            run = run_case(job.scenario, job.case, job.overrides, settings)
            rows[job.key] = rows_of_run(run)
        except Exception as exc:  # noqa: BLE001 - a crash is what a census counts
            rows[job.key] = [{"status": ERROR, "message": f"{type(exc).__name__}: {exc}", "check": "-"}]
    cen.settle(draws, SimpleNamespace(rows=rows))
    return draws


def rows_of_run(run: CaseRun) -> list[dict[str, Any]]:
    """`rigidbench.results.rows_of` (imported here: the results module imports mujoco's version at load)."""
    from rigidbench.results import rows_of

    return rows_of(run)
