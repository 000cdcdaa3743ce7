"""MuJoCo against the central-force closed forms (docs/theory.md K2, K5, K6): the power-law force of rigidbench.forces,
its RK4 order, and checks shown to catch a wrong simulated model (perturbed as `rigidbench power` does)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigidbench import forces, registry
from rigidbench.scenario import OutsideDomain
from rigidbench.settings import Settings

SCENARIO = registry.get("central-force")


def _by_name(run):
    return {o.check.name: o for o in run.outcomes}


def _scale(name: str, index: int, factor: float):
    """Scale entry `index` of the custom numeric `name` of the simulated model (`Scenario.run(perturb=...)`)."""

    def perturb(model: mujoco.MjModel) -> None:
        i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, name)
        model.numeric_data[model.numeric_adr[i] + index] *= factor

    return perturb


@pytest.mark.parametrize("case", [c.name for c in SCENARIO.cases])
def test_reference_profile_reproduces_theory(case):
    run = SCENARIO.run(case)
    assert run.diverged_at is None
    failed = [(o.check.name, o.measured, o.expected, o.error) for o in run.outcomes if not o.passed]
    assert not failed


_PAIR = """<mujoco><option gravity="0 0 0"/>
  <custom>{custom}</custom>
  <worldbody><body name="a" pos="0.3 -0.2 0.1"><freejoint/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>
  <body name="b" pos="1.1 0.4 -0.5"><freejoint/><inertial pos="0 0 0" mass="2" diaginertia="1 1 1"/></body></worldbody>
