"""The hard-spheres and cross-section scenarios in MuJoCo: reference passes, bad input, env, batch determinism."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from rigidbench import registry
from rigidbench.analytic import scattering
from rigidbench.cli import main
from rigidbench.contact import contact_spring
from rigidbench.envs.cross_section import CrossSection, goodness_of_fit
from rigidbench.envs.hard_spheres import HardSpheres
from rigidbench.settings import profile
from rigidbench.simulate import final_states

HARD = registry.get("hard-spheres")


def _failures(run):
    return [(o.check.name, o.measured, o.expected, o.error) for o in run.outcomes if not o.passed]


@pytest.mark.parametrize("case", [c.name for c in HardSpheres.cases])
def test_every_hard_spheres_case_passes_under_reference(case):
    run = HARD.run(case)
    assert run.diverged_at is None
    assert run.outcomes and not _failures(run)


def test_lab_angles_match_soft_prediction_to_1e_4_and_hard_value_within_the_k_bound():
    """The soft prediction (C8) to <= 1e-4 rad; the hard one (C5) only to the k^-1/2 shift, which is resolved."""
    run = HARD.run("heavy-projectile", keep_trajectory=True)
    by = {o.check.name: o for o in run.outcomes}
    for name in ("projectile-lab-angle", "target-lab-angle", "cm-angle"):
        assert by[name].error <= 1e-4
    # The soft shift is real: the simulation differs from the hard sphere by far more than from the soft sphere.
    assert by["cm-angle-hard"].error > 100 * by["cm-angle"].error
    assert by["soft-shift-exponent"].measured == pytest.approx(0.5, abs=0.02)


def test_heavy_projectile_at_b_006_passes_from_the_cli(capsys):
    """The command from the issue: m1/m2 = 3, b = 0.06 m > b0 = 0.0577 m (stretch branch) for a = 0.1 m."""
    assert main(["run", "hard-spheres", "--set", "m1=3", "--set", "m2=1", "--set", "b=0.06", "--quiet"]) == 0
    params = HARD.resolve(HARD.case("heavy-projectile"), {"m1": 3.0, "m2": 1.0, "b": 0.06})
    prediction = HARD.predict(HARD.build(params), HARD.start(HARD.build(params)))
    assert prediction["_branch"] == "stretch"
    stretch, short = prediction["_branches"]["stretch"], prediction["_branches"]["short"]
    assert short is not None and stretch > short  # two LAB speeds at this psi (eq 9.53)


@pytest.mark.parametrize(
    ("setting", "name"),
    [("b=-0.1", "'b'"), ("m1=0", "'m1'"), ("stiffness=1e14", "'stiffness'"), ("b=0.2", "'b'"), ("m2=-1", "'m2'")],
)
def test_bad_input_exits_2_naming_the_parameter(setting, name, capsys):
    assert main(["run", "hard-spheres", "--set", setting, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert name in err and "\n" == err[-1] and err.count("\n") == 1


def test_cross_section_bad_input_exits_2(capsys):
    assert main(["run", "cross-section", "--set", "n=10.5", "--quiet"]) == 2
    assert "'n'" in capsys.readouterr().err


def test_mujoco_default_collision_is_far_from_elastic():
    """A finding, not a pass: MuJoCo's default contact (solref 0.02 1) loses most of the normal velocity."""
    run = HARD.run("head-on", settings=profile("mujoco-default"))
    by = {o.check.name: o for o in run.outcomes}
    assert by["restitution"].measured < 0.5
    assert not by["restitution"].passed and not by["energy"].passed
    assert by["momentum"].passed  # equal and opposite forces still


def test_contact_spring_reads_both_solref_formats():
    direct = contact_spring((-1e8, 0.0), 1e-6)
    assert direct.direct and direct.elastic and direct.stiffness == 1e8 and direct.restitution == 1.0
    standard = contact_spring((0.02, 1.0), 0.002)
    assert not standard.direct and standard.stiffness == pytest.approx(2500) and standard.restitution == 0.0
    assert contact_spring((0.001, 1.0), 0.002).stiffness == pytest.approx(1 / 0.004**2)  # MuJoCo's 2 dt clamp


