"""Issue 35: the hard-spheres contact time, against the exact solution of MuJoCo's contact spring.

MuJoCo's direct solref (-k, 0) with solimp dmin = dmax realises the central spring r'' = k (a - |r|) r / |r| to
round-off; the C8 quadrature of its contact time is checked against an independent ODE integration, and the
`contact-time` check is shown to catch a 1e-6 (and 1e-8) change of the simulated stiffness."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy import integrate

from rigidbench import registry
from rigidbench.analytic import scattering as sc
from rigidbench.power import Perturbation

A = 0.1
HARD = registry.get("hard-spheres")


def _contact_time_ivp(b: float, k: float, u: float) -> float:
    """Time with |r| < a of the relative coordinate under the spring, by DOP853 with events at entry and exit."""

    def rhs(_t, y):
        r = np.hypot(y[0], y[1])
        push = k * (A - r) / r if r < A else 0.0
        return [y[2], y[3], push * y[0], push * y[1]]

    def entry(_t, y):
        return np.hypot(y[0], y[1]) - A

    def exit_(_t, y):
        return np.hypot(y[0], y[1]) - A

    entry.direction, exit_.direction = -1.0, 1.0
    tau = np.pi / np.sqrt(k)
    y0 = [-np.sqrt(A * A - b * b) - 0.01 * u * tau, b, u, 0.0]  # free flight for 0.01 tau before the entry
    sol = integrate.solve_ivp(
        rhs, (0, 3 * tau), y0, method="DOP853", rtol=1e-13, atol=1e-16, max_step=tau / 200, events=(entry, exit_)
    )
    return float(sol.t_events[1][0] - sol.t_events[0][0])


@pytest.mark.parametrize("b_over_a", [0.0, 0.3, 0.5, 0.9, 0.999])
@pytest.mark.parametrize("k", [1e4, 1e8])
def test_contact_time_quadrature_matches_the_ode(b_over_a, k):
    """C8's contact time (Gauss-Legendre after r = r_min + t^2) against the ODE, to 1e-10 relative."""
    b, u = b_over_a * A, 0.5
    expected = _contact_time_ivp(b, k, u)
    assert float(sc.soft_sphere_contact_time(b, A, k, u)) == pytest.approx(expected, rel=1e-10)


def test_contact_time_is_the_half_period_head_on_and_zero_for_a_miss():
    assert float(sc.soft_sphere_contact_time(0.0, A, 1e6, 3.0)) == pytest.approx(np.pi / 1e3, rel=1e-14)
    assert float(sc.soft_sphere_contact_time(A, A, 1e6, 3.0)) == 0.0
    with pytest.raises(ValueError, match="penetration"):
        sc.soft_sphere_contact_time(0.01, A, 1.0, 1.0)


@pytest.mark.parametrize("masses", [(1.0, 1.0), (1.0, 3.0), (17.9, 0.0053), (1e-3, 1e3)])
def test_mujocos_contact_force_is_the_linear_spring_to_round_off(masses):
    """The force law the prediction models: relative normal acceleration k delta (d aref with aref = -k/d delta, R =
    (1 - d)/d A), whatever the masses and the approach speed; no tangential part."""
    model = HARD.build(HARD.resolve(HARD.case("head-on"), {}))
    data = mujoco.MjData(model)
    model.body("projectile").mass[0], model.body("target").mass[0] = masses
    mujoco.mj_setConst(model, data)
    k = -float(model.geom("projectile").solref[0])
    for delta in (1e-6, 1e-4):
        for speed in (0.0, 1.0):
            s = HARD._state(model, data.qpos, data.qvel)
            s["x1"][:] = np.array([-0.6, 0.8, 0.0]) * (A - delta)
            s["x2"][:] = 0.0
            s["v1"][:] = [speed, 0, 0]
            s["v2"][:] = 0.0
            mujoco.mj_forward(model, data)
            acc = data.qacc[0:3] - data.qacc[6:9]
            n = s["x1"] / np.linalg.norm(s["x1"])
            normal = acc @ n
            assert normal == pytest.approx(k * (A - np.linalg.norm(s["x1"])), rel=1e-14)
            assert np.linalg.norm(acc - normal * n) <= 1e-11 * abs(normal)


@pytest.mark.parametrize("case", ["head-on", "equal-mass", "grazing"])
def test_contact_time_catches_a_stiffness_change_of_1e_8(case):
    """Unperturbed: the check passes with room (measured <= 2.4e-10 against 2.5e-9); the simulated stiffness
    scaled by 1 + 1e-8 moves the contact time by 5e-9 relative, and it fails (as `rigidbench power` runs it)."""
    run = HARD.run(case)
    (base,) = [o for o in run.outcomes if o.check.name == "contact-time"]
    assert base.passed and base.error < 0.2 * base.check.tolerance
    for delta in (1e-6, 1e-8):
        run = HARD.run(case, perturb=Perturbation("contact-stiffness", delta))
        (o,) = [o for o in run.outcomes if o.check.name == "contact-time"]
        assert not o.passed
        assert o.error == pytest.approx(delta / 2, rel=0.1)
