"""Issue 36: a closed-loop task's reset simulates nothing (its regret's baseline runs alongside the episode, with the
same bits as the whole rollout at reset gave), and every task states the settings it runs at."""

import copy
import pickle

import gymnasium as gym
import numpy as np
import pytest

from rigidbench import registry
from rigidbench.envs.task import ClosedLoopTask, TaskEnv
from rigidbench.harness import settings_for

CLOSED_LOOP = sorted(i for i, cls in registry.env_classes().items() if issubclass(cls, ClosedLoopTask))
KWARGS = {"rigidbench/TopPrecession-v0": {"duration": 0.2}}


def _counting(env):
    """Count every `_advance` (one agent step or one baseline step simulated) of `env`."""
    calls = []
    advance = env._advance

    def counted(action):
        calls.append(env.data is getattr(env, "_ref_data", None))  # True: a baseline step, on the scratch MjData
        return advance(action)

    env._advance = counted
    return calls


@pytest.mark.parametrize("loop_id", CLOSED_LOOP)
def test_a_closed_loop_reset_simulates_nothing_and_a_step_one_baseline_step(loop_id):
    env = gym.make(loop_id, **KWARGS.get(loop_id, {})).unwrapped
    calls = _counting(env)
    env.reset(seed=0)
    assert calls == []  # no baseline rollout at reset
    env.step(env.action_space.sample())
    assert calls == [True, False]  # the baseline's step 0, then the agent's
    env.step(env.action_space.sample())
    assert calls == [True, False, True, False]
    env.reset(seed=1)
    assert len(calls) == 4
    env = gym.make(loop_id, regret=False, **KWARGS.get(loop_id, {})).unwrapped
    calls = _counting(env)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    assert calls == [False]


@pytest.mark.parametrize("loop_id", CLOSED_LOOP)
def test_lazy_regret_equals_the_whole_rollout_at_reset_bit_for_bit(loop_id):
    """The baseline stepped alongside the episode gives the regret the whole rollout at reset gave (forced here by
    reading `_reference` right after reset, as the old reset computed it), and a second episode of the same target
    reuses the kept rollout with the same values."""
    kwargs = KWARGS.get(loop_id, {})
    eager, lazy = gym.make(loop_id, **kwargs).unwrapped, gym.make(loop_id, **kwargs).unwrapped
    rng = np.random.default_rng(5)
    for seed in range(2):
        eager.reset(seed=seed)
        whole = eager._reference.copy()
        lazy.reset(seed=seed)
        assert lazy._ref_k == 0
        regrets = {"eager": [], "lazy": []}
        while True:
            action = rng.uniform(-1, 1, eager.action_space.shape).astype(np.float32)
            out = [env.step(action) for env in (eager, lazy)]
            regrets["eager"].append(out[0][4]["regret"])
            regrets["lazy"].append(out[1][4]["regret"])
            assert out[0][1] == out[1][1]
            if out[0][2] or out[0][3]:
                break
        assert regrets["eager"] == regrets["lazy"]
        assert lazy._reference.tolist() == whole.tolist()
        # The same configuration again: the kept rollout, no baseline step simulated.
        calls = _counting(lazy)
        lazy.reset(options={"target": {k: lazy.target[k] for k in lazy._target_ranges()}})
        lazy.step(lazy.action_space.sample())
        assert calls == [False] and lazy._reference.tolist() == whole.tolist()
        del lazy._advance


def test_copies_and_pickles_keep_the_lazy_baseline():
    env_id = CLOSED_LOOP[0]
    env = gym.make(env_id, **KWARGS.get(env_id, {})).unwrapped
    env.reset(seed=3)
    env.step(env.action_space.sample())
    for other in (copy.deepcopy(env), pickle.loads(pickle.dumps(env))):
        action = np.full(env.action_space.shape, 0.5, dtype=np.float32)
        assert other.step(action)[4]["regret"] == copy.deepcopy(env).step(action)[4]["regret"]


def test_every_task_states_its_settings_in_info_and_the_reference_profile_is_as_before(task_env_id):
    cls = registry.env_classes()[task_env_id]
    env = gym.make(task_env_id).unwrapped
    _, info = env.reset(seed=0)
    stated = info["task_settings"]
    assert stated["profile"] == "task"
    for key, value in cls.task_settings.items():
        assert stated[key] == value
    if "timestep" in cls.task_settings:
        assert env.model.opt.timestep == cls.task_settings["timestep"]
    assert "theory_regret" in stated and stated["swept"]
    ref = gym.make(task_env_id, profile="reference").unwrapped
    _, info = ref.reset(seed=0)
    assert info["task_settings"] == {"profile": "reference"}
    # The reference profile is the validation reference (with the task's own step where it set one), as before.
    assert ref._settings == settings_for("reference", timestep=cls.reference_timestep)
    assert env._settings == settings_for(
        "reference",
        integrator=cls.task_settings.get("integrator"),
        timestep=cls.task_settings.get("timestep", cls.reference_timestep),
    )
    if not cls.task_settings:  # a task whose settings are the reference's runs exactly as the reference profile
        assert env._settings == ref._settings


def test_the_task_settings_keep_the_reward_within_their_stated_bound():
    """Where a task runs cheaper than the reference (`task_settings` set), random shots and the theory action score
    within `task_record["error_bound"]` of the reference's reward: the bound the settings were chosen for."""
    for env_id, cls in registry.env_classes().items():
        if not (issubclass(cls, TaskEnv) and cls.task_settings):
            continue
        task, ref = gym.make(env_id).unwrapped, gym.make(env_id, profile="reference").unwrapped
        rng = np.random.default_rng(36)
        worst = 0.0
        for seed in range(4):
            action = rng.uniform(-1, 1, task.action_space.shape).astype(np.float32)
            rewards = []
            for env in (task, ref):
                env.reset(seed=seed)
                rewards.append(env.step(env.theory_action() if seed == 0 else action)[1])
            worst = max(worst, abs(rewards[0] - rewards[1]))
        print(f"\n{env_id}: largest reward change at the task settings {worst:.2e}")
        assert worst < cls.task_record["error_bound"]
