"""The passive-force route for forces MuJoCo has no element for (`rigidbench.forces`): what it keeps (RK4's order),
what the alternative loses (a force held over each step is first order), and that it stays out of other models'
way."""

from __future__ import annotations

import gc

import mujoco
import numpy as np
import pytest

from rigidbench import engines, forces, simulate

_PAIR = """<mujoco>
  <option integrator="RK4" timestep="{dt}" gravity="0 0 0"/>
  <worldbody>
    <body name="sun"><freejoint/><inertial pos="0 0 0" mass="{m1}" diaginertia="1 1 1"/></body>
    <body name="planet" pos="1 0 0"><freejoint/><inertial pos="0 0 0" mass="{m2}" diaginertia="1 1 1"/></body>
  </worldbody>
  <custom>{custom}</custom>
</mujoco>"""
_DECLARED = (
    '<text name="rigidbench:inverse-square" data="sun planet"/><numeric name="rigidbench:inverse-square" data="{k}"/>'
)
M1, M2, K = 1.0, 0.25, -2.0  # attractive: k < 0


def _model(dt: float, k: float = K, custom: str | None = None) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(
        _PAIR.format(dt=dt, m1=M1, m2=M2, custom=_DECLARED.format(k=k) if custom is None else custom)
    )


def _circular(model: mujoco.MjModel) -> tuple[mujoco.MjData, float]:
    """A circular relative orbit of radius 1 about the fixed CM (docs/theory.md K1, K2); returns its angular rate."""
    data = mujoco.MjData(model)
    mu = 1 / (1 / M1 + 1 / M2)
    omega = np.sqrt(-K / (mu * 1.0**3))  # mu r omega^2 = |k| / r^2
    v_rel = omega * 1.0
    data.qvel[0:3] = [0, -M2 / (M1 + M2) * v_rel, 0]
    data.qvel[6:9] = [0, M1 / (M1 + M2) * v_rel, 0]
    data.qpos[0:3] = [-M2 / (M1 + M2), 0, 0]
    data.qpos[7:10] = [M1 / (M1 + M2), 0, 0]
    mujoco.mj_forward(model, data)
    return data, omega


def _orbit_error(dt: float, held: bool = False) -> float:
    """Relative-position error after one period of the circular orbit, stepping at `dt`."""
    model = _model(dt, custom="" if held else None)
    data, omega = _circular(model)
    period = 2 * np.pi / omega
    nstep = round(period / dt)
    if held:  # the rejected route: the force from the state at the start of each step, held over the step
        pair = forces.InverseSquare(np.array([1]), np.array([2]), np.array([K]))
        for _ in range(nstep):
            f = pair.forces(data.xipos)[0]
            data.xfrc_applied[2, :3], data.xfrc_applied[1, :3] = f, -f
            mujoco.mj_step(model, data)
        mujoco.mj_forward(model, data)
        r = data.xipos[2] - data.xipos[1]
    else:
        traj = simulate.simulate(model, data, nstep * dt)
        r = traj.qpos[-1, 7:10] - traj.qpos[-1, 0:3]
    angle = omega * nstep * dt
    return float(np.linalg.norm(r - [np.cos(angle), np.sin(angle), 0.0]))


def test_callback_keeps_rk4_fourth_order():
    """RK4 with the force inside mj_passive: the one-period error falls 16x per halving (order 4 +- 0.3)."""
    e = [_orbit_error(dt) for dt in (2e-2, 1e-2, 5e-3)]
    orders = np.log2(np.array(e[:-1]) / np.array(e[1:]))
    assert np.all(np.abs(orders - 4) < 0.3), (e, orders)


def test_force_held_over_the_step_is_first_order():
    """The rejected route (xfrc_applied set between steps) is first order whatever the integrator."""
    e = [_orbit_error(dt, held=True) for dt in (2e-3, 1e-3, 5e-4)]
    orders = np.log2(np.array(e[:-1]) / np.array(e[1:]))
    assert np.all(np.abs(orders - 1) < 0.2), (e, orders)


def test_energy_and_momentum_of_an_eccentric_orbit():
    """An eccentric orbit (speed 0.8 of circular): energy (kinetic + k/r) and momentum kept to RK4's error."""
    model = _model(1e-3)
    data, _ = _circular(model)
    data.qvel[:] *= 0.8
    mujoco.mj_forward(model, data)
    pair = forces.inverse_square(model)
    traj = simulate.simulate(model, data, 20.0)
    e = []
    for qpos, qvel in zip(traj.qpos[::100], traj.qvel[::100], strict=True):
        data.qpos[:], data.qvel[:] = qpos, qvel
        mujoco.mj_forward(model, data)
        kinetic = 0.5 * M1 * qvel[0:3] @ qvel[0:3] + 0.5 * M2 * qvel[6:9] @ qvel[6:9]
        e.append(kinetic + pair.potential_energy(data.xipos))
    e = np.array(e)
    assert np.max(np.abs(e - e[0])) < 1e-9 * abs(e[0])  # RK4 at omega dt = 4e-3: ~(omega dt)^4 per orbit
    p = M1 * traj.qvel[:, 0:3] + M2 * traj.qvel[:, 6:9]
    assert np.max(np.abs(p)) < 1e-12  # equal and opposite forces: the CM stays at rest to round-off