</mujoco>"""


def test_power_law_at_n_2_is_the_inverse_square():
    """The same pair under `rigidbench:power-law` (n = 2) and `rigidbench:inverse-square`: the same passive forces,
    and the r^-4 term adds k4 r / |r|^5."""
    square = mujoco.MjModel.from_xml_string(
        _PAIR.format(
            custom='<text name="rigidbench:inverse-square" data="a b"/>'
            '<numeric name="rigidbench:inverse-square" data="-1.5"/>'
        )
    )
    power = mujoco.MjModel.from_xml_string(
        _PAIR.format(
            custom='<text name="rigidbench:power-law" data="a b a b"/>'
            '<numeric name="rigidbench:power-law" data="-1.5 0"/>'
            '<numeric name="rigidbench:power-law-exponent" data="2 4"/>'
        )
    )
    out = []
    for model in (square, power):
        assert forces.attach(model)
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        out.append(data.qfrc_passive.copy())
    np.testing.assert_allclose(out[1], out[0], rtol=1e-14, atol=1e-15)
    law = forces.power_law(power)
    data = mujoco.MjData(power)
    mujoco.mj_forward(power, data)
    r = data.xipos[2] - data.xipos[1]
    d = np.linalg.norm(r)
    law = forces.PowerLaw(law.first, law.second, np.array([-1.5, -0.25]), law.n)
    np.testing.assert_allclose(law.forces(data.xipos)[1], -0.25 * r / d**5, rtol=1e-14)
    # U = k r^(1 - n) / (n - 1): -1.5 / d - 0.25 / (3 d^3)
    assert law.potential_energy(data.xipos) == pytest.approx(-1.5 / d - 0.25 / (3 * d**3), rel=1e-14)


@pytest.mark.parametrize(
    ("custom", "match"),
    [
        ('<text name="rigidbench:power-law" data="a"/>', "pairs of body names"),
        (
            '<text name="rigidbench:power-law" data="a a"/><numeric name="rigidbench:power-law" data="-1"/>'
            '<numeric name="rigidbench:power-law-exponent" data="2"/>',
            "one body twice",
        ),
        (
            '<text name="rigidbench:power-law" data="a b"/><numeric name="rigidbench:power-law" data="-1"/>',
            "power-law-exponent",
        ),
        (
            '<text name="rigidbench:power-law" data="a b"/><numeric name="rigidbench:power-law" data="-1 2"/>'
            '<numeric name="rigidbench:power-law-exponent" data="2"/>',
            "must hold 1 finite",
        ),
        ('<numeric name="rigidbench:power-law" data="-1"/>', "is missing"),
    ],
)
def test_a_malformed_power_law_fails_before_simulating(custom, match):
    model = mujoco.MjModel.from_xml_string(_PAIR.format(custom=custom))
    with pytest.raises(ValueError, match=match):
        forces.attach(model)


def test_orbit_error_is_fourth_order_in_the_timestep():
    """The force is evaluated at every RK4 stage: halving the step divides the orbit error by ~16."""
    step = SCENARIO.prepare("steep").model.opt.timestep
    errors = [
        _by_name(SCENARIO.run("steep", settings=Settings(timestep=h)))["orbit"].measured for h in (2 * step, step)
    ]
    assert 12 < errors[0] / errors[1] < 24  # 16 for fourth order; a force held over the step would give 2


def test_runge_lenz_drift_is_sharper_than_energy_drift():
    """K2: RK4's error shows more in the orbit's orientation (A) than in its energy, at the same run."""
    out = _by_name(SCENARIO.run("kepler"))
    assert out["runge-lenz-drift"].measured > 5 * out["energy-drift"].measured


def test_a_wrong_strength_is_caught_by_the_orbit():
    """k of the simulated model 1e-6 off (as `rigidbench power` perturbs it): the orbit check fails."""
    out = _by_name(SCENARIO.run("kepler", perturb=_scale(forces.POWER_LAW, 0, 1 + 1e-6)))
    assert not out["orbit"].passed and out["apsidal-angle"].passed  # the apsidal angle of n = 2 is pi at any k


def test_a_wrong_exponent_is_caught_by_the_apsidal_angles():
    """n of the simulated model 1e-4 off: the exact apsidal angle moves by ~pi / sqrt(3 - n) dn / (2 (3 - n))."""
    out = _by_name(SCENARIO.run("log-potential", perturb=_scale(forces.POWER_LAW_EXPONENT, 0, 1 + 1e-4)))
    assert not out["apsidal-angle"].passed


def test_a_wrong_correction_is_caught_by_the_advance():
    """k4 of the simulated model 2 % off: the advance moves by 2 % of 2 pi eps, past twice the second-order term."""
    out = _by_name(SCENARIO.run("perihelion", perturb=_scale(forces.POWER_LAW, 1, 1.02)))
    assert not out["perihelion-advance"].passed and not out["apsidal-angle"].passed


def test_a_wrong_exponent_is_caught_by_the_growth_rate():
    """n = 4 of the simulated model 1e-3 off: r* moves, and the growth measured against the predicted r* fails."""
    out = _by_name(SCENARIO.run("unstable", perturb=_scale(forces.POWER_LAW_EXPONENT, 0, 1 + 1e-3)))
    assert not out["growth-rate"].passed


def test_unbound_circular_eccentric_and_strongly_perturbed_starts_are_refused_before_simulating():
    with pytest.raises(OutsideDomain, match="bound"):  # a large r^-4 term raises the launch speed past escape
        SCENARIO.run("perihelion", {"correction": 60.0, "strength": 1.4, "separation": 0.5, "speed_ratio": 1.2})
    with pytest.raises(OutsideDomain, match="near-circular"):
        SCENARIO.run("steep", {"speed_ratio": 1.05})
    with pytest.raises(OutsideDomain, match="apsides"):
        SCENARIO.run("log-potential", {"exponent": -1.0, "speed_ratio": 1.01})
    with pytest.raises(OutsideDomain, match="first-order"):
        SCENARIO.run("perihelion", {"correction": 0.1})


def test_the_env_follows_the_reference_orbit():
    """Zero action: the env's reward stays at the orbit check's size."""
    import gymnasium as gym

    env = gym.make("rigidbench/CentralForce-v0", case="log-potential")
    env.reset(seed=0)
    worst = 0.0
    for _ in range(200):
        _, reward, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
        worst = max(worst, -reward)
        if terminated or truncated:
            break
    env.close()
    assert worst < 1e-7


def test_the_batched_engines_refuse_every_case():
    """Warp and MJX have no passive-force callback: the power law is refused before simulating (engine matrix)."""
    from rigidbench.engines.base import EngineRefused

    for case in SCENARIO.cases:
        model = SCENARIO.build(SCENARIO.resolve(case))
        for engine in ("warp", "mjx"):
            with pytest.raises(EngineRefused, match="power-law"):
                forces.refuse_on(engine, model)