def test_env_passes_check_env_and_renders():
    env = gym.make("rigidbench/HardSpheres-v0", render_mode="rgb_array", width=64, height=48)
    check_env(env.unwrapped, skip_render_check=True)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (48, 64, 3) and frame.dtype == np.uint8 and frame.std() > 0
    env.close()


def test_env_options_choose_impact_parameter_masses_and_radii_and_zero_action_tracks_theory():
    env = gym.make("rigidbench/HardSpheres-v0")
    params = {"b": 0.03, "m1": 2.0, "m2": 0.5, "r1": 0.04, "r2": 0.07}
    obs, info = env.reset(options={"params": params})
    assert all(info["params"][k] == pytest.approx(v) for k, v in params.items())
    assert obs[1] == pytest.approx(0.03)  # projectile y = b
    worst = 0.0
    while True:
        obs, reward, terminated, truncated, info = env.step(np.zeros(3))
        worst = max(worst, info["deviation"])
        if terminated or truncated:
            break
    assert not terminated and worst < 1e-6  # relative position vs the soft-contact ODE, in units of a
    env.close()


def test_batch_results_identical_across_thread_counts_and_chunks():
    scenario = CrossSection()
    params = scenario.resolve(scenario.case("heavy-projectile"), {"n": 300})
    model = scenario.build(params)
    data = scenario.start(model)
    states0, _ = scenario.beam(model, data)
    nstep = scenario._nstep(model)
    one, d1 = final_states(model, states0, nstep, nthread=1)
    two, d2 = final_states(model, states0, nstep, nthread=2, chunk=7)
    assert not d1.any() and not d2.any()
    np.testing.assert_array_equal(one, two)


def test_batch_matches_single_rollouts():
    """The batched fast path against the plain single-trajectory path, collision by collision."""
    scenario = CrossSection()
    model = scenario.build(scenario.resolve(scenario.case("equal-mass"), {"n": 100}))
    data = scenario.start(model)
    states0, _ = scenario.beam(model, data)
    nstep = scenario._nstep(model)
    batch, _ = final_states(model, states0, nstep, nthread=2)
    for i in (0, 17, 99):
        single, _ = final_states(model, states0[i : i + 1], nstep, nthread=1)
        np.testing.assert_array_equal(batch[i], single[0])


@pytest.mark.parametrize("case", [c.name for c in CrossSection.cases])
def test_every_cross_section_case_passes_under_reference(case):
    run = registry.get("cross-section").run(case)
    assert run.diverged_at is None
    assert run.outcomes and not _failures(run)


def test_goodness_of_fit_rejects_the_wrong_mass_ratio():
    """The distribution tests can fail: heavy-projectile LAB angles against light-projectile theory."""
    scenario = CrossSection()
    model = scenario.build(scenario.resolve(scenario.case("heavy-projectile"), {"n": 1000}))
    data = scenario.start(model)
    beam = scenario.simulate(model, data, scenario.predict(model, data)["_duration"])
    out = HardSpheres().outgoing(model, beam.qpos, beam.qvel, np.array([1.0, 0.0, 0.0]))
    hit = np.linalg.norm(out["v2"], axis=1) > 0
    edges = np.linspace(0, np.arcsin(1 / 3), 21)
    assert goodness_of_fit(out["psi"][hit], edges, scattering.lab_angle_probabilities(edges, 0.1, 3.0)) > 1e-3
    assert goodness_of_fit(out["psi"][hit], edges, scattering.lab_angle_probabilities(edges, 0.1, 2.0)) < 1e-6


@pytest.mark.slow
def test_thorough_cross_section_passes_with_1e5_collisions():
    run = registry.get("cross-section").run("heavy-projectile", settings=profile("thorough"))
    assert run.params["n"] >= 1e5
    assert run.outcomes and not _failures(run)