def test_threads_and_rollout_agree_and_one_thread_is_used():
    """`final_states` steps a declared model on one thread (the callback holds the GIL), with the bits of a loop."""
    model = _model(1e-2)
    data, _ = _circular(model)
    states0 = simulate.initial_states(model, data, np.repeat(data.qpos[None], 3, 0), np.repeat(data.qvel[None], 3, 0))
    assert forces.threads_for(model, 8) == 1 and forces.threads_for(_model(1e-2, custom=""), 8) == 8
    out, diverged = simulate.final_states(model, states0, 200, nthread=2)
    loop = mujoco.MjData(model)
    mujoco.mj_setState(model, loop, states0[0], mujoco.mjtState.mjSTATE_FULLPHYSICS)
    for _ in range(200):
        mujoco.mj_step(model, loop)
    assert not diverged.any()
    np.testing.assert_array_equal(out[:, 1:15], np.repeat(np.concatenate([loop.qpos])[None], 3, 0))


def test_models_compile_while_the_callback_is_installed():
    """MuJoCo's compiler runs mj_forward on a model Python has no object for yet: the installed callback lets it
    through (a plain Python callable would fail every compile in the process while a declared model lives)."""
    declared = _model(1e-2)
    assert forces.attach(declared) and mujoco.get_mjcb_passive() is forces._passive
    spec = mujoco.MjSpec.from_string(_PAIR.format(dt=1e-2, m1=M1, m2=M2, custom=_DECLARED.format(k=K)))
    other = spec.compile()
    assert forces.attach(other)
    data, _ = _circular(other)
    mujoco.mj_step(other, data)
    assert np.any(data.qfrc_passive != 0)


def test_undeclared_models_are_untouched_and_the_callback_leaves_with_the_last_model():
    plain = _model(1e-2, custom="")
    assert not forces.attach(plain)
    declared = _model(1e-2)
    assert forces.attach(declared) and forces.attach(declared)  # idempotent
    assert mujoco.get_mjcb_passive() is forces._passive
    d = mujoco.MjData(plain)
    d.qvel[6:9] = [0, 1, 0]
    mujoco.mj_step(plain, d)
    np.testing.assert_array_equal(d.qfrc_passive, 0.0)  # no force where none is declared
    del declared
    gc.collect()
    assert mujoco.get_mjcb_passive() is None


def test_another_callback_is_never_overwritten():
    def theirs(m, d):
        pass

    model = _model(1e-2)  # compiled first: a Python callable (theirs) cannot see a model MuJoCo is compiling
    mujoco.set_mjcb_passive(theirs)
    try:
        with pytest.raises(RuntimeError, match="another passive-force callback"):
            forces.attach(model)
        assert mujoco.get_mjcb_passive() is theirs
    finally:
        mujoco.set_mjcb_passive(None)


def _declare(names: str, strengths: str | None) -> str:
    text = f'<text name="rigidbench:inverse-square" data="{names}"/>'
    return text if strengths is None else text + f'<numeric name="rigidbench:inverse-square" data="{strengths}"/>'


@pytest.mark.parametrize(
    ("custom", "match"),
    [
        (_declare("sun", "1"), "pairs"),
        (_declare("sun moon", "1"), "'moon'"),
        (_declare("sun sun", "1"), "twice"),
        (_declare("sun planet", None), "missing"),
        (_declare("sun planet", "1 2"), "2 strengths"),
        (_declare("sun planet", "0"), "nonzero"),
    ],
)
def test_malformed_declarations_are_refused_before_simulating(custom, match):
    with pytest.raises(ValueError, match=match):
        forces.attach(_model(1e-2, custom=custom))


@pytest.mark.parametrize("name", ["warp", "mjx"])
def test_batched_engines_refuse_a_declared_force(name):
    with pytest.raises(engines.EngineRefused, match=f"engine {name} has no passive-force callback"):
        forces.refuse_on(name, _model(1e-2))
    forces.refuse_on(name, _model(1e-2, custom=""))  # nothing declared: nothing refused


def test_free_body_fast_path_equals_mj_applyFT():
    """The vectorised add for free bodies gives mj_applyFT's generalised forces to the last bit but one."""
    model = _model(1e-2)
    pair = forces.inverse_square(model)
    assert pair.free_dofs is not None
    data, _ = _circular(model)
    data.qpos[7:10] = [0.3, 0.8, -0.2]
    mujoco.mj_forward(model, data)
    fast, general = np.zeros(model.nv), np.zeros(model.nv)
    data.qfrc_passive[:] = 0
    pair.apply(model, data)
    fast[:] = data.qfrc_passive
    data.qfrc_passive[:] = 0
    forces.InverseSquare(pair.first, pair.second, pair.k).apply(model, data)
    general[:] = data.qfrc_passive
    np.testing.assert_allclose(fast, general, rtol=1e-14, atol=1e-15)
    assert np.any(fast != 0)


def test_a_coincident_pair_feels_no_force_rather_than_nan():
    """At r = 0 the inverse-square force has no direction (a model's qpos0 can put both bodies at the origin before a
    scenario places them): zero, so qfrc_passive stays finite."""
    pair = forces.InverseSquare(np.array([1]), np.array([2]), np.array([K]))
    xipos = np.zeros((3, 3))
    with np.errstate(all="raise"):
        np.testing.assert_array_equal(pair.forces(xipos), 0.0)
    xipos[2] = [2.0, 0.0, 0.0]
    np.testing.assert_allclose(pair.forces(xipos)[0], [K / 4, 0.0, 0.0])
