"""The dm_env view of every env, and (with the `dm` extra) the dm_control suite view."""

import mujoco
import numpy as np
import pytest
from dm_env import StepType

from rigidbench import dm, registry


def test_every_env_has_a_dm_env_view_with_consistent_specs(env_id):
    env = dm.load(env_id)
    first = env.reset()
    assert first.step_type == StepType.FIRST
    env.observation_spec()["observation"].validate(first.observation["observation"])
    action = np.zeros(env.action_spec().shape)
    env.action_spec().validate(action)
    step = env.step(action)
    info = env.last_info
    if "deviation" in info:  # a validation env: MID step, reward = -deviation from theory
        assert step.step_type == StepType.MID and step.discount == 1.0
        assert step.reward == pytest.approx(-info["deviation"])
    else:  # a task: the gymnasium reward, its terms and regret in last_info; a one-shot task ends at once
        assert (step.step_type, step.discount) in ((StepType.MID, 1.0), (StepType.LAST, 0.0))
        terms = [k for k in info if k.startswith("reward_")]
        assert terms and step.reward == pytest.approx(sum(info[k] for k in terms), rel=1e-12)
        assert np.isfinite(info["regret"])
    env.reward_spec().validate(np.float64(step.reward))


def test_dm_env_episode_ends_with_a_last_step_at_the_case_duration():
    env = dm.load("heavy-top", case="nutation", frame_skip=50)
    env.reset()
    steps = 0
    while True:
        ts = env.step(np.zeros(3))
        steps += 1
        if ts.last():
            break
    assert ts.discount == 1.0  # truncation, not termination
    assert steps == int(np.ceil(env.gym_env.episode_duration / (50 * 1e-4) - 1e-9))


def test_dm_load_refuses_unknown_names():
    with pytest.raises(ValueError, match="unknown scenario"):
        dm.load("no-such-scenario")
    with pytest.raises(ValueError, match="unknown case"):
        dm.load("heavy-top", case="no-such-case")


def test_dm_control_suite_runs_the_heavy_top():
    """rigidbench.suite.load mirrors dm_control.suite.load; runs under dm_control (CI: the `dm` extra)."""
    pytest.importorskip("dm_control", reason="needs the dm extra (pip install -e '.[dm]')")
    from rigidbench import suite

    env = suite.load("heavy-top", "nutation")
    ts = env.reset()
    assert ts.first() and ts.observation["observation"].shape == (7,)
    rewards = []
    for _ in range(100):
        ts = env.step(np.zeros(env.action_spec().shape))
        rewards.append(ts.reward)
    # dm_control steps the same compiled model: the tilt tracks theory (mujoco 3.17's RK4 is 2nd order in
    # orientation, ~1e-6 rad here, hence the bound in rad/pi).
    assert max(-r for r in rewards) < 1e-5
    assert env.physics.model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4  # from the model file


def test_dm_control_suite_accepts_every_scenario():
    pytest.importorskip("dm_control", reason="needs the dm extra")
    from rigidbench import suite

    for slug, scenario in registry.scenarios().items():
        if scenario.env_id is None:  # a batch scenario (e.g. a Monte Carlo beam) has no stepping env to view
            with pytest.raises(ValueError, match="no stepping environment"):
                suite.load(slug)
            continue
        env = suite.load(slug)
        env.reset()
        env.step(np.zeros(env.action_spec().shape))


def test_dm_control_suite_applies_actions_as_the_gymnasium_env_does():
    """The suite view steps the same model through the env's own action hook: same actions, same states, bit for
    bit (dm_control's RK4 step is mj_step)."""
    pytest.importorskip("dm_control", reason="needs the dm extra")
    import gymnasium as gym

    from rigidbench import suite

    env = suite.load("heavy-top", "nutation")
    env.reset()
    gym_env = gym.make("rigidbench/HeavyTop-v0", case="nutation").unwrapped
    gym_env.reset()
    rng = np.random.default_rng(0)
    for _ in range(30):
        action = rng.uniform(-0.05, 0.05, 3)
        ts = env.step(action)
        obs, *_ = gym_env.step(action)
    np.testing.assert_array_equal(ts.observation["observation"], obs)
    assert np.abs(obs[4:] - gym_env.scenario.start(gym_env.model).qvel).max() > 1e-3  # the torque did act


