"""MuJoCo against the rotating-frame closed forms (`foucault`, `eastward-deflection`), and the force law they need:
gravity fixed in a turning body's axes (`rigidbench.forces.FrameField`), added at every RK4 stage."""

from __future__ import annotations

import copy
import math

import mujoco
import numpy as np
import pytest

from rigidbench import engines, forces, power, registry, simulate
from rigidbench.analytic import rotating as rot
from rigidbench.envs import rotating
from rigidbench.scenario import OutsideDomain
from rigidbench.settings import profile

_DROP = """<mujoco>
  <option integrator="RK4" timestep="{dt}" gravity="0 0 0"/>
  <worldbody>
    <body name="platform"><joint name="spin" type="hinge" axis="0 {c} {s}"/>
      <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>
    <body name="ball"><freejoint/><inertial pos="0 0 0" mass="{m}" diaginertia="1 1 1"/></body>
  </worldbody>
  <custom>{custom}</custom>
</mujoco>"""
_FIELD = (
    '<text name="rigidbench:frame-field" data="platform ball"/>'
    '<numeric name="rigidbench:frame-field" data="0 0 -9.81"/>'
)


def _drop_model(dt: float, lat: float = 0.6, mass: float = 2.0, custom: str = _FIELD) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(_DROP.format(dt=dt, c=math.cos(lat), s=math.sin(lat), m=mass, custom=custom))


def _drop_error(dt: float, rate: float = 1.0, lat: float = 0.6, t_end: float = 2.0) -> float:
    """Distance (m) between MuJoCo's drop, in the platform's axes, and the exact N1 solution after t_end."""
    model = _drop_model(dt, lat)
    data = mujoco.MjData(model)
    data.qvel[0] = rate
    mujoco.mj_forward(model, data)
    traj = simulate.simulate(model, data, t_end)
    r = rotating.world_to_platform(model, traj.qpos[-1:], traj.qpos[-1:, 1:4])[0]
    exact = rot.drop_path(traj.time[-1:], [0, 0, -9.81], rot.rate_vector(rate, lat))[0]
    return float(np.linalg.norm(r - exact))


def test_frame_field_turns_with_its_frame_and_scales_with_mass():
    """The force on each body is m R g, R the frame body's orientation now: the generalised force equals
    mj_applyFT's of that force, at any platform angle."""
    model = _drop_model(1e-3)
    assert forces.attach(model)
    law = forces.frame_field(model)
    data = mujoco.MjData(model)
    data.qpos[0] = 0.9
    data.qpos[1:4] = [0.3, -0.2, 0.1]
    mujoco.mj_forward(model, data)
    R = data.xmat[1].reshape(3, 3)
    np.testing.assert_allclose(law.field_world(data.xmat), R @ [0, 0, -9.81], rtol=0, atol=1e-15)
    expected = np.zeros(model.nv)
    mujoco.mj_applyFT(model, data, 2.0 * R @ [0, 0, -9.81], np.zeros(3), data.xipos[2], 2, expected)
    np.testing.assert_allclose(data.qfrc_passive, expected, rtol=0, atol=1e-14)
    assert np.all(data.qfrc_passive[:1] == 0)  # the free ball's force does not touch the platform's hinge


def test_frame_field_keeps_rk4_fourth_order():
    """Evaluated at every RK4 stage from the stage's orientation: the drop's error falls 16x per halving (a
    field held over each step would be first order). Omega t = 2 so the truncation error is well above round-off."""
    e = [_drop_error(dt) for dt in (0.1, 0.05, 0.025)]
    orders = np.log2(np.array(e[:-1]) / np.array(e[1:]))
    assert np.all(np.abs(orders - 4) < 0.3), (e, orders)


@pytest.mark.parametrize(
    ("custom", "match"),
    [
        (
            '<text name="rigidbench:frame-field" data="platform"/>'
            '<numeric name="rigidbench:frame-field" data="0 0 1"/>',
            "at least one body",
        ),
        (
            '<text name="rigidbench:frame-field" data="platform moon"/>'
            '<numeric name="rigidbench:frame-field" data="0 0 1"/>',
            "'moon'",
        ),
        (
            '<text name="rigidbench:frame-field" data="platform platform"/>'
            '<numeric name="rigidbench:frame-field" data="0 0 1"/>',
            "distinct moving bodies",
        ),
        ('<text name="rigidbench:frame-field" data="platform ball"/>', "missing"),
        ('<numeric name="rigidbench:frame-field" data="0 0 1"/>', "missing"),
        (
            '<text name="rigidbench:frame-field" data="platform ball"/><numeric name="rigidbench:frame-field" '
            'data="0 1"/>',
            "three finite numbers",
        ),
    ],
)
def test_malformed_frame_field_declarations_are_refused_before_simulating(custom, match):
    with pytest.raises(ValueError, match=match):
        forces.attach(_drop_model(1e-2, custom=custom))


@pytest.mark.parametrize("name", ["warp", "mjx"])
def test_batched_engines_refuse_the_frame_field(name):
    with pytest.raises(engines.EngineRefused, match="rigidbench:frame-field"):
        forces.refuse_on(name, _drop_model(1e-2))


def test_power_perturbs_the_declared_field_as_g():
    model = registry.get("eastward-deflection").build(registry.get("eastward-deflection").defaults())
    (g,) = [q for q in power.quantities(model) if q.name == "g"]
    other = copy.copy(model)
    g.scale(other, 1e-3)
    assert forces.frame_field(other).field_frame[2] == pytest.approx(-9.81 * 1.001, rel=1e-15)
    assert forces.frame_field(model).field_frame[2] == -9.81  # the original is untouched


