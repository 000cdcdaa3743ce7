"""MuJoCo against the gyrocompass closed forms (docs/theory.md G1): every case under the reference settings, the
exact equation resolved beyond its fast-rotor form, the error budget each tolerance names (RK4's dt^4, the
platform's finite inertia), the compiled geometry read back, and the mujoco-default findings' mechanism."""

import copy

import mujoco
import numpy as np
import pytest

from rigidbench import registry
from rigidbench.analytic import gyrocompass as gc
from rigidbench.envs import gyrocompass as env_mod
from rigidbench.scenario import OutsideDomain
from rigidbench.settings import Settings

SCENARIO = registry.get("gyrocompass")


@pytest.mark.parametrize("case", [c.name for c in SCENARIO.cases])
def test_every_case_passes_under_the_reference_settings(case):
    run = SCENARIO.run(case)
    assert run.diverged_at is None
    failed = [(o.check.name, o.error, o.check.tolerance) for o in run.outcomes if not o.passed]
    assert not failed


def test_measured_period_resolves_the_exact_frequency_not_the_fast_rotor_form():
    """omega_g^2 = Omega_perp (H - I_t Omega_perp) / (I_t + I_g): the I_t Omega_perp term moves the period by ~2e-4
    at the defaults; MuJoCo's period matches the exact form to 1e-9 and so misses the simple one by that much."""
    run = SCENARIO.run("small-hunting", keep_trajectory=True)
    theory = run.prediction["_theory"]
    measured = next(o.measured for o in run.outcomes if o.check.name == "hunting-period")
    simple = 2 * np.pi / theory.simple_frequency
    exact = 2 * np.pi / theory.hunting_frequency
    assert abs(measured / exact - 1) < 2e-6  # the a^2/16 shift at 0.005 rad is 1.6e-6
    assert abs(measured / simple - 1) > 100 * abs(measured / exact - 1)


def test_rk4_errors_fall_as_the_fourth_power_of_the_step_and_the_period_check_can_fail():
    """The tolerances' reason: RK4 is fourth order here (H's drift divides by ~16 per halving of the step), the
    derived step leaves the period far inside its 1e-9 (measured 9e-12, the platform's share), and a step 32 times
    longer (omega_max dt = 0.09) breaks the period check: the check sees an under-resolved run."""
    prep = SCENARIO.prepare("large-hunting")
    dt = prep.model.opt.timestep
    errors = {}
    for factor in (32, 16, 8):
        run = SCENARIO.run("large-hunting", settings=Settings(timestep=factor * dt))
        errors[factor] = {o.check.name: o for o in run.outcomes}
    drift = {f: errors[f]["momentum-drift"].measured for f in errors}
    assert drift[16] / drift[8] == pytest.approx(16, rel=0.2)
    assert not errors[32]["hunting-period"].passed
    assert errors[16]["hunting-period"].passed
    reference = SCENARIO.run("large-hunting")
    period = next(o for o in reference.outcomes if o.check.name == "hunting-period")
    assert period.error < 0.05 * period.check.tolerance


def _run_with_platform_inertia(scale: float):
    """Simulate large-hunting with the platform's moment of inertia multiplied by `scale` (the prediction and its
    drift bound computed from that model)."""
    prep = SCENARIO.prepare("large-hunting")
    model = copy.copy(prep.model)
    model.body_inertia[model.body("platform").id] *= scale
    mujoco.mj_setConst(model, mujoco.MjData(model))
    data = SCENARIO.start(model, prep.params)
    prediction = SCENARIO.predict(model, data)
    traj = SCENARIO.simulate(model, data, prep.duration)
    return SCENARIO.measure(model, traj, prediction), prediction


def test_platform_drift_follows_its_momentum_balance_at_any_inertia():
    """The platform's rate is kept by its inertia alone, to I_p Omega + L_n = const: 1e4 times lighter, it drifts 1e4
    times more, as predicted from the gyro's momentum along the axis within 1e-5 both times; the drift stays under
    the bound S / (I_p Omega) the period tolerances carry, and the period moves by about what they allow for it."""
    reference, ref_pred = _run_with_platform_inertia(1.0)
    light, light_pred = _run_with_platform_inertia(1e-4)
    assert light["platform-drift"] / reference["platform-drift"] == pytest.approx(1e4, rel=1e-3)
    for measured, pred in ((reference, ref_pred), (light, light_pred)):
        assert measured["platform-drift"] == pytest.approx(pred["platform-drift"], rel=1e-5)
    g, theory, amplitude = light_pred["_geometry"], light_pred["_theory"], light_pred["_amplitude"]
    swing = gc.platform_momentum_swing(
        g.inertia_transverse,
        g.inertia_gimbal,
        theory.spin_momentum,
        light_pred["_omega"],
        g.latitude,
        amplitude,
        theory.max_rate(amplitude),
    )
    assert light["platform-drift"] <= swing / (g.inertia_platform * light_pred["_omega"])
    moved = abs(light["hunting-period"] / light_pred["hunting-period"] - 1)
    allowed = light_pred["_tolerance"]["hunting-period"] - SCENARIO.check("hunting-period").tolerance
    assert 0.05 * allowed < moved <= allowed


def test_geometry_is_read_back_from_the_compiled_model():
    params = SCENARIO.resolve(SCENARIO.case("high-latitude"), {"I_gimbal": 0.02, "I_axial": 0.015})
    model = SCENARIO.build(params)
    g = env_mod.geometry(model)
    assert g.latitude == pytest.approx(params["latitude"], abs=1e-15)
    assert g.horizontal == pytest.approx(np.cos(params["latitude"]), rel=1e-15)
    assert g.north == pytest.approx(0.0, abs=1e-15)
    assert (g.inertia_axial, g.inertia_transverse, g.inertia_gimbal) == pytest.approx((0.015, 0.01, 0.02), rel=1e-15)
    assert g.inertia_platform == pytest.approx(SCENARIO.reference_settings(params)["platform_inertia"].value, rel=1e-15)