def test_every_task_has_a_dm_env_view_reporting_regret(task_env_id):
    env = dm.load(task_env_id)
    ts = env.reset()
    assert set(env.last_info["target"]) == set(env.gym_env.target_names)
    ts = env.step(env.gym_env.theory_action())
    assert np.isfinite(env.last_info["regret"]) and set(env.last_info) >= {
        "reward_" + n for n in env.gym_env.reward_terms
    }
    env.observation_spec()["observation"].validate(ts.observation["observation"])


def test_dm_control_suite_runs_every_closed_loop_task_like_gymnasium(task_env_id):
    """suite.load accepts a closed-loop task id: its theory policy scores the same return as in gymnasium, over
    an episode of the same length, on the same sampled target, in each of two episodes."""
    pytest.importorskip("dm_control", reason="needs the dm extra")
    import gymnasium as gym

    from rigidbench import suite
    from rigidbench.envs.task import ClosedLoopTask

    if not issubclass(registry.env_classes()[task_env_id], ClosedLoopTask):
        with pytest.raises(ValueError, match="not a closed-loop control task"):
            suite.load(task_env_id)
        return
    env = suite.load(task_env_id, task_kwargs={"random": 0})
    gym_env = gym.make(task_env_id).unwrapped
    for _episode in range(2):  # the second starts from the env's kept start (`ScenarioEnv.load`)
        ts = env.reset()
        target = dict(env.task._env.target)
        total, steps = 0.0, 0
        while not ts.last():
            ts = env.step(env.task.theory_action(env.physics))
            total += ts.reward
            steps += 1
        assert ts.discount == 1.0
        gym_env.reset(options={"target": {k: target[k] for k in gym_env._target_ranges()}})
        assert steps == len(gym_env._reference)
        assert total == pytest.approx(gym_env._reference.sum(), rel=1e-12, abs=1e-15)


def test_dm_control_suite_refuses_an_id_that_is_not_a_closed_loop_task():
    pytest.importorskip("dm_control", reason="needs the dm extra")
    from rigidbench import suite

    with pytest.raises(ValueError, match="not a closed-loop control task"):
        suite.load("rigidbench/HeavyTop-v0")
    with pytest.raises(ValueError, match="takes no case"):
        suite.load("rigidbench/TopPrecession-v0", "nutation")


def test_dm_control_on_this_mujoco_drops_only_the_fields_mujoco_lacks():
    """The compatibility layer removes exactly the size-table entries the installed MuJoCo has no field for (the
    nine flexvert fields on 4.0, none on 3.17), and dm_control's own suite then loads and steps on it."""
    pytest.importorskip("dm_control", reason="needs the dm extra")
    from dm_control import suite as dm_suite
    from dm_control.mujoco.wrapper.mjbindings import sizes

    from rigidbench import suite

    model = mujoco.MjModel.from_xml_string("<mujoco/>")
    data = mujoco.MjData(model)
    for struct, instance in (("mjmodel", model), ("mjdata", data)):
        assert all(hasattr(instance, name) for name in sizes.array_sizes[struct])
        assert not any(hasattr(instance, name) for name in suite.DROPPED[struct])
    if mujoco.__version__.startswith("4."):
        assert sorted(suite.DROPPED["mjmodel"] + suite.DROPPED["mjdata"]) == sorted(
            [
                "flex_vertedge",
                "flex_vertedgeadr",
                "flex_vertedgenum",
                "flex_vertmetric",
                "flexvert_J_colind",
                "flexvert_J_rowadr",
                "flexvert_J_rownnz",
                "flexvert_J",
                "flexvert_length",
            ]
        )
    assert suite.fit_dm_control_to_mujoco() == {"mjmodel": [], "mjdata": []}  # a second call finds nothing
    env = dm_suite.load("cartpole", "swingup")
    env.reset()
    env.step(np.zeros(env.action_spec().shape))
