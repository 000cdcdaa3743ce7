"""MuJoCo against docs/theory.md R8: where the axle's reaction lives in MuJoCo, the rate held with no drive, every case
under reference and mujoco-default, the domains, and what MuJoCo's compiler does to a nearly aligned inertial frame."""

import mujoco
import numpy as np
import pytest

from rigidbench import registry
from rigidbench.analytic import bent_axle as ba
from rigidbench.envs import bent_axle as env_module
from rigidbench.scenario import OutsideDomain
from rigidbench.settings import profile

SCENARIO = registry.get("bent-axle")
EPS = np.finfo(float).eps
# A rotor with both a tilt and an off-axle CoM, so that every component of N and F is nonzero.
SKEW = {"tilt": 0.3, "com_radial": 0.04, "com_axial": -0.07, "I1": 2e-3, "I2": 3e-3, "I3": 4.5e-3, "omega": -13.0}


def _state(case="off-axle", overrides=None, angle=0.7):
    prep = SCENARIO.prepare(case, overrides)
    model, data = prep.model, prep.data
    data.qpos[0] = angle
    mujoco.mj_forward(model, data)
    return model, data, env_module.theory(model, data)


@pytest.mark.parametrize("case", [c.name for c in SCENARIO.cases])
def test_every_case_passes_under_reference(case):
    run = SCENARIO.run(case)
    assert run.diverged_at is None and run.outcomes
    assert all(o.passed for o in run.outcomes), [(o.check.name, o.error) for o in run.outcomes if not o.passed]


def test_the_torque_sensor_reads_the_axles_torque_on_the_rotor_about_the_site():
    """The sensors at `bearing` give what the world exerts on the rotor (not the rotor on the world), about the site,
    in the rotor's axes: R8's N_B and F_B, to round-off."""
    model, data, axle = _state("off-axle", SKEW)
    torque = data.sensordata[env_module.sensor_slice(model, "bearing-torque")]
    force = data.sensordata[env_module.sensor_slice(model, "bearing-force")]
    assert np.all(np.abs(axle.torque_B[:2]) > 1e-3 * axle.torque_scale)  # both components matter here
    np.testing.assert_allclose(torque, axle.torque_B, rtol=0, atol=4 * EPS * axle.torque_scale)
    np.testing.assert_allclose(force, axle.force_B, rtol=0, atol=4 * EPS * axle.force_scale)


def test_cfrc_int_is_the_same_wrench_in_world_axes_about_the_subtree_com():
    """The sensors are cfrc_int (after mj_rnePostConstraint): [torque; force] in world axes, the torque about the
    subtree's centre of mass (the rotor's CoM here), shifted to O and turned into the rotor's axes."""
    model, data, axle = _state("off-axle", SKEW)
    mujoco.mj_rnePostConstraint(model, data)
    b = model.body("rotor").id
    torque_c, force_W = data.cfrc_int[b, :3], data.cfrc_int[b, 3:]
    about_com = data.subtree_com[model.body_rootid[b]]
    site = data.site("bearing").xpos
    torque_W = torque_c - np.cross(site - about_com, force_W)
    R_WB = data.xmat[b].reshape(3, 3)
    np.testing.assert_allclose(R_WB.T @ torque_W, axle.torque_B, rtol=0, atol=4 * EPS * axle.torque_scale)
    np.testing.assert_allclose(R_WB.T @ force_W, axle.force_B, rtol=0, atol=4 * EPS * axle.force_scale)


def test_a_hinge_is_not_a_constraint_so_efc_force_holds_nothing():
    model, data, axle = _state("off-axle", SKEW)
    assert data.nefc == 0 and np.all(data.qfrc_constraint == 0)
    assert axle.torque > 0  # while the axle does carry a torque


def test_the_rate_needs_no_drive_the_hinges_bias_force_is_zero_to_round_off():
    """N is perpendicular to omega, so the hinge's equation is I_zz theta'' = 0: MuJoCo's bias force about it and
    its acceleration vanish to round-off at any angle (measured <= 0.6 eps omega^2 |I_O|)."""
    for angle in np.linspace(-3, 3, 7):
        model, data, axle = _state("off-axle", SKEW, angle)
        assert abs(data.qfrc_bias[0]) <= 4 * EPS * axle.torque_scale
        assert abs(data.qacc[0]) * axle.inertia_O[2, 2] <= 4 * EPS * axle.torque_scale


