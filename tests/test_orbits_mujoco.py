"""MuJoCo against the two-body closed forms (docs/theory.md K1-K5): the Hooke force as a zero-length tendon, the Kepler
force through rigidbench.forces, under the reference profile and MuJoCo's defaults."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigidbench import forces, registry
from rigidbench.envs import two_body_orbit as tbo
from rigidbench.scenario import OutsideDomain
from rigidbench.settings import Settings, profile

SCENARIO = registry.get("two-body-orbit")


def _by_name(run):
    return {o.check.name: o for o in run.outcomes}


@pytest.mark.parametrize("case", [c.name for c in SCENARIO.cases])
def test_reference_profile_reproduces_theory(case):
    run = SCENARIO.run(case)
    assert run.diverged_at is None
    failed = [(o.check.name, o.measured, o.expected, o.error) for o in run.outcomes if not o.passed]
    assert not failed
    assert run.settings["integrator"] == "RK4"


def test_each_case_simulates_one_force_law_the_native_tendon_or_the_declared_force():
    """Hooke cases: the tendon spring, no declaration (no callback); Kepler cases: the declaration, no spring."""
    for case in SCENARIO.cases:
        model = SCENARIO.build(SCENARIO.resolve(case))
        stiffness = float(model.tendon_stiffness[model.tendon("spring").id])
        if case.name.startswith("hooke"):
            assert forces.declared(model) == [] and stiffness > 0
        else:
            assert forces.declared(model) == [forces.INVERSE_SQUARE] and stiffness == 0
            assert SCENARIO.read_params(model)["strength"] == case.values["strength"]


def test_the_lab_view_starts_body_2_at_rest_and_its_cm_moves_uniformly():
    """001's LAB picture: body 2 at rest at t = 0, the CM moving at (m1/M) v0 along a straight line (K1)."""
    run = SCENARIO.run("hooke", keep_trajectory=True)
    traj, pred = run.trajectory, run.prediction
    model = SCENARIO.build(SCENARIO.resolve(SCENARIO.case("hooke")))
    view = SCENARIO.cm_frame(model, traj, pred)
    _, x2, _, v2 = SCENARIO._states(model, traj.qpos[:1], traj.qvel[:1])
    assert np.all(v2 == 0)
    travelled = np.linalg.norm(view["cm"][-1] - view["cm"][0])
    assert travelled > pred["_theory"].semi_major  # the CM really moves, by more than the orbit's size
    assert _by_name(run)["cm-motion"].measured < 1e-12


@pytest.mark.parametrize("case", ["kepler", "hooke"])
def test_orbit_error_is_fourth_order_in_the_timestep(case):
    """RK4 at every stage (the force callback is evaluated per stage): halving the step divides the orbit error by
    ~16 (the reference step's error is RK4's, not a force held over the step, which would be first order)."""
    step = SCENARIO.prepare(case).model.opt.timestep
    errors = [
        _by_name(SCENARIO.run(case, settings=Settings(timestep=h)))["orbit-1"].measured for h in (4 * step, 2 * step)
    ]
    assert 12 < errors[0] / errors[1] < 20


def test_predictions_come_from_the_compiled_model():
    """A mass edited in the compiled model moves the prediction (mu, a_i), as `power` relies on."""
    prep = SCENARIO.prepare("kepler")
    model = prep.model
    model.body_mass[model.body("body2").id] *= 1.1
    other = SCENARIO.predict(model, SCENARIO.start(model, prep.params))
    assert other["semi-major-1"] != pytest.approx(prep.prediction["semi-major-1"], rel=1e-3)


@pytest.mark.parametrize(
    ("case", "overrides", "domain"),
    [
        ("kepler", {"stiffness": 5.0}, "case kepler: stiffness"),
        ("kepler", {"speed_ratio": 1.5}, "case kepler: speed_ratio"),
        ("kepler", {"speed_ratio": 1.4}, "bound-ellipse"),
        ("kepler", {"speed_ratio": 0.4}, "bound-ellipse"),
        ("kepler-near-circular", {"speed_ratio": 1.001}, "apsides"),
        ("hooke-near-circular", {"speed_ratio": 1.0}, "apsides"),
    ],
)
def test_sets_outside_the_theory_are_refused_naming_the_domain(case, overrides, domain):
    with pytest.raises(OutsideDomain) as info:
        SCENARIO.resolve(SCENARIO.case(case), overrides)
    assert info.value.domain == domain


def test_an_unbound_kepler_orbit_is_refused_by_the_bound_ellipse_domain():
    """K2 needs E < 0 (s < sqrt 2); the domain names it when the case's regime is not in the way."""
    values = {**SCENARIO.resolve(SCENARIO.case("kepler")), "speed_ratio": 1.5}
    assert "unbound" in tbo._kepler_budget(values)
    values["speed_ratio"] = 0.4  # e = 0.84 > 0.8
    assert "e = |s^2 - 1| = 0.84" in tbo._kepler_budget(values)


def test_mujoco_default_euler_shortens_the_hooke_period_by_symplectic_eulers_omega_h_squared_over_24():
    """Finding: MuJoCo's default (semi-implicit Euler, 2 ms) runs the oscillator fast: its period is short by
    (w h)^2 / 24 (the symplectic Euler map turns at 2/h arcsin(w h / 2) > w)."""
    run = SCENARIO.run("hooke", settings=profile("mujoco-default"))
    h = run.settings["timestep"]
    orbit = SCENARIO.prepare("hooke").prediction["_theory"]
    w = 2 * np.pi / orbit.period
    period = _by_name(run)["period-1"]
    assert (period.expected - period.measured) / period.expected == pytest.approx((w * h) ** 2 / 24, rel=1e-2)


