"""`gymnasium.make_vec` for every env: N copies give the same results as N single envs, bit for bit."""

import gymnasium as gym
import numpy as np
import pytest

from rigidbench import registry


@pytest.mark.parametrize("mode", ["default", "sync"])
def test_make_vec_matches_single_envs_bit_for_bit(env_id, mode):
    """Default mode: the batched vector env where the env opts in (rigidbench.envs.batched), else sync."""
    n, steps = 3, 12
    envs = gym.make_vec(env_id, num_envs=n, vectorization_mode=None if mode == "default" else mode)
    singles = [gym.make(env_id) for _ in range(n)]
    obs, _ = envs.reset(seed=5)  # copy i is seeded 5 + i
    single_obs = [env.reset(seed=5 + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.array(single_obs))
    envs.action_space.seed(0)
    done = [False] * n
    for _ in range(steps):
        actions = envs.action_space.sample()
        obs, rewards, terminated, truncated, _info = envs.step(actions)
        for i, env in enumerate(singles):
            if done[i]:  # gymnasium's default autoreset (next step): the step after an episode's end resets it
                expected, reward, term, trunc = env.reset()[0], 0.0, False, False
            else:
                expected, reward, term, trunc, _ = env.step(actions[i])
            done[i] = term or trunc
            np.testing.assert_array_equal(obs[i], expected)
            assert (rewards[i], terminated[i], truncated[i]) == (reward, term, trunc)
    envs.close()


def test_batched_vector_env_is_used_where_the_env_opts_in(env_id):
    envs = gym.make_vec(env_id, num_envs=2)
    assert type(envs).__name__ == ("BatchedVectorEnv" if registry.env_classes()[env_id].batched else "SyncVectorEnv")
    envs.close()


def test_batched_vector_env_autoresets_a_finished_copy_like_gymnasium():
    """Short episodes (frame_skip large) so that copies finish and reset inside the test."""
    kwargs = {"case": "nutation", "frame_skip": 400}
    batched = gym.make_vec("rigidbench/HeavyTop-v0", num_envs=2, **kwargs)
    sync = gym.make_vec("rigidbench/HeavyTop-v0", num_envs=2, vectorization_mode="sync", **kwargs)
    for envs in (batched, sync):
        envs.reset(seed=0)
    ends = 0
    for _ in range(12):
        a = batched.step(np.full((2, 3), 0.01))
        b = sync.step(np.full((2, 3), 0.01))
        for x, y in zip(a[:4], b[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        ends += int(a[3].sum())
    assert ends >= 2
