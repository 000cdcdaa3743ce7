"""`gymnasium.make_vec` for every env: N copies give the same results as N single envs, bit for bit."""

import gymnasium as gym
import numpy as np


def test_make_vec_matches_single_envs_bit_for_bit(env_id):
    n, steps = 2, 12
    envs = gym.make_vec(env_id, num_envs=n)
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
