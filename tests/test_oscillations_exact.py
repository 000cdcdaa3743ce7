"""The exact companions of the linear-regime oscillation cases (issue 35): the reference against an independent
solution, and the companions catching a 1e-6 change of the simulated model that the linear checks let through."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rigidbench import harness, registry
from rigidbench.analytic import oscillations as osc
from rigidbench.analytic import oscillations_exact as exact
from rigidbench.contract import OutsideDomain
from rigidbench.envs import double_pendulum, pendulums
from rigidbench.power import Perturbation


def _newton_row(row: exact.SpringRow):
    """Second formulation of a spring row: forces as vectors in the x-z plane, torques r x F about each hinge (not
    the energy's gradient), integrated by DOP853 at rtol 1e-13."""

    def rhs(_t, y):
        n = len(row.mgl)
        th, w = y[:n], y[n:]
        d = row.height
        attach = np.stack([row.pivot_x - d * np.sin(th), -d * np.cos(th)], axis=-1)  # (x, z) of each attachment
        lever = attach - np.stack([row.pivot_x, np.zeros(n)], axis=-1)
        torque = -row.mgl * np.sin(th)
        for (i, j), k, rest in zip(row.pairs, row.stiffness, row.rest_length, strict=True):
            line = attach[j] - attach[i]
            length = np.linalg.norm(line)
            force_i = k * (length - rest) * line / length  # on i, towards j when stretched
            for body, force in ((i, force_i), (j, -force_i)):
                torque[body] += lever[body][1] * force[0] - lever[body][0] * force[1]  # (r x F)_y = r_z F_x - r_x F_z
        return np.concatenate([w, torque / row.inertia_pivot])

    return rhs


def _relative_double(model: exact.DoublePendulumModel):
    """Second formulation of the double pendulum: Lagrange's equations in MuJoCo's hinge coordinates (phi1 = th1, phi2
    = th2 - th1) through the Christoffel symbols of their mass matrix, integrated by DOP853 at rtol 1e-13."""
    (m1, m2), (c1, c2), (i1, i2), e1, g = model.mass, model.com, model.inertia_cm, model.hinge2, model.g

    def rhs(_t, y):
        p1, p2, v1, v2 = y
        c, s = np.cos(p2), np.sin(p2)
        mass = np.array(
            [
                [m1 * c1**2 + i1 + m2 * (e1**2 + c2**2 + 2 * e1 * c2 * c) + i2, m2 * (c2**2 + e1 * c2 * c) + i2],
                [m2 * (c2**2 + e1 * c2 * c) + i2, m2 * c2**2 + i2],
            ]
        )
        dmass = np.array([[-2 * m2 * e1 * c2 * s, -m2 * e1 * c2 * s], [-m2 * e1 * c2 * s, 0.0]])  # d mass / d phi2
        v = np.array([v1, v2])
        # C_i = sum_jk (dM_ij/dphi_k - 1/2 dM_jk/dphi_i) v_j v_k, only phi2 appearing in M
        coriolis = dmass @ v * v2 - np.array([0.0, 0.5 * v @ dmass @ v])
        grad = np.array(
            [(m1 * c1 + m2 * e1) * g * np.sin(p1) + m2 * g * c2 * np.sin(p1 + p2), m2 * g * c2 * np.sin(p1 + p2)]
        )
        return np.concatenate([v, np.linalg.solve(mass, -coriolis - grad)])

    return rhs


def _dop853(rhs, y0, t):
    sol = solve_ivp(rhs, (0.0, t[-1]), y0, method="DOP853", rtol=1e-13, atol=1e-19, dense_output=True)
    return sol.sol(t).T


@pytest.mark.parametrize(
    ("slug", "case", "seconds"), [("coupled-pendulums", "beats", 20.0), ("pendulum-chain", "end-released", 20.0)]
)
def test_spring_row_reference_equals_dop853_of_the_vector_newton_equations(slug, case, seconds):
    prep = harness.prepare(registry.get(slug), case)
    row = exact.SpringRow(**pendulums.spring_row(prep.model))
    modes, angles0 = prep.prediction["_modes"], prep.prediction["_angles0"]
    t = np.arange(round(seconds / prep.model.opt.timestep) + 1) * prep.model.opt.timestep
    ref = exact.motion(t, row.acceleration, modes, angles0)
    other = _dop853(_newton_row(row), np.concatenate([angles0, np.zeros_like(angles0)]), t)
    scale = np.abs(angles0).max()
    assert ref.method == "duhamel-picard" and ref.bound < 1e-12
    # DOP853 at rtol 1e-13 carries ~1e-13 of the amplitude per period; the companions' tolerances are >= 2.7e-11.
    assert np.abs(ref.angles - other[:, : len(angles0)]).max() / scale < 3e-12
    assert np.abs(ref.rates - other[:, len(angles0) :]).max() / (scale * modes.frequencies.max()) < 3e-12


@pytest.mark.parametrize("case", ["released", "unequal"])
def test_double_pendulum_reference_equals_dop853_of_lagrange_in_hinge_coordinates(case):
    prep = harness.prepare(registry.get("double-pendulum"), case)
    model = double_pendulum.exact_model(prep.model)
    modes, angles0 = prep.prediction["_modes"], prep.prediction["_angles0"]
    t = np.arange(round(20.0 / prep.model.opt.timestep) + 1) * prep.model.opt.timestep
    ref = exact.motion(t, model.acceleration, modes, angles0)
    other = _dop853(_relative_double(model), [angles0[0], angles0[1] - angles0[0], 0.0, 0.0], t)
    absolute = np.stack([other[:, 0], other[:, 0] + other[:, 1]], axis=-1)
    assert ref.bound < 1e-12
    assert np.abs(ref.angles - absolute).max() / np.abs(angles0).max() < 3e-12


def test_reference_gives_nan_and_an_infinite_bound_beyond_the_linear_regime():
    modes = osc.coupled_modes(1.0, 9.81, 1.0, 0.5)
    row = exact.SpringRow(
        np.ones(2), np.full(2, 9.81), np.array([-0.25, 0.25]), 0.5, [(0, 1)], np.ones(1), np.full(1, 0.5)
    )
    ref = exact.motion(np.arange(20001) * 2e-3, row.acceleration, modes, np.array([1.0, 0.0]))
    assert np.isnan(ref.angles).all() and ref.bound == np.inf


def test_cumulative_integral_is_sixth_order():
    def error(h: float, order: int) -> float:
        t = np.arange(round(20 / h) + 1) * h
        return float(np.abs(exact.cumulative_integral(np.cos(3 * t), h, order=order) - np.sin(3 * t) / 3).max())

    assert 50 < error(0.05, 6) / error(0.025, 6) < 80  # 2^6 = 64
    assert 12 < error(0.05, 4) / error(0.025, 4) < 20  # 2^4 = 16


# One 1e-6 change of a declared quantity each, and the companion that must catch it; the linear check of the same
# quantity lets it through (its tolerance is the neglected amplitude^2 terms').
CATCHES = [
    ("coupled-pendulums", "beats", "g", "omega-in-phase-exact", "omega-in-phase"),
    ("coupled-pendulums", "beats", "spring-k", "omega-anti-phase-exact", "omega-anti-phase"),
    ("coupled-pendulums", "beats", "mass:pendulum1", "beat-waveform-exact", "beat-waveform"),
    ("pendulum-chain", "end-released", "g", "mode-frequencies-exact", "mode-frequencies"),
    ("pendulum-chain", "end-released", "spring-k", "mode-frequencies-exact", "mode-frequencies"),
    ("pendulum-chain", "end-released", "mass:pendulum1", "mode-frequencies-exact", "mode-frequencies"),
    ("double-pendulum", "released", "g", "omega-fast-exact", "omega-fast"),
    ("double-pendulum", "released", "mass:pendulum1", "omega-fast-exact", "omega-fast"),
    ("double-pendulum", "released", "mass:pendulum2", "omega-slow-exact", "omega-slow"),
]


@pytest.mark.parametrize(("slug", "case", "quantity", "companion", "linear"), CATCHES)
def test_exact_companion_catches_a_1e_6_change_the_linear_check_lets_through(slug, case, quantity, companion, linear):
    run = harness.run(registry.get(slug), case, perturb=Perturbation(quantity, 1e-6))
    outcome = {o.check.name: o for o in run.outcomes}
    assert not outcome[companion].passed, (companion, outcome[companion].error / outcome[companion].check.tolerance)
    assert outcome[linear].passed


def test_companions_pass_unperturbed_with_the_integrators_error():
    """RK4's frequency error (omega dt)^4 / 120 is what the frequency companion measures (the linear check cannot
    see it: its tolerance is 1e6 times larger)."""
    run = harness.run(registry.get("double-pendulum"), "fast-mode", keep_trajectory=True)
    outcome = {o.check.name: o for o in run.outcomes}
    omega = run.prediction["omega-fast"]
    eps4 = pendulums.rk4_frequency_error(omega, run.settings["timestep"])
    assert all(o.passed for o in run.outcomes)
    assert outcome["omega-fast-exact"].measured == pytest.approx(-eps4, rel=0.05)


@pytest.mark.parametrize(("case", "amplitude2"), [("in-phase", -0.001), ("anti-phase", 0.001), ("in-phase", 0.0)])
def test_symmetric_cases_refuse_a_second_amplitude_off_the_modes_shape(case, amplitude2):
    scenario = registry.get("coupled-pendulums")
    with pytest.raises(OutsideDomain, match=f"outside the regime of case '{case}'"):
        scenario.prepare(case, {"amplitude1": 0.001, "amplitude2": amplitude2})
    assert scenario.prepare(case, {"amplitude1": 0.001}).params["amplitude2"] == (
        0.001 if case == "in-phase" else -0.001
    )