def test_reversing_the_axle_keeps_the_torque_fixed_in_the_rotor():
    run_plus = SCENARIO.run("off-axle", {**SKEW, "omega": 13.0}, keep_trajectory=True)
    run_minus = SCENARIO.run("off-axle", SKEW, keep_trajectory=True)
    np.testing.assert_allclose(run_plus.trajectory.torque_B[0], run_minus.trajectory.torque_B[0], rtol=1e-14)
    assert all(o.passed for o in run_plus.outcomes + run_minus.outcomes)


def test_the_torque_is_fixed_in_the_rotor_over_the_run():
    run = SCENARIO.run("tilted-disc", keep_trajectory=True)
    torque_B = run.trajectory.torque_B
    axle = run.prediction["_theory"]
    assert np.abs(torque_B - torque_B[0]).max() <= 4 * EPS * axle.torque_scale
    # and in space it has turned through the run's five turns with the rotor
    angle = run.trajectory.qpos[-1, 0]
    assert angle == pytest.approx(axle.omega * run.duration, rel=1e-13)


def test_mujoco_default_is_exact_too_theta_double_dot_is_zero():
    """Euler at 2 ms integrates theta = omega t exactly (no acceleration to integrate) and the sensors are a function
    of the state alone: every check passes under mujoco-default as well (the finding: nothing to find)."""
    for case in SCENARIO.cases:
        run = SCENARIO.run(case.name, settings=profile("mujoco-default"))
        assert run.settings["integrator"] == "Euler" and run.settings["timestep"] == 0.002
        assert all(o.passed for o in run.outcomes), case.name


def test_a_perturbed_inertia_is_seen_by_the_torque_check():
    """The reaction is read from the simulated model (power's perturbed copy), not recomputed from the predicted one."""

    def heavier(model):
        model.body_inertia[1] *= 1 + 1e-7
        mujoco.mj_setConst(model, mujoco.MjData(model))

    run = SCENARIO.run("tilted-disc", perturb=heavier)
    magnitude = next(o for o in run.outcomes if o.check.name == "torque-magnitude")
    assert not magnitude.passed and magnitude.error == pytest.approx(1e-7, rel=1e-3)


def test_mujoco_drops_an_inertial_frame_within_1e_6_of_the_bodys_and_the_domain_refuses_it():
    """MuJoCo 4.0's compiler takes an inertial quaternion within 1e-6 of the body's for the body's own
    (body_sameframe) and simulates with the body frame: body_iquat keeps the tilt, ximat does not."""
    spec = SCENARIO.spec()
    tilt = 1.76e-6
    spec.body("rotor").iquat = [np.cos(tilt / 2), np.sin(tilt / 2), 0, 0]
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert model.body_iquat[1][1] == pytest.approx(np.sin(tilt / 2))
    assert model.body_sameframe[1] != mujoco.mjtSameFrame.mjSAMEFRAME_NONE
    np.testing.assert_array_equal(data.ximat[1].reshape(3, 3), np.eye(3))  # the tilt is gone from the dynamics
    with pytest.raises(OutsideDomain, match="mujoco-sameframe") as exc:
        SCENARIO.resolve(SCENARIO.case("tilted-disc"), {"tilt": tilt})
    assert "tilt" in str(exc.value)
    with pytest.raises(OutsideDomain, match="mujoco-sameframe"):
        SCENARIO.resolve(SCENARIO.case("off-axle"), {"com_radial": 9e-7, "com_axial": 0.0})
    spec.body("rotor").iquat = [np.cos(2e-6), np.sin(2e-6), 0, 0]  # tilt 4e-6 rad: the domain's edge, kept
    assert spec.compile().body_sameframe[1] == mujoco.mjtSameFrame.mjSAMEFRAME_NONE