def test_a_rotor_that_is_not_axisymmetric_is_refused():
    model = SCENARIO.build(SCENARIO.resolve(SCENARIO.case(None)))
    model.body_inertia[model.body("rotor").id][0] *= 1.01
    with pytest.raises(ValueError, match="transverse moments .* differ"):
        env_mod.geometry(model)
    model = SCENARIO.build(SCENARIO.resolve(SCENARIO.case(None)))
    model.body_inertia[model.body("gimbal").id][0] *= 1.01
    with pytest.raises(ValueError, match="horizontal moments .* differ"):
        env_mod.geometry(model)


def test_north_seeking_domain_refuses_a_rotor_too_slow_for_the_platform():
    """H < I_t Omega_perp has no hunting about North. Inside the printed ranges (I_a >= I_t, spin_rate >= 10 rad/s,
    Omega <= 5 rad/s) only the corner of the slowest spin, the fastest platform and a release near South comes
    close; here a slow spin released at 2.5 rad makes H negative."""
    p = {**SCENARIO.resolve(SCENARIO.case(None)), "spin_rate": 1.0, "Omega": 5.0, "latitude": 0.0, "amplitude": 2.5}
    assert "H = " in env_mod._north_seeking(p)
    assert env_mod._north_seeking(SCENARIO.resolve(SCENARIO.case(None))) is None


def test_mujoco_default_euler_loses_H_at_first_order_in_the_step():
    """The mujoco-default finding's mechanism: semi-implicit Euler does not keep H = I_a (chi' + Omega_perp cos
    alpha); its drift halves with the step (first order), and so does the turning angle's growth."""
    drifts, growth = [], []
    for dt in (2e-3, 1e-3):
        run = SCENARIO.run("large-hunting", settings=Settings(integrator="Euler", timestep=dt))
        by_name = {o.check.name: o for o in run.outcomes}
        drifts.append(by_name["momentum-drift"].measured)
        growth.append(by_name["turning-angle"].error)
    assert drifts[0] / drifts[1] == pytest.approx(2, rel=0.05)
    assert growth[0] / growth[1] == pytest.approx(2, rel=0.05)


# A census draw (seed 3, index 1): a 405 rad/s spin against a platform's horizontal rate of 3.5e-4 rad/s, released
# 1e-4 rad from North: rho = eps chi' / (Omega_perp sin a) = 2.4e-6.
FAST_SPIN_SLOW_PLATFORM = {
    "Omega": 0.003117,
    "latitude": 1.456,
    "spin_rate": 404.8,
    "amplitude": 1.038e-4,
    "I_transverse": 5.061,
    "I_axial": 10.1,
    "I_gimbal": 2.192e-4,
}


def test_gyroscopic_round_off_is_carried_by_the_tolerances_and_refused_beyond_its_domain():
    """MuJoCo's world-frame gyroscopic torque rounds to ~eps I chi'^2: at rho = 2.4e-6 the turning angle is off by
    ~1e-8, a thousand times RK4's error, and the tolerances' floor ~rho covers it; at rho > 1e-5 the set is refused."""
    run = SCENARIO.run("large-hunting", FAST_SPIN_SLOW_PLATFORM, keep_trajectory=True)
    assert run.prediction["_rho"] == pytest.approx(2.4e-6, rel=0.05)
    turning = next(o for o in run.outcomes if o.check.name == "turning-angle")
    assert turning.error > 1e-9  # round-off, not RK4 (~1e-11 at the derived step)
    assert all(o.passed for o in run.outcomes)
    with pytest.raises(OutsideDomain, match="gyroscopic-round-off"):
        SCENARIO.resolve(
            SCENARIO.case("small-hunting"), {"Omega": 1e-3, "latitude": 1.5, "spin_rate": 1e4, "amplitude": 1e-4}
        )


@pytest.mark.parametrize(
    ("case", "params"),
    [
        # Near the separatrix, a small rotor on a heavy gimbal under a slow platform near the pole (a review's corners).
        (
            "large-hunting",
            {
                "amplitude": 3.0,
                "Omega": 1e-3,
                "latitude": 1.5,
                "spin_rate": 1e4,
                "I_transverse": 1e-4,
                "I_axial": 2e-4,
                "I_gimbal": 10.0,
            },
        ),
        (
            "small-hunting",
            {
                "amplitude": 0.01,
                "Omega": 1e-3,
                "latitude": 1.5,
                "spin_rate": 1e4,
                "I_transverse": 1e-4,
                "I_axial": 1.8e-4,
                "I_gimbal": 1.0,
            },
        ),
    ],
)
def test_roundoff_floor_holds_at_the_ranges_corners(case, params):
    """The gyroscopic round-off rho is taken at the turning point (sin|a|, not sin(min(|a|, pi/2)): 7x larger at
    a = 3), and the hunting period's floor is scaled by its sensitivity to the amplitude (~5 there): these in-range
    sets failed by up to 18x before, within their tolerances now."""
    from rigidbench import runner

    job = runner.plan([f"gyrocompass:{case}"], {k: repr(v) for k, v in params.items()}, None)[0]
    rows = runner.run_job(job, None)
    assert all(r["status"] == "pass" for r in rows), [(r["check"], r["error"], r["tolerance"]) for r in rows]
