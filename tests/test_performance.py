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
    one = [r for rows in runner.execute(jobs, settings) for r in rows]
    threaded = runner.execute(jobs, settings, workers=2, progress=lambda i, n, job: seen.append(i))
    two = [r for rows in threaded for r in rows]
    strip = [{k: v for k, v in r.items() if k not in VOLATILE} for r in one]
    assert strip == [{k: v for k, v in r.items() if k not in VOLATILE} for r in two]
    assert seen == [0, 1, 2]


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
        assert env._deviation(measured, predicted) == _pendulum_deviation_reference(env, measured, predicted)
    nan = np.zeros(n)
    nan[n // 2] = np.nan
    assert math.isnan(env._deviation(nan, np.zeros(n)))


def test_observation_fast_paths_equal_the_state_they_copy(env_id):
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    for _ in range(3):
        obs, *_ = env.step(env.action_space.sample())
        # A fresh array every step (a caller may keep it), equal to the observation read afresh.
        assert not np.shares_memory(obs, env.data.qpos) and not np.shares_memory(obs, env.data.qvel)
        np.testing.assert_array_equal(obs, env._observation())


def test_rotor_views_follow_a_replaced_data():
    """rigidbench.suite binds an env to dm_control's MjData: observation and torque must follow it."""
    env = gym.make("rigidbench/HeavyTop-v0").unwrapped
    env.reset(seed=0)
    other = mujoco.MjData(env.model)
    other.qpos[:4] = [0.0, 1.0, 0.0, 0.0]
    env.data = other
    np.testing.assert_array_equal(env._observation()[:4], [0.0, 1.0, 0.0, 0.0])
    env._apply_action(np.full(3, 0.01))
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
        assert read_settings(scenario.build(scenario.resolve(scenario.cases[0])))["disabled"] == disabled