@pytest.mark.parametrize(
    ("case", "overrides", "domain", "names"),
    [
        ("tilted-disc", {"tilt": 1e-5}, "resolvable-torque", "tilt"),
        ("tilted-disc", {"I3": 3e-3, "I2": 3e-3}, "resolvable-torque", "I1, I2, I3"),
        (
            "off-axle",
            {"com_radial": 5e-7, "tilt": 0.3, "I1": 1e-3, "I2": 1e-3, "I3": 1.8e-3},
            "resolvable-force",
            "com_radial",
        ),
        ("balanced", {"I3": 1e-6, "I1": 1.0, "I2": 1.0, "com_axial": 0.5}, "axle-inertia", "kappa"),
    ],
)
def test_domains_refuse_before_simulating_naming_the_parameters(case, overrides, domain, names):
    with pytest.raises(OutsideDomain, match=domain) as exc:
        SCENARIO.resolve(SCENARIO.case(case), overrides)
    assert names in str(exc.value)


def test_balanced_case_regime_is_refused_if_tilted():
    with pytest.raises(OutsideDomain, match="tilt"):
        SCENARIO.resolve(SCENARIO.case("balanced"), {"tilt": 0.1})


def test_a_drive_torque_makes_the_env_deviate_from_theory():
    """The env's reward is the deviation from R8 at constant rate: zero action stays on it, a drive does not."""
    import gymnasium as gym

    deviations = {}
    for action in (0.0, 1.0):
        env = gym.make("rigidbench/BentAxle-v0", case="off-axle")
        env.reset(seed=0)
        for _ in range(20):
            _obs, _reward, _term, _trunc, info = env.step(np.array([action], dtype=np.float32))
        deviations[action] = info["deviation"]
        env.close()
    assert deviations[0.0] < 1e-12 < 1e-4 < deviations[1.0]


def test_the_predicted_inertia_is_read_back_from_the_compiled_model():
    model, data, axle = _state("off-axle", SKEW)
    b = model.body("rotor")
    rotation = ba.tilted_principal_frame(SCENARIO.read_params(model)["tilt"])
    expected = ba.inertia_about_point(float(b.mass[0]), b.inertia, rotation, b.ipos)
    np.testing.assert_allclose(axle.inertia_O, expected, rtol=0, atol=4 * EPS * np.abs(expected).max())


@pytest.mark.parametrize("integrator", ["RK4", "Euler"])
def test_sensordata_after_mj_step_belongs_to_the_state_before_it(integrator):
    """mj_step computes the sensors at the state it starts from (RK4's later stages skip them): after a step,
    sensordata is one step stale until mj_forward. The scenario and the env call mj_forward first."""
    prep = SCENARIO.prepare("tilted-disc")
    model, data = prep.model, prep.data
    model.opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    data.qfrc_applied[0] = 0.01  # a drive, so the torque changes from step to step (at constant rate it does not)
    mujoco.mj_forward(model, data)
    at_start = data.sensordata.copy()
    mujoco.mj_step(model, data)
    stale = data.sensordata.copy()
    mujoco.mj_forward(model, data)
    np.testing.assert_array_equal(stale, at_start)
    assert np.abs(data.sensordata - stale).max() > 1e-4 * np.abs(stale).max()


def test_a_float32_engine_is_held_to_the_secular_floor_of_the_rotors_angle(monkeypatch):
    """On a float32 engine (test_engines' fake: every step's state rounded to float32) the rotor's angle carries the
    secular round-off of 785 additions up to 31 rad (measured 5.3e-4 rad in the torque's direction): the direction
    and rate checks are held to that floor (prediction["_roundoff_secular"]), and still pass."""
    from test_engines import Float32Engine

    from rigidbench.engines import registry as engine_registry
    from rigidbench.settings import Settings

    monkeypatch.setattr(engine_registry, "engine_for", lambda name, **kw: Float32Engine())
    run = SCENARIO.run("off-axle", settings=Settings(engine="mjx"))
    direction = next(o for o in run.outcomes if o.check.name == "torque-direction")
    assert 1e-5 < direction.error < direction.check.tolerance  # float32 moved it, within its stated floor
    assert "secular" in direction.check.reason
    assert all(o.passed for o in run.outcomes), [(o.check.name, o.error) for o in run.outcomes if not o.passed]