# ---- the scenarios under reference ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def foucault_runs():
    scenario = registry.get("foucault")
    return {c.name: scenario.run(c.name, keep_trajectory=True) for c in scenario.cases}


@pytest.fixture(scope="module")
def drop_runs():
    scenario = registry.get("eastward-deflection")
    return {c.name: scenario.run(c.name, keep_trajectory=True) for c in scenario.cases}


def test_every_foucault_case_passes_under_reference(foucault_runs):
    for name, run in foucault_runs.items():
        assert run.outcomes and all(o.passed for o in run.outcomes), (
            name,
            [(o.check.name, o.error) for o in run.outcomes],
        )


def test_every_drop_case_passes_under_reference(drop_runs):
    for name, run in drop_runs.items():
        assert run.outcomes and all(o.passed for o in run.outcomes), (
            name,
            [(o.check.name, o.error) for o in run.outcomes],
        )


def test_swing_plane_turns_clockwise_in_the_north_and_counter_clockwise_in_the_south(foucault_runs):
    def rate(case):
        return next(o.measured for o in foucault_runs[case].outcomes if o.check.name == "precession-rate")

    assert rate("mid-latitude") < 0 and rate("pole") < 0 and rate("southern") > 0
    # |rate| follows |sin(lambda)|: Paris against Sydney, within the checks' tolerances.
    ratio = rate("mid-latitude") / rate("southern")
    assert ratio == pytest.approx(-math.sin(math.radians(48.85)) / math.sin(math.radians(33.87)), rel=2e-3)


def test_foucault_misses_n2_by_its_neglected_terms_not_more(foucault_runs):
    """MuJoCo's error is the theory's own neglected terms: at the pole Airy's (3/8) a^2 alone (a = 0.02 rad), which
    the full nonlinear pendulum shows too (tests/test_rotating_analytic.py)."""
    pole = foucault_runs["pole"]
    (o,) = [o for o in pole.outcomes if o.check.name == "precession-rate"]
    assert o.measured / o.expected - 1 == pytest.approx(-0.375 * math.sin(0.02) ** 2, rel=0.01)


def test_the_platform_rate_is_constant_to_the_bit(foucault_runs, drop_runs):
    """The pivot is on the axis and a ball joint transmits no torque: nothing changes the platform's rate."""
    for run in (*foucault_runs.values(), *drop_runs.values()):
        model = registry.get(run.scenario).build(run.params)
        rate = rotating.spin_rate(model, run.trajectory.qvel)
        assert np.all(rate == rate[0])


def test_eastward_deflection_is_n3_plus_its_second_order_correction(drop_runs):
    """MuJoCo lands where the exact motion does: N3 x (1 + x0^2 (3 cos^2(lambda)/8 - 1/10)), to 1e-6 of it."""
    for case, lat in (("mid-latitude", math.pi / 4), ("equator", 0.0)):
        (o,) = [o for o in drop_runs[case].outcomes if o.check.name == "eastward-deflection"]
        x0 = 0.02 * rot.fall_time(9.81, 20.0)
        assert o.measured / o.expected - 1 == pytest.approx(x0**2 * (3 * math.cos(lat) ** 2 / 8 - 0.1), rel=1e-2)


def test_semi_implicit_euler_leads_the_drop_by_half_a_step():
    """mujoco-default (semi-implicit Euler, 2 ms): x_n = g dt^2 n (n + 1)/2, so the path leads the exact one by
    g t dt / 2 at time t: 2 cm after a 20 m drop; the eastward offset where the ball has fallen 20 m stays right,
    the error being a time shift."""
    scenario = registry.get("eastward-deflection")
    run = scenario.run("equator", settings=profile("mujoco-default"))
    by = {o.check.name: o for o in run.outcomes}
    t_end = run.duration
    assert by["drop-path"].measured == pytest.approx(9.81 * t_end * 2e-3 / 2, rel=0.02)
    assert not by["drop-path"].passed and by["eastward-deflection"].passed


@pytest.mark.parametrize(
    ("slug", "case", "params", "name"),
    [
        ("foucault", "mid-latitude", {"rate": 0.5}, "rate"),
        ("foucault", "mid-latitude", {"latitude": 0.2}, "latitude"),
        ("foucault", "equator", {"azimuth": 0.3}, "azimuth"),
        ("eastward-deflection", "equator", {"rate": 1.0}, "rate"),
        ("eastward-deflection", "pole", {"latitude": 1.2}, "latitude"),
    ],
)
def test_sets_outside_the_theorys_domain_are_refused_naming_the_parameter(slug, case, params, name):
    scenario = registry.get(slug)
    with pytest.raises(ValueError, match=f"'{name}'") as exc:
        scenario.resolve(scenario.case(case), params)
    if name == "latitude" or name == "azimuth":
        assert isinstance(exc.value, OutsideDomain)


def test_an_east_west_swing_on_the_equator_is_an_exact_planar_pendulum(foucault_runs):
    """Coriolis and centrifugal forces of an East-West swing on the equator lie along the rod: the period is O1's
    exactly, MuJoCo missing it by RK4's own frequency error (omega0 dt)^4/120 and no more."""
    run = foucault_runs["equator"]
    (o,) = [o for o in run.outcomes if o.check.name == "swing-period"]
    omega0_dt = 2 * math.pi / 200
    assert abs(o.measured / o.expected - 1) <= 1.5 * omega0_dt**4 / 120
