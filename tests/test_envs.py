"""Every registered gymnasium env: the checker, headless rendering, theory-scored rewards, input checks."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from rigidbench import registry
from rigidbench.envs.task import TaskEnv


@pytest.mark.filterwarnings("ignore:.*Box observation space (minimum|maximum) value is:UserWarning")
def test_every_env_passes_gymnasiums_checker(env_id):
    """Unbounded observations (angular rates) are by design, as in gymnasium's own MuJoCo envs."""
    env = gym.make(env_id)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_every_env_renders_rgb_array_headless(env_id, gl_available):
    env = gym.make(env_id, render_mode="rgb_array", width=96, height=64)
    env.reset(seed=0)
    env.step(env.action_space.sample() * 0)
    frame = env.render()
    env.close()
    assert frame.shape == (64, 96, 3) and frame.dtype == np.uint8
    assert frame.std() > 5, "a blank frame: the camera shows nothing"


def test_zero_action_tracks_theory_and_reports_it(validation_env_id):
    """Zero action is the textbook problem: the reward (-deviation from theory) stays tiny at reference."""
    env = gym.make(validation_env_id)
    _obs, info = env.reset(seed=0)
    assert info["params"] and info["settings"]["mujoco"] and info["case"]  # the run's record, at reset
    worst = 0.0
    for _ in range(50):
        _obs, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
        assert reward == -info["deviation"] == info["reward_deviation"]
        assert not terminated and not info["diverged"]
        worst = max(worst, info["deviation"])
        if truncated:
            break
    assert worst < 1e-6
    assert info["measured"].keys() == info["predicted"].keys() == set(env.unwrapped.observables)
    env.close()


def test_reset_options_select_case_and_parameters(validation_env_id):
    env = gym.make(validation_env_id).unwrapped
    scenario = env.scenario
    last = scenario.cases[-1].name
    _obs, info = env.reset(seed=1, options={"case": last})
    assert info["case"] == last
    p = scenario.params[0]
    value = p.check(p.valid.low + 0.5 * (min(p.valid.high, 1e6) - p.valid.low)) if p.size == 1 else None
    if value is not None:
        try:
            env.reset(options={"params": {p.name: value}})
        except ValueError as exc:  # a cross-parameter constraint may refuse it: then it must name it
            assert p.name in str(exc)
        else:
            assert env.params[p.name] == pytest.approx(value, rel=1e-15)


def test_bad_reset_options_and_actions_are_refused(env_id):
    env = gym.make(env_id).unwrapped
    env.reset()
    with pytest.raises(ValueError, match="unknown reset option"):
        env.reset(options={"bogus": 1})
    if not isinstance(env, TaskEnv):  # a task starts from its own case: it takes a target, not a case
        with pytest.raises(ValueError, match="unknown case"):
            env.reset(options={"case": "no-such-case"})
    with pytest.raises(ValueError, match="unknown parameter"):
        env.reset(options={"params": {"no_such_param": 1.0}})
    with pytest.raises(ValueError, match="not finite"):
        env.step(np.full(env.action_space.shape, np.nan))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(env.action_space.shape[0] + 1))


def test_out_of_range_actions_are_clipped_to_the_action_space(env_id):
    a = gym.make(env_id).unwrapped
    b = gym.make(env_id).unwrapped
    a.reset(seed=0)
    b.reset(seed=0)
    high = a.action_space.high
    obs_a, *_ = a.step(high * 100)
    obs_b, *_ = b.step(high)
    np.testing.assert_array_equal(obs_a, obs_b)


def test_same_seed_same_trajectory_bit_for_bit(env_id):
    runs = []
    for _ in range(2):
        env = gym.make(env_id)
        env.reset(seed=3)
        env.action_space.seed(3)
        observations = []
        for _ in range(20):
            obs, _reward, terminated, truncated, _info = env.step(env.action_space.sample())
            observations.append(obs)
            if terminated or truncated:  # one-shot tasks end after a step: a new episode continues the stream
                observations.append(env.reset()[0])
        runs.append(np.array(observations))
    np.testing.assert_array_equal(runs[0], runs[1])


def test_every_scenario_with_an_env_is_registered_with_gymnasium():
    for env_id in registry.env_classes():
        assert env_id in gym.registry
