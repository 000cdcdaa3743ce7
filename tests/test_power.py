"""`rigidbench power`'s quantities: of the model (masses, g, stiffness, damping, ...) and of the parameters a scenario
computes its start state or controls from (a turning platform's rate, an applied load), found without the scenario
declaring them (`rigidbench.power`)."""

from __future__ import annotations

import copy
import pickle

import mujoco
import numpy as np
import pytest

from rigidbench import power, registry


def _names(slug: str) -> set[str]:
    return {q.name for _, q in power.plan([slug], None)}


def _quantity(slug: str, name: str) -> power.Quantity:
    return next(q for _, q in power.plan([slug], None) if q.name == name)


@pytest.mark.parametrize(
    ("slug", "present", "absent"),
    [
        ("foucault", {"rate:platform", "g"}, {"load:rate"}),
        ("eastward-deflection", {"rate:platform", "g"}, set()),
        ("gyrocompass", {"rate:platform"}, {"rate:rotor", "rate:gimbal"}),  # the rotor's spin is an initial condition
        ("cushion-rebound", {"load:cushion_height", "load:restitution", "contact-damping"}, {"load:speed"}),
        ("cue-strike", {"load:speed", "contact-damping"}, {"rate:ball"}),  # the cue's impulse M v
        ("marble-shot", {"load:impulse"}, {"contact-damping"}),  # its contacts are elastic (no damping)
        ("pivoted-stick", {"load:impulse"}, set()),
        ("struck-stick", {"load:impulse"}, set()),
        ("rutherford", {"coulomb-k"}, {"inverse-square-k"}),  # repulsive strengths: Coulomb's
        ("two-body-orbit", {"inverse-square-k"}, {"coulomb-k"}),  # attractive: gravity
        ("hard-spheres", {"contact-stiffness"}, {"contact-damping", "load:speed", "load:b"}),
        ("heavy-top", {"g"}, {"rate:top", "load:spin"}),  # a top's spin is an initial condition
        ("bent-axle", set(), {"rate:rotor"}),
        ("pendulum", {"g"}, {"joint-damping", "load:amplitude"}),
    ],
)
def test_each_quantity_is_listed_where_the_scenario_has_it_and_only_there(slug, present, absent):
    names = _names(slug)
    assert present <= names
    assert not names & absent
    parameters = {n for n in names if n.startswith(("rate:", "load:"))}
    assert all(_quantity(slug, n).numeric is not None for n in parameters)


def test_a_perturbation_survives_pickling_with_its_kind():
    """Jobs carrying a perturbation run in process pools and on clusters (`rigidbench.runner`)."""
    for slug, name in (("foucault", "rate:platform"), ("cushion-rebound", "load:restitution"), ("pendulum", "g")):
        p = _quantity(slug, name).perturb(1e-6)
        back = pickle.loads(pickle.dumps(p))
        assert back == p and back.from_params == p.from_params
    assert _quantity("foucault", "rate:platform").perturb(1e-6).from_params
    assert not _quantity("pendulum", "g").perturb(1e-6).from_params


@pytest.mark.parametrize(
    ("slug", "case", "name", "check"),
    [
        ("foucault", "mid-latitude", "rate:platform", "precession-rate"),
        ("eastward-deflection", "mid-latitude", "rate:platform", "drop-path"),
        ("gyrocompass", "small-hunting", "rate:platform", "hunting-period"),
        ("cushion-rebound", "low", "load:restitution", "rebound-slip"),
        ("cushion-rebound", "low", "load:cushion_height", "rebound-slip"),
        ("pivoted-stick", "sweet-spot", "load:impulse", "angular-velocity"),
    ],
)
def test_a_parameter_quantity_moves_what_is_simulated_and_not_the_prediction(slug, case, name, check):
    """Scaled by 1e-3, the simulated start state or controls change (the measured value moves, and the check
    fails), while the prediction is the unperturbed one."""
    scenario = registry.get(slug)
    base = {o.check.name: o for o in scenario.run(case).outcomes}
    moved = {o.check.name: o for o in scenario.run(case, perturb=_quantity(slug, name).perturb(1e-3)).outcomes}
    assert moved[check].expected == base[check].expected
    assert base[check].passed and not moved[check].passed
    assert moved[check].measured != base[check].measured


