"""`gymnasium.make_vec` for every env: N copies give the same results as N single envs, bit for bit.

Every env uses gymnasium's sync vector env: a batched one (the copies' physics in one threaded mujoco.rollout)
was measured no faster on the tops (benchmarks/vector_envs.py) and is not registered.
"""

import gymnasium as gym
import numpy as np


def test_make_vec_matches_single_envs_bit_for_bit(env_id):
    n, steps = 3, 12
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


def test_task_methods_reach_every_copy_of_a_vector_env():
    """``envs.call("theory_action")`` gives each copy's own theory action (targets differ per copy)."""
    envs = gym.make_vec("rigidbench/CueShot-v0", num_envs=2)
    envs.reset(seed=0)
    actions = np.array(envs.call("theory_action"))
    targets = [t["speed"] for t in envs.get_attr("target")]
    assert actions.shape == (2, 2) and targets[0] != targets[1] and actions[0, 1] != actions[1, 1]
    _obs, _rewards, terminated, _trunc, info = envs.step(actions)
    assert terminated.all() and np.all(np.abs(info["regret"]) < 1e-5)
    envs.close()
