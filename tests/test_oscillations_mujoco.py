"""The pendulum family in MuJoCo against theory (docs/theory.md O1-O7): every case under the reference profile, the
issue's parameter sets through the CLI, what MuJoCo's default integrator does, bad input, and the measurement
methods themselves (each tolerance rests on one)."""

import mujoco
import numpy as np
import pytest

from rigidbench import cli, registry
from rigidbench.analytic import oscillations as osc
from rigidbench.envs import pendulums
from rigidbench.envs.coupled_pendulums import transfer_time
from rigidbench.scenario import OutsideDomain
from rigidbench.settings import profile

G = 9.81
FAMILY = ("pendulum", "coupled-pendulums", "pendulum-chain", "double-pendulum")
CASES = [f"{slug}:{c.name}" for slug in FAMILY for c in registry.get(slug).cases]


@pytest.mark.parametrize("family_case", CASES)
def test_every_case_matches_theory_under_reference(family_case):
    scenario, (case,) = registry.parse_target(family_case)
    run = scenario.run(case)
    assert run.diverged_at is None
    failed = [(o.check.name, o.measured, o.expected, o.error) for o in run.outcomes if not o.passed]
    assert not failed, failed
    # The issue's bar: normal-mode frequencies agree to <= 1e-6 relative (the checks' tolerance; they pass).
    for o in run.outcomes:
        if o.check.name.startswith(("omega-", "mode-frequencies")):
            assert o.check.tolerance <= 1e-6 and o.error <= 1e-6, o.check.name


def test_beats_at_k_3p7_and_d_0p42_pass_through_the_cli(capsys):
    assert cli.main(["run", "coupled-pendulums:beats", "--set", "k=3.7", "--set", "d=0.42", "--quiet"]) == 0
    assert "transfer-time" in capsys.readouterr().out


def test_beats_prediction_uses_the_compiled_k_and_d():
    run = registry.get("coupled-pendulums").run("beats", {"k": 3.7, "d": 0.42}, keep_trajectory=True)
    assert run.params["k"] == 3.7 and run.params["d"] == 0.42
    i_o = 1.0 + 1e-9  # m l^2 + the bob's 1e-9 kg m^2, as compiled
    expected = np.sqrt((G * 1.0 + 2 * 3.7 * 0.42**2) / i_o)
    assert run.prediction["omega-anti-phase"] == pytest.approx(expected, rel=1e-14)


def test_chain_of_7_passes_through_the_cli():
    assert cli.main(["run", "pendulum-chain", "--set", "n=7", "--quiet"]) == 0


def test_chain_is_built_through_mjspec_with_n_bodies_and_relaxed_horizontal_springs():
    scenario = registry.get("pendulum-chain")
    params = scenario.resolve(scenario.cases[0], {"n": 7, "d": 0.3})
    model = scenario.build(params)
    assert model.njnt == 7 and model.ntendon == 6
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)  # at qpos0, every pendulum hanging
    np.testing.assert_allclose(data.ten_length, model.tendon_lengthspring[:, 0], rtol=0, atol=1e-15)
    sites = [model.site(f"spring{i}").id for i in range(1, 8)]
    np.testing.assert_allclose(data.site_xpos[sites, 2], -0.3, rtol=1e-15)
    assert scenario.read_params(model)["n"] == 7


@pytest.mark.parametrize(
    "args, named",
    [
        (["pendulum-chain", "--set", "n=0"], "'n' = 0 is outside the valid range integers in [2, 40]"),
        (["pendulum-chain", "--set", "n=2.5"], "'n' = 2.5"),
        (
            ["coupled-pendulums", "--set", "d=1.5"],
            "'d' = 1.5 m is outside its range [1e-3 length, length] = [0.001, 1] m",
        ),
        (["pendulum-chain", "--set", "d=1.2"], "'d' = 1.2 m"),
        (["coupled-pendulums", "--set", "k=-1"], "'k' = -1 N/m is outside the valid range [1e-15, 1e+15] N/m"),
        (["pendulum", "--set", "length=0"], "'length' = 0 m is outside the valid range [0.001, 100] m"),
        (["pendulum", "--set", "amplitude=3.5"], "'amplitude' = 3.5 rad"),
        (["double-pendulum", "--set", "mass2=0"], "'mass2' = 0 kg"),
    ],
)
def test_bad_input_exits_2_naming_the_parameter_value_and_range(args, named, capsys):
    assert cli.main(["run", *args]) == 2
    err = capsys.readouterr().err
    assert named in err and err.count("\n") == 1


