"""MuJoCo against the Coulomb closed forms (`rigidbench.envs.rutherford`, docs/theory.md C1-C4, C6, C7, C9): every case
under the reference settings, RK4's order on the forces route, the finite-distance correction, the beam as one
model, and the inputs refused before simulating."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigidbench import forces
from rigidbench.analytic import coulomb
from rigidbench.envs.rutherford import BLOCK, Rutherford
from rigidbench.scenario import OutsideDomain
from rigidbench.settings import Settings

SCENARIO = Rutherford()


@pytest.mark.parametrize("case", [c.name for c in SCENARIO.cases])
def test_every_case_passes_under_the_reference_settings(case):
    run = SCENARIO.run(case)
    assert run.diverged_at is None
    failed = [(o.check.name, o.measured, o.expected, o.error) for o in run.outcomes if not o.passed]
    assert not failed, failed
    assert run.outcomes


def test_prediction_reads_the_compiled_model_and_the_simulated_state():
    """Masses and k come back from the model; b and v from the initial state's invariants (not the request)."""
    prep = SCENARIO.prepare("heavy-target", {"m1": 0.5, "k": 2e-3})
    pr = prep.prediction["_pairs"]
    assert pr["m1"] == prep.model.body("projectile").mass[0] == 0.5
    assert pr["m2"] == pytest.approx(10.0) and pr["k"] == 2e-3
    d = coulomb.distance_scale(2e-3, 0.5 * 10 / 10.5, 1.0)
    assert prep.prediction["_distance"] == pytest.approx(d, rel=1e-12)
    assert prep.prediction["_b"][0] == pytest.approx(2 * d, rel=1e-10)  # the case's b = 2 D, read back


def test_deflection_error_is_fourth_order_in_the_timestep():
    """The force is added inside mj_passive, at every RK4 stage: halving the step cuts the CM-angle error 16x."""
    prep = SCENARIO.prepare("equal-mass")
    errors = []
    for factor in (2.0, 1.0):
        settings = Settings(timestep=factor * prep.model.opt.timestep)
        run = SCENARIO.run("equal-mass", settings=settings)
        errors.append(next(o.error for o in run.outcomes if o.check.name == "cm-angle"))
    assert np.log2(errors[0] / errors[1]) == pytest.approx(4.0, abs=0.3), errors


def test_the_finite_distance_correction_is_needed():
    """Uncorrected, the angle between the start and end velocities misses theta by 2 delta(R) ~ b D / R^2, far more
    than the check's tolerance; against the exact orbit at R it matches to RK4's error."""
    run = SCENARIO.run("equal-mass", keep_trajectory=True)
    raw = next(o for o in run.outcomes if o.check.name == "finite-distance-deflection")
    theta = run.prediction["cm-angle"]
    lag = run.prediction["_lag"]
    assert abs(raw.measured - theta) == pytest.approx(2 * lag, rel=1e-3)
    assert 2 * lag > 100 * raw.check.tolerance and raw.passed


def test_beam_is_one_model_of_independent_pairs():
    """n pairs in one model, each its own declared pair (vectorised free-body path); the beam's deflections all match
    tan(theta/2) = D / b, and its impact parameters fill the disc of radius D cot(theta_min / 2)."""
    prep = SCENARIO.prepare("cross-section", {"n": 200})
    law = forces.inverse_square(prep.model)
    assert len(law.first) == 200 and law.free_dofs is not None
    b = prep.prediction["_b"]
    d = prep.prediction["_distance"]
    radius = coulomb.beam_radius(float(prep.model.numeric("min_angle").data[0]), d)
    assert b.max() <= radius and b.min() >= 0 and b.max() > 0.9 * radius
    run = SCENARIO.run("cross-section", {"n": 200})
    assert all(o.passed for o in run.outcomes), [(o.check.name, o.measured) for o in run.outcomes]


def test_a_beam_larger_than_a_block_runs_in_blocks_of_one_model():
    """n = 620 > BLOCK: one compiled model of BLOCK pairs, stepped twice from two draws; 620 collisions counted."""
    run = SCENARIO.run("cross-section", {"n": 620}, keep_trajectory=True)
    blocks = run.trajectory.blocks
    assert [count for _, count in blocks] == [BLOCK, 620 - BLOCK]
    assert not np.array_equal(blocks[0][0].qpos[0], blocks[1][0].qpos[0])  # each block its own impact points
    assert all(o.passed for o in run.outcomes), [(o.check.name, o.measured) for o in run.outcomes]