def test_elastic_contact_from_a_target_penetration_and_its_refusal():
    from rigidbench.contact import elastic_contact

    contact = elastic_contact(timestep=5e-7, penetration=1e-4, approach_speed=1.0)
    assert contact.stiffness == pytest.approx(1e8)
    assert contact.steps(5e-7) == pytest.approx(np.pi / (1e4 * 5e-7))
    assert contact.solref == (-1e8, 0.0)
    with pytest.raises(ValueError, match="too high for timestep"):
        elastic_contact(timestep=5e-7, stiffness=1e14)


@pytest.mark.slow
def test_soft_shift_of_the_simulation_scales_as_k_to_minus_half_over_three_decades():
    """Sweep: theta_hard - theta_sim against k from 1e6 to 1e9 (equal masses, b = a/2): the fitted exponent is
    -1/2, and each shift matches the soft prediction (C8) far better than the hard one (C5)."""
    ks = np.array([1e6, 1e7, 1e8, 1e9])
    shifts = []
    for k in ks:
        run = HARD.run("equal-mass", {"stiffness": k})
        by = {o.check.name: o for o in run.outcomes}
        assert by["cm-angle"].passed
        shifts.append(by["cm-angle-hard"].expected - by["cm-angle-hard"].measured)
    slope = np.polyfit(np.log(ks), np.log(shifts), 1)[0]
    assert slope == pytest.approx(-0.5, abs=0.01)


@pytest.mark.parametrize(("steps", "bound"), [(20.0, 6e-6), (20.9, 1.5e-4)])
def test_beam_angles_match_the_soft_sphere_prediction_when_the_contact_ends_on_a_step(steps, bound):
    """The cross-section's reference step is chosen for cost, 20 RK4 steps per contact, a whole number so that
    the force's kink at contact exit falls on a step boundary: its CM angles match the soft-sphere angle C8 to
    the ~5e-6 rad the model file claims (measured 4.3e-6 over 3000 collisions). The same step count made
    fractional leaves the kink inside a step, and the error is ~20x larger (measured 8.4e-5)."""
    scenario = CrossSection()
    model = scenario.build(scenario.resolve(scenario.case("heavy-projectile"), {"n": 300, "contact_steps": steps}))
    data = scenario.start(model)
    states0, b = scenario.beam(model, data)
    states, diverged = final_states(model, states0, scenario._nstep(model), nthread=1)
    assert not diverged.any()
    nq, nv = model.nq, model.nv
    out = HardSpheres().outgoing(model, states[:, 1 : 1 + nq], states[:, 1 + nq : 1 + nq + nv], np.array([1.0, 0, 0]))
    _, _, a = HardSpheres._geometry(model)
    k = HardSpheres._spring(model).stiffness
    hit = b < a
    assert hit.sum() > 150
    soft = np.array([scattering.soft_sphere_cm_angle(bi, a, k, 1.0) for bi in b[hit]])
    error = np.abs(out["theta"][hit] - soft).max()
    assert bound / 3 < error <= bound


def test_lab_angles_just_past_psi_max_count_in_the_top_bin_but_no_further():
    """An energy error of 1e-7 moves psi_max; `limit_slack` (from a 1e-5 energy budget) absorbs that, not more."""
    from rigidbench.envs.cross_section import limit_slack

    x = 3.0
    psi_max = scattering.max_lab_angle(x)
    edges = np.linspace(0.0, psi_max, 21)
    probabilities = scattering.lab_angle_probabilities(edges, 0.1, x)
    rng = np.random.default_rng(0)
    samples = np.interp(rng.random(20000), np.concatenate([[0.0], np.cumsum(probabilities)]), edges)
    slack = limit_slack(psi_max, x)
    assert 5e-6 < slack < 1e-5 and limit_slack(np.pi / 2, 1.0) == 0.0
    past = samples.copy()
    past[:30] = psi_max + 2.4e-6  # the worst overshoot measured (x = 3, k = 1e8, 20 steps per contact)
    assert goodness_of_fit(past, edges, probabilities) == 0.0  # strictly, one sample past the limit fails
    assert goodness_of_fit(past, edges, probabilities, slack=slack) > 1e-3
    past[:30] = psi_max + 2 * slack
    assert goodness_of_fit(past, edges, probabilities, slack=slack) == 0.0