# ---- what MuJoCo's default integrator does ------------------------------------------------------------------


def test_default_euler_at_2ms_raises_the_frequency_by_omega_dt_squared_over_24():
    """MuJoCo's Euler is semi-implicit (symplectic): on an oscillator it keeps the amplitude but turns faster by
    (omega dt)^2 / 24. At 2 ms that is 1.6e-6 for a 1 m pendulum: above the 1e-6 tolerance, so the check fails."""
    run = registry.get("pendulum").run("small-amplitude", settings=profile("mujoco-default"))
    period = next(o for o in run.outcomes if o.check.name == "period")
    omega_dt = 2 * np.pi / period.expected * 2e-3
    assert 1 - period.measured / period.expected == pytest.approx(omega_dt**2 / 24, rel=0.05)
    assert not period.passed


def test_default_euler_energy_error_oscillates_at_omega_dt_over_2_and_does_not_drift():
    """Semi-implicit Euler conserves a shadow energy: the true energy swings by ~omega dt / 2 = 3e-3 of itself
    (the energy checks fail by 5 orders of magnitude) but does not grow over 400 s, and the turning angle holds."""
    run = registry.get("coupled-pendulums").run(
        "weak-coupling", settings=profile("mujoco-default"), keep_trajectory=True
    )
    row = {o.check.name: o for o in run.outcomes}
    omega_dt = row["omega-in-phase"].expected * 2e-3
    assert row["energy-drift"].measured == pytest.approx(omega_dt / 2, rel=0.1)
    assert not row["energy-drift"].passed
    model = registry.get("coupled-pendulums").build(run.params, profile("mujoco-default"))
    traj = run.trajectory
    energy = pendulums.row_energy(model, traj.qpos, traj.qvel) / run.prediction["_energy_scale"]
    first, last = np.array_split(energy, 10)[0], np.array_split(energy, 10)[-1]
    assert abs(last.mean() - first.mean()) < 0.1 * omega_dt  # bounded, not secular


# ---- the measurement methods ---------------------------------------------------------------------------------


@pytest.mark.parametrize("k, d", [(1.0, 0.5), (3.7, 0.42), (0.25, 0.5)])
def test_transfer_time_estimator_recovers_the_closed_form_within_1e_5(k, d):
    """The peak-parabola estimator on the exact O4 signal, sampled as MuJoCo's is: its own error is <= 1e-5, a
    tenth of the transfer-time tolerance, at these couplings."""
    beats = osc.Beats(1e-3, *osc.coupled_frequencies(1.0, G, k, d))
    t = np.arange(round(2.5 * beats.transfer_time / 1e-3) + 1) * 1e-3
    w0, wb = beats.carrier, beats.beat
    rate2 = beats.amplitude * (w0 * np.cos(w0 * t) * np.sin(wb * t) + wb * np.sin(w0 * t) * np.cos(wb * t))
    measured = transfer_time(t, beats.angles(t)[:, 1], rate2, before=2 * beats.transfer_time)
    assert measured == pytest.approx(beats.transfer_time, rel=1e-5)


def test_transfer_time_estimator_errs_by_at_most_2p8e_5_over_the_beats_regime():
    """Over kappa = k d^2 / (m g l) in [2e-3, 0.1] (the beats cases' regime; at kappa = 0.15 too few carrier peaks
    per beat leave it undefined), on the exact O4 signal at the derived step: <= 2.8e-5, under the 1e-4 tolerance
    with the regime's 2.5e-5 for the amplitude shift."""
    worst = 0.0
    for kappa in np.geomspace(2e-3, 0.1, 25):
        beats = osc.Beats(1e-3, *osc.coupled_frequencies(1.0, G, kappa * G / 0.25, 0.5))
        dt = 6.3e-3 / beats.omega_a
        t = np.arange(round(2.5 * beats.transfer_time / dt) + 1) * dt
        w0, wb = beats.carrier, beats.beat
        rate2 = beats.amplitude * (w0 * np.cos(w0 * t) * np.sin(wb * t) + wb * np.sin(w0 * t) * np.cos(wb * t))
        measured = transfer_time(t, beats.angles(t)[:, 1], rate2, before=2 * beats.transfer_time)
        worst = max(worst, abs(measured / beats.transfer_time - 1))
    assert worst <= 2.8e-5