def test_a_wrong_cross_section_fails_the_goodness_of_fit():
    """The test can fail: a target 30 % heavier in the simulated model (D shrinks, every angle with it) is caught."""

    def heavier(model: mujoco.MjModel) -> None:
        law = forces.inverse_square(model)
        model.body_mass[law.first] *= 1.3
        mujoco.mj_setConst(model, mujoco.MjData(model))  # MuJoCo 4 caches the joint-space inertia (dof_M0)

    run = SCENARIO.run("cross-section", perturb=heavier)
    failed = {o.check.name for o in run.outcomes if not o.passed}
    assert "beam-cm-angle" in failed and "cm-distribution-pvalue" in failed


def test_lab_orbit_drifts_as_log_t_and_the_cm_orbit_does_not():
    """C9: the fitted ln t coefficient of the projectile's LAB offset is C = -(m2/M) D sin(theta - psi) (nonzero);
    the CM-frame offset's is zero, both to their tolerances."""
    run = SCENARIO.run("lab-orbit")
    out = {o.check.name: o for o in run.outcomes}
    assert out["lab-log-drift"].passed and out["cm-log-drift"].passed
    assert abs(out["lab-log-drift"].measured) > 50 * out["lab-log-drift"].check.tolerance
    assert abs(out["cm-log-drift"].measured) < 1e-3 * abs(out["lab-log-drift"].measured)


@pytest.mark.parametrize(
    ("case", "overrides", "match"),
    [
        ("equal-mass", {"k": -1.0}, "outside the valid range"),
        ("equal-mass", {"k": 1e3}, "D = k / \\(mu u\\^2\\)"),
        ("head-on", {"b": 10.0}, "100 D"),
        ("equal-mass", {"n": 5}, "regime of case 'equal-mass'"),
        ("cross-section", {"n": 10}, "regime of case 'cross-section'"),
        ("lab-orbit", {"separation": 50.0}, "regime of case 'lab-orbit'"),
        ("equal-mass", {"min_angle": 0.01}, "outside the valid range"),
    ],
)
def test_bad_inputs_are_refused_before_simulating(case, overrides, match):
    with pytest.raises(ValueError, match=match):
        SCENARIO.resolve(SCENARIO.case(case), overrides)


def test_an_equal_mass_projectile_stopped_head_on_is_outside_the_domain():
    with pytest.raises(OutsideDomain, match="projectile-at-rest"):
        SCENARIO.resolve(SCENARIO.case("equal-mass"), {"b": 0.0})


def test_power_theory_sensitivity_finds_a_quantity_in_each_cases_own_model(monkeypatch):
    """`rigidbench power` lists the quantities of every case; rutherford's cases have different bodies (a beam of
    pairs, a probe pair, one pair), so the theory's sensitivity perturbs each case's model by the quantity's name,
    and a case without it is left as it is (it once indexed a body the single-pair models do not have)."""
    from rigidbench import power, registry

    monkeypatch.setattr(power, "DELTAS", (1e-2,))
    scenario = registry.get("rutherford")
    names = {q.name for sc, q in power.plan(["rutherford"], None) if sc is scenario}
    assert {"mass:projectile", "mass:target", "mass:target1"} <= names
    quantity = next(q for sc, q in power.plan(["rutherford"], None) if q.name == "mass:target1")
    assert power.theory_sensitivity(scenario, quantity, None) in (None, 1e-2)


def test_a_beam_env_follows_its_first_pairs_orbit_in_that_pairs_plane():
    """A beam's env is scored on its first pair, which comes at a random azimuth about the beam: the theory is that
    pair's orbit turned into its plane, so the textbook problem (zero action) deviates by RK4's error only (it was
    0.43 r_min on the first step when the theory stayed in the x-y plane)."""
    import gymnasium as gym

    env = gym.make("rigidbench/Rutherford-v0", case="cross-section", params={"n": 100}).unwrapped
    env.reset(seed=0)
    assert abs(env.prediction["_azimuth"]) > 0.1  # this seed's first pair is well out of the x-y plane
    deviations = []
    for _ in range(30):
        _, _, terminated, truncated, info = env.step(np.zeros(3, dtype=np.float32))
        deviations.append(info["deviation"])
        if terminated or truncated:
            break
    assert max(deviations) < 1e-7  # the single collisions' orbit checks hold 1e-7 rad; here 7.5e-10 r_min
