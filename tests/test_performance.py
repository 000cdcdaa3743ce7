"""The fast paths (issue 8) against plain reference implementations: same numbers, bit for bit."""

import json
import math

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from mujoco import rollout

from rigidbench import cli, frames, registry, runner
from rigidbench.settings import profile, read_settings
from rigidbench.simulate import get_state, simulate

VOLATILE = ("wall_time",)


def _quat_to_matrix_reference(q):
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )


@pytest.mark.parametrize("shape", [(4,), (50, 4), (3, 5, 4)])
def test_quat_to_matrix_in_place_equals_stacking(shape):
    q = np.random.default_rng(0).normal(size=shape)
    np.testing.assert_array_equal(frames.quat_to_matrix(q), _quat_to_matrix_reference(q))


def test_simulate_writes_rollout_states_in_place_equal_to_a_plain_rollout():
    scenario = registry.get("heavy-top")
    model = scenario.build(scenario.resolve(scenario.case("nutation")))
    data = scenario.start(model)
    state0 = get_state(model, data)
    traj = simulate(model, data, 0.05)
    np.testing.assert_array_equal(get_state(model, data), state0)  # `data` stays at the initial state
    states, _ = rollout.rollout(model, data, state0[None], nstep=len(traj.time) - 1)
    expected = np.concatenate([state0[None], states[0]])
    np.testing.assert_array_equal(traj.time, expected[:, 0])
    np.testing.assert_array_equal(traj.qpos, expected[:, 1 : 1 + model.nq])
    np.testing.assert_array_equal(traj.qvel, expected[:, 1 + model.nq : 1 + model.nq + model.nv])


def test_cases_on_two_threads_give_the_rows_of_one_thread_in_job_order():
    settings = profile("reference")
    jobs = runner.plan(["heavy-top:nutation", "heavy-top:fast-precession", "pendulum:small-amplitude"], {}, settings)
    seen = []
    one = [r for _, rows in runner.execute(jobs, settings) for r in rows]
    threaded = sorted(runner.execute(jobs, settings, workers=2, progress=lambda i, n, job: seen.append(i)))
    two = [r for _, rows in threaded for r in rows]  # rows come as jobs complete; each names its job's index
    strip = [{k: v for k, v in r.items() if k not in VOLATILE} for r in one]
    assert strip == [{k: v for k, v in r.items() if k not in VOLATILE} for r in two]
    assert sorted(seen) == [0, 1, 2]


def test_closing_a_threaded_run_early_cancels_the_cases_not_started():
    settings = profile("reference")
    jobs = runner.plan(["heavy-top"], {}, settings)
    batches = runner.execute(jobs, settings, workers=2)
    assert next(batches)
    batches.close()  # what the CLI does on SIGINT/SIGTERM; must return at once, leaving no queue behind


def _pendulum_deviation_reference(env, measured, predicted):
    return float(np.abs(measured - predicted).max() / env.prediction["_scale"])