def test_zero_crossing_frequency_resolves_far_below_an_fft_bin():
    """30 periods of a sampled sinusoid: an FFT bin is 1/30 of the frequency; the crossing fit is exact to 1e-12."""
    t = np.arange(0, 60.0, 1e-3)
    omega = 3.1320919526731650
    assert pendulums.frequency(t, 1e-3 * np.cos(omega * t + 0.3)) == pytest.approx(omega, rel=1e-12)


def test_mode_purity_detects_a_wrong_mode_shape():
    """The chain's mode-purity check can fail: the same trajectory filtered with shapes perturbed by 1e-3 shows
    residuals far above its 1e-4 tolerance, while the O5 shapes leave ~1e-6."""
    scenario = registry.get("pendulum-chain")
    run = scenario.run("end-released", keep_trajectory=True)
    modes, traj = run.prediction["_modes"], run.trajectory
    tol = scenario.check("mode-purity").tolerance

    def purity(shapes):
        q = traj.qpos @ modes.inertia @ shapes
        return max(
            pendulums.sinusoid_residual(traj.time, q[:, r], pendulums.frequency(traj.time, q[:, r]))
            for r in range(q.shape[1])
        )

    assert purity(modes.shapes) < tol
    wrong = modes.shapes + 1e-3 * np.random.default_rng(0).standard_normal(modes.shapes.shape)
    assert purity(wrong) > 10 * tol


def test_envs_track_theory_with_zero_action_and_take_a_torque_on_pendulum_1():
    import gymnasium as gym

    for env_id in ("rigidbench/SimplePendulum-v0", "rigidbench/CoupledPendulums-v0", "rigidbench/PendulumChain-v0"):
        env = gym.make(env_id).unwrapped
        env.reset(seed=0)
        for _ in range(20):
            _obs, reward, *_ = env.step(np.zeros(1))
        assert -reward < 1e-6
        env.step(np.ones(1))  # clipped to 0.1 N m on pendulum 1 only
        assert env.data.qfrc_applied[0] == 0.1 and not env.data.qfrc_applied[1:].any()
        env.close()


# ---- sweeps (slow) -------------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("n", [2, 3, 4, 6, 8, 10, 12, 20, 40])
def test_chain_matches_theory_for_every_size(n):
    from rigidbench.envs import pendulum_chain

    scenario = registry.get("pendulum-chain")
    for case in ("end-released", "strong-coupling"):
        # The default 1 mrad, or half the case regime's a_max where more modes crowd it (n = 40: a_max = 0.73 mrad).
        fixed = {k: v for k, v in scenario.case(case).values.items() if not callable(v)}
        limit = pendulum_chain.amplitude_limit({**scenario.defaults(), **fixed, "n": n})
        run = scenario.run(case, {"n": n, "amplitude": min(1e-3, limit / 2)})
        assert all(o.passed for o in run.outcomes), [(o.check.name, o.error) for o in run.outcomes]


@pytest.mark.slow
@pytest.mark.parametrize(
    "slug, case, params",
    [
        ("coupled-pendulums", "beats", {"mass": 0.2, "length": 0.5, "k": 0.3, "d": 0.25}),
        ("coupled-pendulums", "anti-phase", {"mass": 3.0, "length": 2.0, "k": 50.0, "d": 2.0, "g": 1.62}),
        ("pendulum-chain", "end-released", {"n": 9, "mass": 0.5, "length": 0.3, "k": 2.0, "d": 0.1}),
        ("double-pendulum", "released", {"mass1": 2.0, "mass2": 0.1, "length1": 0.4, "length2": 1.5}),
        (
            "double-pendulum",
            "fast-mode",
            {"mass1": 0.5, "mass2": 1.0, "length1": 1.0, "length2": 0.5, "amplitude1": 1e-4},
        ),  # noqa: E501
        ("pendulum", "near-inverted", {"length": 0.05, "g": 3.7}),
    ],
)
def test_predictions_follow_the_parameters_actually_simulated(slug, case, params):
    run = registry.get(slug).run(case, params)
    assert all(run.params[k] == pytest.approx(v, rel=1e-15) for k, v in params.items())
    assert all(o.passed for o in run.outcomes), [(o.check.name, o.error) for o in run.outcomes]