def test_the_platform_rate_is_the_started_hinge_velocity_of_the_copy():
    scenario = registry.get("eastward-deflection")
    prep = scenario.prepare("mid-latitude")
    q = _quantity("eastward-deflection", "rate:platform")
    other = copy.copy(prep.model)
    q.perturb(1e-3)(other)
    dof = prep.model.joint("spin").dofadr[0]
    assert scenario.start(other).qvel[dof] == pytest.approx(prep.data.qvel[dof] * 1.001, rel=1e-15)
    assert scenario.start(prep.model).qvel[dof] == prep.data.qvel[dof]  # the original is untouched


def test_theory_sensitivity_predicts_from_the_perturbed_parameters(monkeypatch):
    """The theory's own sensitivity of a parameter quantity: the prediction from the perturbed rate or restitution
    moves by a tolerance at 1e-2 (the precession rate is proportional to the platform's, the rebound's slip to
    1 + e)."""
    monkeypatch.setattr(power, "DELTAS", (1e-2,))
    for slug, name in (("foucault", "rate:platform"), ("cushion-rebound", "load:restitution")):
        assert power.theory_sensitivity(registry.get(slug), _quantity(slug, name), None) == 1e-2


def test_contact_damping_scales_each_contacts_damping():
    model = registry.get("cue-strike").prepare("centre").model
    (q,) = [q for q in power.quantities(model) if q.name == "contact-damping"]
    other = copy.copy(model)
    q.scale(other, 1e-3)
    np.testing.assert_allclose(other.geom_solref[:, 1], model.geom_solref[:, 1] * 1.001, rtol=1e-15)
    np.testing.assert_array_equal(other.geom_solref[:, 0], model.geom_solref[:, 0])


def test_joint_damping_is_a_quantity_where_a_joint_declares_one():
    xml = """<mujoco><worldbody><body><joint name="h" type="hinge" damping="{d}"/>
        <geom type="sphere" size="0.1" mass="1"/></body></worldbody></mujoco>"""
    damped = mujoco.MjModel.from_xml_string(xml.format(d=0.3))
    assert "joint-damping" in {q.name for q in power.quantities(damped)}
    assert "joint-damping" not in {q.name for q in power.quantities(mujoco.MjModel.from_xml_string(xml.format(d=0)))}
    power.Perturbation("joint-damping", 1e-3)(damped)
    assert damped.dof_damping[0] == pytest.approx(0.3 * 1.001, rel=1e-15)


def test_a_pendulum_has_a_length_row_and_its_perturbation_moves_the_period():
    """length:<body> scales the centre of mass's distance from its joint (a pendulum's rod): the simulated period
    moves by half the relative change (T ~ sqrt(l)) while the prediction keeps the unperturbed model."""
    scenario = registry.get("pendulum")
    case = scenario.cases[0]
    model = scenario.prepare(case.name).model
    names = [q.name for q in power.quantities(model)]
    assert "length:pendulum" in names
    base = {o.check.name: o for o in scenario.run(case.name).outcomes}
    moved = {
        o.check.name: o for o in scenario.run(case.name, perturb=power.Perturbation("length:pendulum", 1e-4)).outcomes
    }
    check = next(n for n in base if "period" in n)
    assert moved[check].expected == base[check].expected
    assert moved[check].measured / base[check].measured - 1 == pytest.approx(0.5e-4, rel=1e-2)
    assert "length:top" in [q.name for q in power.quantities(registry.get("heavy-top").prepare("nutation").model)]
    assert not any(
        n.startswith("length:")
        for n in [q.name for q in power.quantities(registry.get("free-symmetric-top").prepare().model)]
    )


def test_a_power_law_force_has_strength_and_exponent_rows_that_move_the_orbit():
    """central-force declares its law through `rigidbench.forces` (k / r^n terms): power scales the strengths and the
    exponents; the scaled model's force is what is simulated."""
    scenario = registry.get("central-force")
    model = scenario.prepare("kepler").model
    names = [q.name for q in power.quantities(model)]
    assert "power-law-k" in names and "power-law-n" in names
    failed = {
        o.check.name
        for o in scenario.run("kepler", perturb=power.Perturbation("power-law-k", 1e-6)).outcomes
        if not o.passed
    }
    assert failed