def test_mujoco_default_euler_velocity_lags_the_position_so_apsides_from_qvel_move():
    """Finding: under semi-implicit Euler qvel is the velocity that moved qpos into place, half a step behind it, so
    r.v = 0 misses the apsides by ~w h / (2 e): the near-circular Kepler orbit's apsidal angle comes out ~0.55 rad
    short, while the same positions differentiated alone give pi to 1e-3."""
    settings = profile("mujoco-default")
    run = SCENARIO.run("kepler-near-circular", settings=settings, keep_trajectory=True)
    pred, traj = run.prediction, run.trajectory
    orbit = pred["_theory"]
    assert orbit.apsidal_angle - _by_name(run)["apsidal-angle"].measured > 0.3
    model = SCENARIO.build(SCENARIO.resolve(SCENARIO.case("kepler-near-circular")), settings)
    view = SCENARIO.cm_frame(model, traj, pred)
    r = view["x1"] - view["x2"]
    v = np.gradient(r, traj.time, axis=0)
    plane = orbit.momentum / np.linalg.norm(orbit.momentum)
    angle = tbo._apsidal(traj.time[1:-1], r[1:-1], v[1:-1], plane, orbit)
    assert abs(angle - orbit.apsidal_angle) < 1e-3


def test_batched_worlds_step_bit_for_bit_while_a_declared_force_is_alive():
    """mujoco.batch refuses the Python passive callback `rigidbench.forces` installs while a declared model lives,
    for every model; the worlds then step one at a time (`CWorlds.step`), bit for bit as mj_step on one MjData. A
    batch built before the callback was installed (the pendulum's here) steps the same way while it is."""
    from rigidbench.engines import worlds

    pendulum = registry.get("pendulum").prepare().model
    early = worlds(None, pendulum, 2)  # built with no callback installed
    kepler = SCENARIO.prepare("kepler")  # keeps the declared model, and so the callback, alive
    assert mujoco.get_mjcb_passive() is not None
    for model, data, batch in (
        (kepler.model, kepler.data, worlds(None, kepler.model, 2)),
        (pendulum, None, worlds(None, pendulum, 2)),
        (pendulum, None, early),
    ):
        data = data if data is not None else registry.get("pendulum").start(model)
        batch.load(np.array([0, 1]), data)
        batch.xfrc_applied[1, -1, 0] = 0.01  # world 1 pushed: the worlds are independent
        single = mujoco.MjData(model)
        mujoco.mj_setState(model, single, _state(model, data), mujoco.mjtState.mjSTATE_INTEGRATION)
        batch.step(7)
        mujoco.mj_step(model, single, 7)
        assert np.array_equal(batch.qpos[0], single.qpos) and np.array_equal(batch.qvel[0], single.qvel)
        assert not np.array_equal(batch.qvel[1], single.qvel)
    del kepler


def _state(model, data):
    state = np.empty(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_INTEGRATION))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_INTEGRATION)
    return state


def test_power_perturbs_each_force_law_in_the_cases_that_have_it():
    """`rigidbench power` lists the quantities of every case (the spring of the Hooke cases, the declared strength of
    the Kepler cases); a case whose model lacks one runs unperturbed."""
    from rigidbench import power

    names = [q.name for _, q in power.plan(["two-body-orbit"], None)]
    assert {"spring-k", "inverse-square-k", "mass:body1", "mass:body2"} <= set(names)
    kepler = SCENARIO.prepare("kepler").model
    power.Perturbation("inverse-square-k", 1e-3)(kepler)
    assert forces.inverse_square(kepler).k[0] == pytest.approx(-100.0 * (1 + 1e-3), rel=1e-15)
    hooke = SCENARIO.prepare("hooke").model
    before = hooke.tendon_stiffness.copy(), hooke.numeric_data.copy()
    power.Perturbation("inverse-square-k", 1e-3)(hooke)
    assert np.array_equal(hooke.tendon_stiffness, before[0]) and np.array_equal(hooke.numeric_data, before[1])


def test_a_heavy_body_carried_by_a_fast_cm_passes_within_its_round_off_floor():
    """At m1/m2 = 100, e = 0.8 and cm_speed = 3 the heavy body's CM-frame velocity is a 1e-3 part of its LAB velocity,
    which each of the 2.4e4 steps rounds: energy-partition measured 1.5e-8 there, above RK4's 1e-8; the per-run floor
    n eps m_i^2 max|v_i'| max|v_i| / (mu |E|) covers it, and is not added where the CM is at rest and m1 = m2."""
    run = SCENARIO.run("kepler", {"m1": 10.0, "m2": 0.1, "speed_ratio": 1.34, "cm_speed": 3.0})
    partition = _by_name(run)["energy-partition"]
    assert partition.passed and partition.measured > tbo.ENERGY_PARTITION
    still = SCENARIO.prepare("kepler", {"m1": 1.0, "m2": 1.0, "speed_ratio": 1.34})
    assert still.prediction["_tolerance"]["energy-partition"] < 1.01 * tbo.ENERGY_PARTITION