# ---- the beam in blocks: shards that merge exactly (issue 17) ----------------------------------------------------


def _small_blocks(monkeypatch, n=750, block=300, case="heavy-projectile"):
    """A beam of `n` collisions cut into blocks of `block` (so that several blocks stay fast): model, data, nstep."""
    from rigidbench.envs import cross_section

    monkeypatch.setattr(cross_section, "BLOCK", block)
    scenario = CrossSection()
    model = scenario.build(scenario.resolve(scenario.case(case), {"n": n}))
    data = scenario.start(model)
    return scenario, model, data, scenario._nstep(model)


def test_a_beam_of_at_most_one_block_is_the_single_generator_draw_it_always_was():
    """Block 0 is drawn by default_rng(seed), so a beam of n <= BLOCK has the impact points (and hence the results)
    it had before the beam was cut into blocks."""
    from rigidbench.envs.cross_section import BLOCK

    scenario = CrossSection()
    model = scenario.build(scenario.resolve(scenario.case("equal-mass"), {"n": BLOCK}))
    data = scenario.start(model)
    _, b = scenario.beam(model, data)
    _, _, a = HardSpheres._geometry(model)
    seed = int(model.numeric("seed").data[0])
    radius = a * (1 + float(model.numeric("margin").data[0]))
    np.testing.assert_array_equal(b, radius * np.sqrt(np.random.default_rng(seed).random(BLOCK)))


def test_block_tallies_add_up_exactly_to_the_tally_of_the_whole_beam_in_one_batch(monkeypatch):
    """The merge is exact: n = 2.5 blocks stepped in one batch and counted once gives the same hits and histograms
    as its blocks simulated and counted one by one (`tally_block`, as shards run) and added, and hence the same
    p-values and total cross section."""
    from rigidbench.envs.cross_section import Beam, BeamShard, Tally, tally, tally_block
    from rigidbench.simulate import get_state

    scenario, model, data, nstep = _small_blocks(monkeypatch)
    assert scenario.blocks(model) == 3
    states0, b = scenario.beam(model, data)
    assert len(b) == 750 and len(np.unique(b)) == 750  # no block repeats another's draw
    states, diverged = final_states(model, states0, nstep, nthread=2)
    nq, nv = model.nq, model.nv
    whole = tally(model, states[:, 1 : 1 + nq], states[:, 1 + nq : 1 + nq + nv], diverged)
    parts = [tally_block(BeamShard(model, get_state(model, data), j, nstep, 1))[0] for j in range(3)]
    assert [p.collisions for p in parts] == [300, 300, 150]
    merged = parts[0] + parts[1] + parts[2]
    assert merged == whole and whole.hits > 300 and whole.diverged == 0
    for k in whole.counts:
        np.testing.assert_array_equal(merged.counts[k], whole.counts[k])
    prediction = scenario.predict(model, data)
    beam = scenario.simulate(model, data, prediction["_duration"])  # the scenario's own path: shards, merged
    assert isinstance(beam.tally, Tally) and beam.tally == whole
    one_batch = Beam(beam.time, whole, beam.qpos, beam.qvel, beam.impact, None, 0)
    assert scenario.measure(model, beam, prediction) == scenario.measure(model, one_batch, prediction)


def test_the_result_does_not_depend_on_where_or_in_what_order_the_shards_run(monkeypatch):
    """Shards mapped backwards, or on a pool of threads finishing in any order, give the measured values of shards
    run here in turn, bit for bit."""
    from rigidbench import shards
    from rigidbench.runner import Threads

    scenario, *_ = _small_blocks(monkeypatch, n=1000, block=250)

    def backwards(fn, calls):
        for i in reversed(range(len(calls))):
            yield i, fn(*calls[i])

    def measured(run):
        return [(o.check.name, o.measured) for o in run.outcomes]

    here = measured(scenario.run("heavy-projectile", {"n": 1000}))
    with shards.use(backwards):
        assert measured(scenario.run("heavy-projectile", {"n": 1000})) == here
    with shards.use(Threads(3).map):
        assert measured(scenario.run("heavy-projectile", {"n": 1000})) == here
