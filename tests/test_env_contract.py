"""What an RL user relies on without reading the code (issue 20): copies of an env continue exactly like it,
blowing up the simulation never pays, `terminated` is the task's own end, videos play in real time (and a one-shot
task can record its shot), and a module-qualified id works in a freshly spawned process."""

import copy
import math
import pickle
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

from rigidbench.envs.base import DEVIATION_CAP
from rigidbench.envs.task import ClosedLoopTask, ShotTask


def _actions(env, n, seed):
    rng = np.random.default_rng(seed)
    low, high = env.action_space.low, env.action_space.high
    return [low + (high - low) * rng.random(env.action_space.shape) for _ in range(n)]


def _drive(env, actions):
    out = []
    for a in actions:
        obs, reward, terminated, truncated, _ = env.step(a)
        out.append((obs.copy(), reward))
        if terminated or truncated:
            break
    return out


@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_a_copy_mid_episode_continues_exactly_like_the_original(env_id, how):
    env = gym.make(env_id)
    env.reset(seed=3)
    if not isinstance(env.unwrapped, ShotTask):
        _drive(env, _actions(env, 4, 0))  # mid-episode
    twin = copy.deepcopy(env) if how == "deepcopy" else pickle.loads(pickle.dumps(env))
    actions = _actions(env, 5, 1)
    original, copied = _drive(env, actions), _drive(twin, actions)
    assert len(original) == len(copied)
    for (o1, r1), (o2, r2) in zip(original, copied, strict=True):
        assert np.array_equal(o1, o2) and (r1 == r2 or (math.isnan(r1) and math.isnan(r2)))


def test_copies_are_independent_two_pendulums_driven_apart_end_apart():
    env = gym.make("rigidbench/SimplePendulum-v0")
    env.reset(seed=0)
    env.step(np.zeros(1))
    twin = copy.deepcopy(env)
    for _ in range(20):
        a, _, *_ = env.step(np.array([0.1]))
        b, _, *_ = twin.step(np.array([-0.1]))
    assert not np.array_equal(a, b)


def test_blowing_up_a_validation_env_never_pays(validation_env_id):
    env = gym.make(validation_env_id)
    env.reset(seed=0)
    rewards = [env.step(np.zeros(env.action_space.shape))[1] for _ in range(3)]
    inner = env.unwrapped
    inner.data.qvel[:] = np.nan  # what a blown-up integrator leaves behind
    obs, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
    assert terminated and not truncated and info["diverged"]
    # steps the episode had left (MuJoCo reset the blown-up data's time; an episode may start after a blow, t0 > 0)
    steps_left = math.ceil((inner.episode_duration - inner._time0) / inner._env_dt) - 4
    assert reward <= -DEVIATION_CAP * steps_left  # the worst the rest of the episode could have scored
    assert reward < min(rewards)
    assert {"measured", "predicted", "deviation", "reward_deviation", "time"} <= set(info)
    assert np.isfinite(obs).all()


def test_every_steps_reward_is_capped_so_divergence_is_the_worst_outcome(validation_env_id):
    env = gym.make(validation_env_id)
    env.reset(seed=0)
    for _ in range(5):
        _, reward, terminated, truncated, _ = env.step(env.action_space.high)
        assert reward >= -DEVIATION_CAP
        if terminated or truncated:
            break


def test_a_validation_episode_ends_truncated_at_the_scenarios_duration():
    env = gym.make("rigidbench/HeavyTop-v0")
    env.reset(seed=0)
    for _ in range(100_000):
        _, _, terminated, truncated, _ = env.step(np.zeros(3))
        if terminated or truncated:
            break
    assert truncated and not terminated


def test_closed_loop_tasks_say_whether_their_horizon_is_their_end(task_env_id):
    env = gym.make(task_env_id)
    inner = env.unwrapped
    if not isinstance(inner, ClosedLoopTask):
        pytest.skip("a one-shot task: its one step is the task's end (terminated)")
    env.reset(seed=0)
    for _ in range(100_000):
        _, _, terminated, truncated, _ = env.step(inner.theory_action())
        if terminated or truncated:
            break
    assert (terminated, truncated) == ((True, False) if inner.horizon_ends_task else (False, True))


def test_an_energy_transfer_episode_terminates_at_T_where_its_whole_reward_is_paid():
    """The reward is pendulum 2's energy at T and the observation counts down to T: T is the task's own end, so a
    learner must not bootstrap past it (terminated, not truncated); a tracking task's horizon is a time limit."""
    assert gym.make("rigidbench/PendulumEnergyTransfer-v0").unwrapped.horizon_ends_task
    assert not gym.make("rigidbench/TopPrecession-v0").unwrapped.horizon_ends_task
    env = gym.make("rigidbench/PendulumEnergyTransfer-v0")
    obs, _ = env.reset(seed=0)
    rewards = []
    while True:
        obs, reward, terminated, truncated, _ = env.step(np.zeros(1))
        rewards.append(reward)
        if terminated or truncated:
            break
    assert terminated and not truncated and obs[-1] == pytest.approx(0.0, abs=1e-12)
    assert all(r == 0.0 for r in rewards[:-1]) and rewards[-1] > 0.0


def test_render_fps_plays_the_simulation_in_real_time(validation_env_id):
    env = gym.make(validation_env_id)
    env.reset(seed=0)
    inner = env.unwrapped
    assert inner.metadata["render_fps"] == pytest.approx(1 / (inner.model.opt.timestep * inner.frame_skip), rel=1e-9)
    assert env.metadata["render_fps"] == inner.metadata["render_fps"]


def test_a_one_shot_task_records_its_whole_shot(task_env_id, gl_available):
    env = gym.make(task_env_id, render_mode="rgb_array_list", width=64, height=48)
    if not isinstance(env.unwrapped, ShotTask):
        pytest.skip("a closed-loop task renders a frame a step")
    env.reset(seed=0)
    assert len(env.render()) == 1
    env.step(env.unwrapped.theory_action())
    frames = env.render()
    assert len(frames) == ShotTask.SHOT_FRAMES and frames[0].shape == (48, 64, 3)
    assert not np.array_equal(frames[0], frames[-1])  # the shot moves


def test_a_module_qualified_id_works_in_a_spawned_process_that_never_imported_rigidbench():
    code = (
        "import gymnasium as gym\n"
        "envs = gym.make_vec('rigidbench:rigidbench/SimplePendulum-v0', num_envs=2, vectorization_mode='async',"
        " vector_kwargs={'context': 'spawn'})\n"
        "obs, _ = envs.reset(seed=0)\n"
        "envs.step(envs.action_space.sample())\n"
        "print(obs.shape)\n"
        "envs.close()\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "(2, 2)"