@pytest.mark.slow
def test_heavy_lower_bob_is_refused_at_the_default_amplitude_and_passes_inside_its_regime():
    """A heavy bob under a light one (m1 = 0.1, m2 = 2 kg, l1 = 1.5, l2 = 0.4 m): the fast mode is at 25 rad/s with
    th2/th1 = -3.9. At the default 0.25 mrad its first-order amplitude shift (7.7e-6, measured before the regime
    existed) exceeds the 1e-6 tolerance, so the set is refused before simulating; 10x smaller, it passes, energy
    included (the timestep follows omega_fast: omega dt as in the default cases)."""
    scenario = registry.get("double-pendulum")
    params = {"mass1": 0.1, "mass2": 2.0, "length1": 1.5, "length2": 0.4}
    with pytest.raises(OutsideDomain, match="amplitude1"):
        scenario.run("fast-mode", params)
    run = scenario.run("fast-mode", {**params, "amplitude1": 2.5e-5})
    assert all(o.passed for o in run.outcomes), [(o.check.name, o.error) for o in run.outcomes]
    assert run.settings["timestep"] == pytest.approx(2e-3 * 5.097363286 / run_omega_fast(run), rel=1e-6)


def run_omega_fast(run) -> float:
    return next(o.expected for o in run.outcomes if o.check.name == "omega-fast")


# ---- issue 13: every valid set passes or is refused with the theory's reason -------------------------------------


@pytest.mark.parametrize(
    "args",
    [
        ["coupled-pendulums:in-phase", "--set", "amplitude1=0.5", "--set", "amplitude2=0.5"],
        ["coupled-pendulums:anti-phase", "--set", "amplitude1=0.45", "--set", "k=50"],
        ["pendulum", "--set", "length=0.0127", "--set", "amplitude=3.1", "--set", "g=149.3"],
        ["pendulum", "--set", "g=1e-6", "--set", "length=100"],
    ],
)
def test_symmetric_releases_and_fast_or_slow_pendulums_pass_at_any_amplitude(args, capsys):
    """In-phase and anti-phase releases are one-degree-of-freedom motions predicted exactly (O1's elliptic period;
    the level spring's quadrature); the timestep follows sqrt(g/l) (a 1.3 cm pendulum at 149 m/s^2 swinging
    through the bottom at 2 sqrt(g/l), or a 100 m one at 1e-6 m/s^2 with a 1.7e4 s period)."""
    assert cli.main(["run", *args, "--quiet"]) == 0, capsys.readouterr()


@pytest.mark.parametrize(
    "args, named",
    [
        (["coupled-pendulums:beats", "--set", "amplitude1=0.5"], "'amplitude1' = 0.5 rad is outside the regime"),
        (["pendulum-chain", "--set", "amplitude=0.5"], "'amplitude' = 0.5 rad is outside the regime"),
        (["double-pendulum:released", "--set", "amplitude1=0.5"], "'amplitude1' = 0.5 rad is outside the regime"),
        (["coupled-pendulums:beats", "--set", "k=5"], "'k' = 5 N/m is outside the regime of case 'beats'"),
        (["coupled-pendulums:anti-phase", "--set", "amplitude1=1"], "'amplitude1' = 1 rad is outside the regime"),
        (["coupled-pendulums", "--set", "k=1e6"], "'k' = 1e+06 N/m is outside its range (0, 199.5] m g l / d^2"),
        (["double-pendulum", "--set", "mass2=1000"], "'mass2' = 1000 kg is outside its range [1e-3 mass1"),
    ],
)
def test_linear_theory_refuses_amplitudes_and_couplings_beyond_its_domain(args, named, capsys):
    """Multi-mode releases are linear theory: amplitudes where the first-order amplitude shift exceeds a quarter
    of the tolerance are refused with exit 2 and one line naming the parameter and the regime; so are a coupling
    too strong for the beats' transfer time and ratios of time scales beyond the run-length domains."""
    assert cli.main(["run", *args]) == 2
    err = capsys.readouterr().err
    assert named in err and err.count("\n") == 1


def test_beats_regime_follows_the_first_order_amplitude_shift():
    """In phase -(3/4 + 2 kappa) a^2/16 and anti-phase -(3/4 + 4 kappa) a^2/(16 + 32 kappa) bound the beats'
    amplitude: a quarter of the 1e-6 frequency tolerance, and a quarter of the 3e-4 waveform tolerance for the
    phase the shift accumulates over 2.5 T_x; at the defaults the waveform sets 2.15 mrad, and 1 mrad is inside."""
    from rigidbench.envs.coupled_pendulums import amplitude_limit

    scenario = registry.get("coupled-pendulums")
    limit = amplitude_limit(scenario.resolve(scenario.case("beats")))
    kappa = 0.5**2 / G
    shifts = np.array([(0.75 + 2 * kappa) / 16, (0.75 + 4 * kappa) / (16 + 32 * kappa)])
    omegas = np.array(osc.coupled_frequencies(1.0 + 1e-9, G, 1.0, 0.5))
    duration = 2.5 * np.pi / (omegas[1] - omegas[0])
    expected = min(np.sqrt(0.25e-6 / shifts.max()), np.sqrt(0.25 * 3e-4 / ((shifts * omegas).max() * duration)))
    assert limit == pytest.approx(expected, rel=1e-4)
    assert 1e-3 < limit