@pytest.mark.parametrize("pendulum_env", ["rigidbench/SimplePendulum-v0", "rigidbench/PendulumChain-v0"])
def test_pendulum_deviation_over_floats_equals_numpy(pendulum_env):
    env = gym.make(pendulum_env).unwrapped
    env.reset(seed=0)
    rng = np.random.default_rng(1)
    n = env.model.nq
    for _ in range(200):
        measured, predicted = rng.normal(size=n), rng.normal(size=n)
        assert env.deviation(measured, predicted) == _pendulum_deviation_reference(env, measured, predicted)
    nan = np.zeros(n)
    nan[n // 2] = np.nan
    assert math.isnan(env.deviation(nan, np.zeros(n)))


@pytest.mark.parametrize("rotor_env", ["rigidbench/FreeSymmetricTop-v0", "rigidbench/FreeAsymmetricTop-v0"])
def test_rotor_deviation_over_floats_equals_numpy(rotor_env):
    """|omega - omega_theory| / |omega_theory| over three Python floats, against numpy's vector formula."""
    env = gym.make(rotor_env).unwrapped
    env.reset(seed=0)
    rng = np.random.default_rng(2)
    worst = 0.0
    for _ in range(2000):
        measured, predicted = rng.normal(size=3), rng.normal(size=3)
        diff = measured - predicted
        expected = float(np.sqrt(diff @ diff / (predicted @ predicted)))
        got = env.deviation(measured.tolist(), predicted.tolist())
        worst = max(worst, abs(got - expected) / expected)
    assert worst <= 4e-16  # numpy's dot may sum in another order: an ulp or two at most


def test_observation_fast_paths_equal_the_state_they_copy(env_id):
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    for _ in range(3):
        obs, *_ = env.step(env.action_space.sample())
        # A fresh array every step (a caller may keep it), equal to the observation read afresh.
        assert not np.shares_memory(obs, env.data.qpos) and not np.shares_memory(obs, env.data.qvel)
        np.testing.assert_array_equal(obs, env.observe())


def test_rotor_views_follow_a_replaced_data():
    """rigidbench.suite binds an env to dm_control's MjData: observation and torque must follow it."""
    env = gym.make("rigidbench/HeavyTop-v0").unwrapped
    env.reset(seed=0)
    other = mujoco.MjData(env.model)
    other.qpos[:4] = [0.0, 1.0, 0.0, 0.0]
    env.data = other
    np.testing.assert_array_equal(env.observe()[:4], [0.0, 1.0, 0.0, 0.0])
    env.apply_action(np.full(3, 0.01))
    np.testing.assert_array_equal(other.xfrc_applied[env.model.body("top").id, 3:6], np.full(3, 0.01))


def test_cli_jobs_must_be_a_positive_integer_and_do_not_change_the_rows(tmp_path, capsys):
    for bad in ("0", "-1", "two"):
        with pytest.raises(SystemExit) as exc:
            cli.main(["run", "--jobs", bad, "heavy-top:nutation"])
        assert exc.value.code == 2
    outputs = []
    for jobs in ("1", "2"):
        path = tmp_path / f"jobs{jobs}.json"
        assert (
            cli.main(
                [
                    "run",
                    "--quiet",
                    "--jobs",
                    jobs,
                    "heavy-top:nutation",
                    "pendulum:small-amplitude",
                    "--json",
                    str(path),
                ]
            )
            == 0
        )
        rows = json.loads(path.read_text())["results"]
        outputs.append([{k: v for k, v in r.items() if k not in VOLATILE} for r in rows])
    assert outputs[0] == outputs[1]


def test_one_quaternion_takes_the_float_path_with_the_bits_of_the_vectorised_one():
    q = np.random.default_rng(2).normal(size=(20_000, 4)) * np.random.default_rng(3).uniform(0.1, 10, (20_000, 1))
    batched = frames.quat_to_matrix(q)
    for i in range(len(q)):
        np.testing.assert_array_equal(frames.quat_to_matrix(q[i]), batched[i])
    np.testing.assert_array_equal(frames.quat_to_matrix(q[:1]), batched[:1])


@pytest.mark.parametrize("profile_name", ["reference", "mujoco-default"])
def test_skipping_idle_stages_leaves_every_state_bit_for_bit_the_same(scenario, profile_name):
    """`Scenario.build` switches off the stages that can do nothing (settings.idle_stages); 300 steps of every
    scenario's first case, pushed by a generalised force so the state moves, are identical with them on."""
    case = scenario.cases[0]
    model = scenario.build(scenario.resolve(case), profile(profile_name))
    skipped = model.opt.disableflags
    states = {}
    for flags in (skipped, 0):
        model.opt.disableflags = flags
        data = scenario.start(model)
        data.qfrc_applied[:] = 1e-3
        mujoco.mj_step(model, data, nstep=300)
        states[flags] = get_state(model, data)
    np.testing.assert_array_equal(states[skipped], states[0])


def test_idle_stages_finds_what_can_collide_or_constrain():
    from rigidbench.settings import idle_stages

    def stages(body):
        return idle_stages(mujoco.MjModel.from_xml_string(f"<mujoco><worldbody>{body}</worldbody></mujoco>"))

    free = '<body><freejoint/><geom size=".1" contype="{}" conaffinity="{}"/></body>'
    assert stages(free.format(0, 0) + free.format(0, 0)) == ("contact", "constraint")
    assert stages(free.format(1, 0) + free.format(0, 1)) == ()  # contype of one meets conaffinity of the other
    assert stages(free.format(2, 0) + free.format(0, 1)) == ("contact", "constraint")  # no common bit
    # Two geoms of one body never collide; a limited joint is a constraint.
    one_body = '<body><joint type="hinge" range="-1 1"/><geom size=".1"/><geom size=".1" pos=".3 0 0"/></body>'
    assert stages(one_body) == ("contact",)
    for slug, disabled in (("pendulum", ("contact", "constraint")), ("hard-spheres", ())):
        scenario = registry.get(slug)
        assert set(read_settings(scenario.build(scenario.resolve(scenario.cases[0])))["disabled"]) == set(disabled)


# ---- the percussion envs (rigidbench.envs.planar.BlowEnv): float fast paths against the PlanarMotion arrays ----

PERCUSSION_ENVS = {
    "rigidbench/StruckStick-v0": {"length": 1.7},
    "rigidbench/BallStick-v0": {"length": 1.7},
    "rigidbench/MarbleShot-v0": {"length": 1.7},
    "rigidbench/CueStrike-v0": {"mu": 0.3},
    "rigidbench/CushionRebound-v0": {"mu": 0.3},
    "rigidbench/PivotedStick-v0": {"length": 1.7},
}


def _percussion_reference_observation(env):
    """`BlowEnv.observe` (and `CueStrikeEnv.observe`) as it was before the float fast path (issue 8):
    `PlanarMotion`'s numpy arrays for the current state."""
    from rigidbench.envs.cue_strike import CueStrike, CueStrikeEnv
    from rigidbench.envs.planar import body_state

    s = body_state(env.model, env.data, env.body)
    if isinstance(env, CueStrikeEnv):
        slip = CueStrike.slip(env.model, s)[0]
        height = s.com_W[0, 2] - env.prediction["_rest_height"]
        return np.array([s.com_W[0, 0], height, s.v_W[0, 0], s.v_W[0, 2], s.omega_W[0, 1], slip])
    return np.array([*s.com_W[0, :2], s.heading[0], *s.v_W[0, :2], s.omega_W[0, 2]])


def _percussion_reference_measure(env, obs):
    from rigidbench.envs.ball_stick import BallStickEnv
    from rigidbench.envs.cue_strike import CueStrikeEnv
    from rigidbench.envs.pivoted_stick import PivotedStickEnv

    if isinstance(env, CueStrikeEnv):
        return obs[[0, 2, 5]]
    if isinstance(env, BallStickEnv):
        return obs[[3, 5]]
    if isinstance(env, PivotedStickEnv):
        return np.array([obs[2], np.hypot(obs[0], obs[1])])
    return obs[:3]


def _percussion_reference_deviation(env, measured, predicted):
    from rigidbench.envs.ball_stick import BallStickEnv
    from rigidbench.envs.cue_strike import CueStrikeEnv
    from rigidbench.envs.pivoted_stick import PivotedStickEnv

    measured, predicted = np.asarray(measured), np.asarray(predicted)
    if isinstance(env, CueStrikeEnv):
        theory = env.prediction["_theory"]
        return float(abs(measured[0] - predicted[0]) / max(abs(theory.skid_distance), theory.radius))
    if isinstance(env, PivotedStickEnv):
        dh = (measured[0] - predicted[0] + np.pi) % (2 * np.pi) - np.pi
        return float(abs(dh) / np.pi + measured[1] / env.params["length"])
    if np.isnan(predicted).any():
        return 0.0
    if isinstance(env, BallStickEnv):
        stick = env.prediction["_theory"].stick
        return float(
            abs(measured[0] - predicted[0]) / stick.com_velocity
            + abs(measured[1] - predicted[1]) / abs(stick.angular_velocity)
        )
    dx, dy = measured[0] - predicted[0], measured[1] - predicted[1]
    dh = (measured[2] - predicted[2] + np.pi) % (2 * np.pi) - np.pi
    return float((abs(dx) + abs(dy)) / env.params["length"] + abs(dh) / np.pi)


def _reference_wrench(env, action):
    from rigidbench.envs.cue_strike import CueStrikeEnv

    a = np.clip(action, -1.0, 1.0) * env.action_scale  # the physical (SI) wrench of the normalised action
    return [a[0], 0.0, 0.0, 0.0, a[1], 0.0] if isinstance(env, CueStrikeEnv) else [a[0], a[1], 0.0, 0.0, 0.0, a[2]]


# The pose deviations wrap a heading difference d as (d + pi) % 2 pi - pi, exact only to an ulp of pi: a heading
# one ulp apart (math.atan2 against numpy's arctan2, whose SIMD loops on AVX-512 differ from libm by <= 1 ulp)
# may move the deviation by ulp(pi) / pi = 1.4e-16 however small it is. The end-to-end reward is compared to that.
WRAP_ATOL = 2 * np.spacing(np.pi) / np.pi


@pytest.mark.parametrize("percussion_env_id", list(PERCUSSION_ENVS))
def test_percussion_float_paths_equal_the_planar_motion_arrays(percussion_env_id):
    """Observation, reward and info of every percussion env over every case (plus one with other parameters),
    under zero, random, boundary and out-of-range actions, against the numpy/PlanarMotion hooks they replaced:
    observation and measured observables to within a few ulps (rtol 1e-14), the deviation bit for bit from the
    same measured values (and end to end to rtol 1e-14 plus `WRAP_ATOL`), the wrench in xfrc_applied bit for bit."""
    env = gym.make(percussion_env_id).unwrapped
    rng = np.random.default_rng(8)
    high = env.action_space.high
    episodes = [{"case": c.name} for c in env.scenario.cases] + [{"params": PERCUSSION_ENVS[percussion_env_id]}]
    worst_rel, worst_abs = 0.0, 0.0

    def check(obs, reward, info):
        nonlocal worst_rel, worst_abs
        ref_obs = _percussion_reference_observation(env)
        ref_measured = _percussion_reference_measure(env, ref_obs)
        measured, predicted = list(info["measured"].values()), list(info["predicted"].values())
        assert all(type(v) is float for v in measured)
        got, want = np.array([*obs, *measured]), np.array([*ref_obs, *ref_measured])
        np.testing.assert_allclose(got, want, rtol=1e-14, atol=0)
        differ = got != want
        worst_rel = max(worst_rel, float(np.max(np.abs(got - want)[differ] / np.abs(want[differ]), initial=0.0)))
        # The deviation's own arithmetic: the same bits from the same measured values ...
        assert info["deviation"] == _percussion_reference_deviation(env, measured, predicted) == -reward
        # ... and end to end, from the reference observation.
        ref_deviation = _percussion_reference_deviation(env, ref_measured, predicted)
        assert info["deviation"] == pytest.approx(ref_deviation, rel=1e-14, abs=WRAP_ATOL)
        worst_abs = max(worst_abs, abs(info["deviation"] - ref_deviation))

    for seed, options in enumerate(episodes):
        obs, info = env.reset(seed=seed, options=options)
        check(obs, info["reward_deviation"], info)
        for k in range(300):
            kind = k % 4
            if kind == 0:
                action = np.zeros(high.shape)
            elif kind == 1:
                action = rng.uniform(-high, high)
            elif kind == 2:
                action = rng.uniform(-5 * high, 5 * high)  # mostly out of range: clipped
            else:
                action = rng.choice([-1.0, 1.0], size=high.shape) * high
            obs, reward, terminated, truncated, info = env.step(action)
            assert not terminated
            check(obs, reward, info)
            np.testing.assert_array_equal(
                env.data.xfrc_applied[env.model.body(env.body).id], _reference_wrench(env, action)
            )
            if truncated:
                break
    print(
        f"\n{percussion_env_id}: largest difference from the PlanarMotion reference: observation and measured "
        f"{worst_rel:.1e} relative, deviation {worst_abs:.1e} absolute"
    )


def test_blow_env_views_follow_a_replaced_data():
    """rigidbench.suite binds a percussion env to dm_control's MjData: observation and wrench must follow it."""
    env = gym.make("rigidbench/StruckStick-v0").unwrapped
    env.reset(seed=0)
    other = mujoco.MjData(env.model)
    other.qpos[:7] = [0.5, -0.25, 0.0, 1.0, 0.0, 0.0, 1.0]  # turned by pi/2 about z (normalised by the env)
    other.qvel[:6] = [1.0, 2.0, 0.0, 0.0, 0.0, 3.0]
    env.data = other
    np.testing.assert_allclose(env.observe(), [0.5, -0.25, np.pi / 2, 1.0, 2.0, 3.0], rtol=1e-15)
    env.apply_action(np.array([0.01, 0.02, 0.03]))
    np.testing.assert_array_equal(other.xfrc_applied[env.model.body("stick").id], [0.01, 0.02, 0, 0, 0, 0.03])


# ---- HardSpheres-v0 and TopPrecession-v0 (issue 8): cached views and float paths against the hooks they replaced ----


def _random_actions(rng, high, n):
    """Zero, in-range, mostly out-of-range (clipped) and boundary actions, in turn."""
    for k in range(n):
        kind = k % 4
        if kind == 0:
            yield np.zeros(high.shape)
        elif kind == 1:
            yield rng.uniform(-high, high)
        elif kind == 2:
            yield rng.uniform(-5 * high, 5 * high)
        else:
            yield rng.choice([-1.0, 1.0], size=high.shape) * high


def _hard_spheres_reference(env):
    """`HardSpheresEnv`'s observation, measured r and deviation as they were before the fast path (issue 8):
    `HardSpheres._state`'s slices looked up by name, numpy's subtraction and norm."""
    from rigidbench.envs.hard_spheres import HardSpheres

    s = HardSpheres._state(env.model, env.data.qpos, env.data.qvel)
    obs = np.concatenate([s["x1"], s["x2"], s["v1"], s["v2"]])
    measured = obs[0:3] - obs[3:6]
    return obs, measured, lambda predicted: float(np.linalg.norm(measured - predicted) / env.prediction["_a"])


def test_hard_spheres_fast_paths_equal_the_numpy_hooks():
    """Observation, measured r and deviation of HardSpheres-v0 (frame_skip 1 and the default 40) over every case
    and one with other parameters, under zero, random, boundary and out-of-range actions: the observation, r and
    the applied force bit for bit; the deviation (math.sqrt of three squares against numpy's norm, whose BLAS dot
    may round otherwise) to rtol 1e-14."""
    worst = 0.0
    for frame_skip in (1, 40):
        env = gym.make("rigidbench/HardSpheres-v0", frame_skip=frame_skip).unwrapped
        rng = np.random.default_rng(8)
        high = env.action_space.high
        episodes = [{"case": c.name} for c in env.scenario.cases] + [{"params": {"b": 0.013, "m1": 2.0}}]
        for seed, options in enumerate(episodes):
            obs, info = env.reset(seed=seed, options=options)
            for k, action in enumerate(_random_actions(rng, high, 400 if frame_skip == 1 else 60)):
                if k:
                    obs, reward, terminated, truncated, info = env.step(action)
                    assert not terminated and reward == -info["deviation"]
                    np.testing.assert_array_equal(
                        env.data.xfrc_applied[env.model.body("projectile").id], [*np.clip(action, -high, high), 0, 0, 0]
                    )
                ref_obs, ref_measured, ref_deviation = _hard_spheres_reference(env)
                np.testing.assert_array_equal(obs, ref_obs)
                assert list(info["measured"].values()) == ref_measured.tolist()
                predicted = np.array(list(info["predicted"].values()))
                want = ref_deviation(predicted)
                assert info["deviation"] == pytest.approx(want, rel=1e-14, abs=0)
                if want:
                    worst = max(worst, abs(info["deviation"] - want) / want)
                if k and truncated:
                    break
    print(f"\nHardSpheres-v0: largest relative difference of the deviation from numpy's norm: {worst:.1e}")


def test_hard_spheres_views_follow_a_replaced_data():
    env = gym.make("rigidbench/HardSpheres-v0").unwrapped
    env.reset(seed=0)
    other = mujoco.MjData(env.model)
    other.qpos[:] = np.arange(env.model.nq)
    env.data = other
    ref_obs, _, _ = _hard_spheres_reference(env)
    np.testing.assert_array_equal(env.observe(), ref_obs)
    env.apply_action(np.array([0.1, 0.2, 0.3]))
    np.testing.assert_array_equal(other.xfrc_applied[env.model.body("projectile").id], [0.1, 0.2, 0.3, 0, 0, 0])


def _top_precession_reference_terms(env):
    """`TopPrecessionEnv._terms` as it was before the float path (issue 8): `_state`'s full dict, then the
    relative errors."""
    s = env._state()
    target = env.target
    rate = abs(s["phi_dot"] - target["precession"]) / abs(target["precession"])
    tilt = abs(s["theta"] - target["tilt"]) / target["tilt"]
    return {"rate": -min(rate, 10.0), "tilt": -min(tilt, 10.0)}


def _top_precession_reference_rollout(env):
    """The baseline's rewards from the current (initial) state, simulated as `ClosedLoopTask._reference_rewards`
    did, with the reference terms, on a copy of the MjData."""
    own = env.data
    env.data = mujoco.MjData(env.model)
    mujoco.mj_copyData(env.data, env.model, own)
    body = env.model.body("top").id
    rewards = []
    try:
        for _ in range(env._nsteps):
            env.data.xfrc_applied[body, 3:6] = env.theory_action() * env.action_scale
            mujoco.mj_step(env.model, env.data, env.frame_skip)
            assert np.isfinite(env.data.qvel).all()
            rewards.append(sum(_top_precession_reference_terms(env).values()))
    finally:
        env.data = own
    return rewards


def test_top_precession_fast_paths_equal_the_state_dict():
    """Observation, reward terms, regret and info of TopPrecession-v0 over several episodes and tilts, under zero,
    random, boundary and out-of-range torques, against `_state`'s dict and the concatenated observation they
    replaced, and the regret's reference rollout against one scored by the reference terms: all bit for bit
    (the float path keeps MuJoCo's quaternion-to-matrix and numpy's matmul, the steps BLAS could round otherwise)."""
    env = gym.make("rigidbench/TopPrecession-v0", duration=0.3).unwrapped
    rng = np.random.default_rng(8)
    high = env.action_space.high
    episodes = [{}, {"target": {"tilt": 0.3}}, {"target": {"tilt": 1.2}}, {"params": {"spin": 150.0}}]
    for seed, options in enumerate(episodes):
        obs, info = env.reset(seed=seed, options=options)
        assert env._reference.tolist() == _top_precession_reference_rollout(env)
        for action in _random_actions(rng, high, env._nsteps):
            reference = env._reference[env._k]
            obs, reward, terminated, truncated, info = env.step(action)
            assert not terminated
            ref_obs = np.concatenate(
                (env.data.qpos[:4], env.data.qvel[-3:], (env.target["precession"], env.target["tilt"]))
            )
            np.testing.assert_array_equal(obs, ref_obs)
            terms = _top_precession_reference_terms(env)
            assert {"reward_rate": terms["rate"], "reward_tilt": terms["tilt"]} == {
                k: info[k] for k in ("reward_rate", "reward_tilt")
            }
            assert reward == float(sum(terms.values())) and info["regret"] == reference - reward
            assert info["target"] == env.target and info["time"] == env.data.time and info["diverged"] is False
            assert list(info) == ["reward_rate", "reward_tilt", "regret", "target", "time", "diverged"]
        assert truncated


def test_top_precession_views_follow_a_replaced_data():
    """The theory rollout swaps `self.data` for a scratch MjData: the observation and terms must follow it."""
    env = gym.make("rigidbench/TopPrecession-v0", duration=0.05).unwrapped
    env.reset(seed=0)
    other = mujoco.MjData(env.model)
    other.qpos[:4] = [np.cos(0.2), np.sin(0.2), 0.0, 0.0]
    other.qvel[:] = [1.0, 2.0, 100.0]
    env.data = other
    np.testing.assert_array_equal(env.observe()[:7], [*other.qpos[:4], 1.0, 2.0, 100.0])
    assert env._terms(np.zeros(3)) == _top_precession_reference_terms(env)
