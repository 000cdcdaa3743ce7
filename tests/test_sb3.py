"""Stable-Baselines3 on every env (issue 17): `check_env`, its vector envs, and a short PPO run.

Needs the `rl` extra (``pip install -e ".[test,rl]"``; docs/ci.md says how to keep torch small); without
stable-baselines3 the module is skipped. `.ci/run` runs it in its own environment, `.venv-rl`.

Every env's action space is float32 and normalised to [-1, 1] (its physical action, SI, is ``action_scale`` times
it), so `check_env` gives no warning at all: any warning is an error here.
"""

import functools
import math
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

sb3 = pytest.importorskip("stable_baselines3")

from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.env_checker import check_env  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv  # noqa: E402


def test_check_env_passes_with_no_warning(env_id):
    env = gym.make(env_id)
    assert env.action_space.dtype == np.float32
    assert np.all(env.action_space.low == -1.0) and np.all(env.action_space.high == 1.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, warn=True)
    assert [str(w.message) for w in caught] == []


def _rollout(venv, seed: int, steps: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Seed, reset and step `venv` with seeded uniform actions; the (observations, rewards) of every step, the
    observation of a step that ended an episode being that step's, not the next episode's first."""
    venv.seed(seed)
    venv.reset()
    rng = np.random.default_rng(seed)
    space = venv.action_space
    out = []
    for _ in range(steps):
        actions = space.low + (space.high - space.low) * rng.random((venv.num_envs, *space.shape))
        obs, rewards, dones, infos = venv.step(actions)
        obs = obs.copy()
        for i in np.flatnonzero(dones):  # SB3 autoresets: the step's own observation is in the info
            obs[i] = infos[i]["terminal_observation"]
        out.append((obs, rewards.copy()))
    return out


def test_dummy_vec_env_copy_i_is_the_env_seeded_seed_plus_i(env_id):
    venv = DummyVecEnv([functools.partial(gym.make, env_id)] * 2)
    (obs, rewards), *_ = _rollout(venv, seed=7, steps=2)
    assert obs.shape == (2, *venv.observation_space.shape) and np.isfinite(rewards).all()
    # copy 1 of the vector env, stepped with its action, is a single env reset with seed 7 + 1
    single = gym.make(env_id)
    single.reset(seed=8)
    space = venv.action_space
    action = (space.low + (space.high - space.low) * np.random.default_rng(7).random((2, *space.shape)))[1]
    obs1, reward1, *_ = single.step(action)
    assert np.array_equal(obs[1], obs1) and rewards[1] == np.float32(reward1)  # SB3 keeps rewards as float32
    venv.close()


@pytest.mark.parametrize("task_id", ["rigidbench/CueShot-v0", "rigidbench/TopPrecession-v0"])
def test_subproc_vec_env_with_the_module_qualified_id_steps_like_dummy_vec_env(task_id):
    """SubprocVecEnv's workers (forkserver) never imported rigidbench: the id `rigidbench:...` makes gymnasium do
    it (docs/ci.md). One shot task and one closed-loop task, not every env: each worker costs seconds to start."""
    qualified = f"rigidbench:{task_id}"
    subproc = SubprocVecEnv([functools.partial(gym.make, qualified)] * 2)
    try:
        remote = _rollout(subproc, seed=3, steps=3)
    finally:
        subproc.close()
    local = _rollout(DummyVecEnv([functools.partial(gym.make, task_id)] * 2), seed=3, steps=3)
    for (o1, r1), (o2, r2) in zip(remote, local, strict=True):
        # SubprocVecEnv returns the rewards as float64, DummyVecEnv as float32
        assert np.array_equal(o1, o2) and r1.dtype == np.float64 and np.array_equal(r1.astype(np.float32), r2)


def test_a_short_ppo_run_on_cue_shot_learns_with_finite_rewards():
    """256 PPO steps (four updates of 64 shots) on CueShot-v0: a smoke test that SB3 trains on a task, not a claim
    about what it learns (benchmarks/rl_baselines.py measures that)."""
    venv = DummyVecEnv([functools.partial(gym.make, "rigidbench/CueShot-v0")])
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=32, n_epochs=2, seed=0, device="cpu")
    model.learn(total_timesteps=256)
    assert model.num_timesteps == 256
    rewards = model.rollout_buffer.rewards
    assert rewards.shape == (64, 1) and np.isfinite(rewards).all()
    action, _ = model.predict(venv.reset(), deterministic=True)
    assert action.dtype == np.float32 and venv.action_space.contains(action[0])
    assert all(math.isfinite(v) for v in model.logger.name_to_value.values())


def test_rl_baselines_scores_the_theory_policy_near_zero_regret_and_prints_every_method():
    """benchmarks/rl_baselines.py's scoring, cheaply (its full run is a documented command, ~10 min): the theory
    policy through the [-1, 1] rescaling is the theory's own action (regret 0 on the closed-loop top, by
    construction), and the table has a cell for every method."""
    root = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(root / "benchmarks"))
    try:
        import rl_baselines
    finally:
        sys.path.pop(0)
    top = rl_baselines.evaluate("rigidbench/TopPrecession-v0", rl_baselines._theory, episodes=1)
    assert abs(top["regret"]) < 1e-9 and top["return"] < 0  # a sum of 1000 exact zeros' rounding
    cue = rl_baselines.evaluate("rigidbench/CueShot-v0", rl_baselines._theory, episodes=2)
    assert 0 <= cue["regret"] < 1e-5  # the theory's measured regret (docs/gymnasium.md: 4.9e-8; bound 1e-5)
    rows = [
        {"task": t, "method": m, "regret": 1.0, "return": -1.0}
        for t in rl_baselines.TASKS
        for m in rl_baselines.METHODS
    ]
    table = rl_baselines.markdown(rows)
    assert table.count("\n") == len(rl_baselines.TASKS) + 1 and table.count("1 (-1)") == 25