@pytest.mark.parametrize("slug", FAMILY)
def test_timestep_follows_the_fastest_time_scale_and_is_2ms_in_the_slowest_default_case(slug):
    """dt = c / omega_max, c = 2 ms x the smallest omega_max of the default cases: 2 ms there, never more in a
    default case, and omega dt the same for every set (here g and k x 100: omega x 10, dt / 10); the rule is
    recorded."""
    scenario = registry.get(slug)
    steps = {}
    for case in scenario.cases:
        model = scenario.build(scenario.resolve(case))
        steps[case.name] = model.opt.timestep
    assert max(steps.values()) == pytest.approx(2e-3, rel=1e-12)
    case = scenario.cases[0]
    params = scenario.resolve(case)
    scaled = {x: 100 * params[x] for x in ("g", "k") if x in params}  # the same kappa = k d^2 / (m g l)
    faster = scenario.build(scenario.resolve(case, scaled))
    assert faster.opt.timestep == pytest.approx(steps[case.name] / 10, rel=1e-2)
    derived = registry.get(slug).run(case.name, scaled).settings["derived"]
    assert "omega_max" in derived["timestep"]["rule"]


@pytest.mark.parametrize("slug", FAMILY)
def test_census_draws_no_set_that_is_refused_for_a_reason_other_than_a_domain(slug):
    """Every draw of the census (40 sets, seed 1) is valid, and a refusal, if any, is a domain of the theory
    (planning only: nothing is simulated here; the full census runs in CI)."""
    from rigidbench import census

    draws, _jobs = census.plan([slug], n=40, seed=1, settings=None)
    reasons = [d.reason for d in draws if d.status in (census.REFUSED, census.CRASHED)]
    assert not any(r.startswith("not a domain") for r in reasons), reasons
    assert not any(d.status == census.CRASHED for d in draws), reasons
    # The bound is 10 % of all the census's draws; the chain's double-precision domain (its mode purity's
    # round-off gain, `pendulum_chain.purity_gain`) refuses 5 of its 40 here (12.5 %), the family 5 of 160.
    assert len(reasons) <= 6


def test_tiny_releases_below_double_precision_are_refused_naming_the_amplitude(capsys):
    """A chain released at 1e-14 rad from pivots 0.75 m out: the restoring torque is below the rounding of the
    model's coordinates (rho = 9); refused, not measured as noise."""
    args = ["pendulum-chain", "--set", "n=4", "--set", "length=0.0019", "--set", "d=2.9e-5", "--set", "amplitude=1e-14"]
    assert cli.main(["run", *args]) == 2
    assert "double-precision" in capsys.readouterr().err


def test_double_pendulum_float32_floors_grow_with_the_step_count_only_with_both_modes_excited():
    """On float32 a double pendulum swinging in both modes gets the secular floor (eps / 2) N on every check (a fast
    mode riding a slow one: measured on Warp up to 0.27 eps N, 16x over the random-walk floor); one mode alone keeps
    the random-walk floor 10 eps sqrt(N + 1). Float64 tolerances are untouched."""
    from rigidbench.engines import ROUNDOFF_FACTOR

    scenario = registry.get("double-pendulum")
    eps = float(np.finfo(np.float32).eps)
    for case, secular in (("released", True), ("unequal", True), ("slow-mode", False), ("fast-mode", False)):
        prep = scenario.prepare(case, {}, profile("reference"))
        for name in scenario.case(case).checks:
            check = scenario._scaled_check(name, prep.prediction)
            same, _ = scenario._roundoff_check(check, prep.prediction, "float64", prep.nstep)
            assert same.tolerance == check.tolerance
            scored, _ = scenario._roundoff_check(check, prep.prediction, "float32", prep.nstep)
            floor = 0.5 * eps * prep.nstep if secular else ROUNDOFF_FACTOR * eps * np.sqrt(prep.nstep + 1)
            assert scored.tolerance == pytest.approx(check.tolerance + floor), (case, name)
