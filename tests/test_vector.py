"""`gymnasium.make_vec` for every env: N copies give the same results as N single envs, bit for bit.

Gymnasium's sync vector env works for every env; every validation env also has a batched vector env
(``vectorization_mode="vector_entry_point"``, `rigidbench.envs.vector`: the copies' physics one `mujoco.batch` call,
their observations and rewards in arrays), which must equal the sync one bit for bit on C MuJoCo: observations,
rewards, terminations, truncations and every number in ``info``, through autoresets and clipped actions.
"""

import math

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import data_equivalence

from rigidbench.registry import env_classes


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


def _assert_infos_equal(expected: dict, got: dict, where: str) -> None:
    """Same keys, masks and numbers (NaN equal to NaN) as gymnasium's merged infos; object arrays (the reset's
    case, params and settings) compared element by element."""
    assert set(expected) == set(got), f"{where}: keys differ: {set(expected) ^ set(got)}"
    for key, value in expected.items():
        if isinstance(value, dict):
            _assert_infos_equal(value, got[key], f"{where}/{key}")
        elif value.dtype == object:
            assert list(value) == list(got[key]), f"{where}/{key}"
        else:
            assert value.dtype == got[key].dtype, f"{where}/{key}: {value.dtype} != {got[key].dtype}"
            np.testing.assert_array_equal(got[key], value, err_msg=f"{where}/{key}")


def _run_both(env_id: str, n: int, steps: int, seed: int = 0, **kwargs) -> int:
    """Step a sync and a batched vector env of `env_id` side by side with the same random actions (some outside
    the action space, so clipping is exercised); assert every output equal; return the number of episode ends."""
    sync = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", **kwargs)
    batched = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    (obs_s, info_s), (obs_b, info_b) = sync.reset(seed=seed), batched.reset(seed=seed)
    np.testing.assert_array_equal(obs_b, obs_s)
    _assert_infos_equal(info_s, info_b, "reset")
    rng = np.random.default_rng(seed)
    high = sync.single_action_space.high
    ends = 0
    for t in range(steps):
        actions = rng.uniform(-0.3, 0.3, sync.action_space.shape) * high
        actions[t % n] *= 5.0  # beyond the action space: clipped by both
        out_s, out_b = sync.step(actions), batched.step(actions)
        for name, a, b in zip(("obs", "reward", "terminated", "truncated"), out_s[:4], out_b[:4], strict=True):
            np.testing.assert_array_equal(b, a, err_msg=f"{env_id} step {t}: {name}")
        _assert_infos_equal(out_s[4], out_b[4], f"{env_id} step {t}")
        ends += int(out_s[2].sum() + out_s[3].sum())
    sync.close()
    batched.close()
    return ends


def test_batched_vector_env_equals_sync_bit_for_bit(validation_env_id):
    """Every validation env, 3 copies, 60 steps at 5x its frame skip (the fast envs end episodes and autoreset)."""
    frame_skip = 5 * env_classes()[validation_env_id].default_frame_skip
    _run_both(validation_env_id, 3, 60, frame_skip=frame_skip)


@pytest.mark.parametrize(
    "one_id", ["rigidbench/HeavyTop-v0", "rigidbench/StruckStick-v0", "rigidbench/SimplePendulum-v0"]
)
def test_one_copy_equals_sync_through_its_autoresets(one_id):
    """N = 1 on C MuJoCo steps the template env itself (`VectorScenarioEnv._step_one`): the same outputs as a sync
    vector env of one, through at least one episode end and its autoreset."""
    env = gym.make(one_id).unwrapped
    env.reset(seed=0)
    frame_skip = math.ceil(env.episode_duration / env.model.opt.timestep / 25)  # an episode in 25 steps
    assert _run_both(one_id, 1, 60, frame_skip=frame_skip) >= 2


def test_batched_vector_env_autoresets_as_sync_does():
    """HeavyTop at 50 steps a call ends its first episode within 100 calls: the next call restarts it (reward 0, the
    reset's info), in both vector envs alike."""
    assert _run_both("rigidbench/HeavyTop-v0", 4, 100, frame_skip=50) >= 4


def test_batched_vector_env_reset_options_set_the_whole_batch():
    envs = gym.make_vec("rigidbench/HeavyTop-v0", num_envs=2, vectorization_mode="vector_entry_point")
    single = gym.make("rigidbench/HeavyTop-v0")
    obs, info = envs.reset(options={"case": "looping", "params": {"spin": 150.0}})
    expected, _ = single.reset(options={"case": "looping", "params": {"spin": 150.0}})
    np.testing.assert_array_equal(obs, [expected, expected])
    assert list(info["case"]) == ["looping", "looping"] and np.all(info["params"]["spin"] == 150.0)
    envs.close()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"num_envs": 0}, "num_envs = 0 must be an integer >= 1"),
        ({"num_envs": 2, "render_mode": "rgb_array"}, "render_mode"),
        ({"num_envs": 2, "engine": "bullet"}, "engine 'bullet' is not one of"),
        ({"num_envs": 2, "engine": "mujoco", "precision": "float32"}, "engine mujoco runs on the cpu in float64"),
        ({"num_envs": 2, "case": "spinning"}, "spinning"),
    ],
)
def test_batched_vector_env_refuses_bad_arguments_by_name(kwargs, message):
    with pytest.raises(ValueError, match=message):
        gym.make_vec("rigidbench/HeavyTop-v0", vectorization_mode="vector_entry_point", **kwargs)


def test_batched_vector_env_refuses_bad_actions_by_name():
    envs = gym.make_vec("rigidbench/SimplePendulum-v0", num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(RuntimeError, match="reset"):
        envs.step(np.zeros((2, 1)))
    envs.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions shape \(3, 1\) != \(2, 1\)"):
        envs.step(np.zeros((3, 1)))
    with pytest.raises(ValueError, match="action of env 1 .* is not finite"):
        envs.step(np.array([[0.0], [np.nan]]))
    envs.close()


def test_control_tasks_have_no_batched_vector_env():
    """The tasks draw targets and simulate baselines per copy: gymnasium's sync and async vector envs run them."""
    with pytest.raises(gym.error.Error, match="vector entry point"):
        gym.make_vec("rigidbench/CueShot-v0", num_envs=2, vectorization_mode="vector_entry_point")
    # Built directly, the batched env refuses a class with its own step() by name, for one copy as for several.
    from rigidbench.envs.vector import VectorScenarioEnv

    for n in (1, 2):
        with pytest.raises(TypeError, match="CueShot.* has its own step"):
            VectorScenarioEnv(env_classes()["rigidbench/CueShot-v0"], n)


def test_batched_hooks_equal_the_per_copy_fallbacks():
    """The array hooks of an env (here the planar blows: rotations, headings, wrapped angles) against
    the per-copy fallbacks (`PerCopyHooks`), which run the single env's own hooks: the same bits."""
    from rigidbench.envs.vector import BATCHED_HOOKS, PerCopyHooks, VectorScenarioEnv

    fast_cls = env_classes()["rigidbench/PivotedStick-v0"]
    fallbacks = {h: lambda self, *a, _h=h: getattr(PerCopyHooks(self), _h)(*a) for h in BATCHED_HOOKS}
    plain_cls = type("PlainPivotedStick", (fast_cls,), fallbacks)
    fast, plain = VectorScenarioEnv(fast_cls, 3, frame_skip=50), VectorScenarioEnv(plain_cls, 3, frame_skip=50)
    np.testing.assert_array_equal(fast.reset(seed=0)[0], plain.reset(seed=0)[0])
    rng = np.random.default_rng(1)
    for _ in range(80):
        actions = rng.uniform(-1, 1, fast.action_space.shape) * fast.single_action_space.high
        for a, b in zip(fast.step(actions)[:4], plain.step(actions)[:4], strict=True):
            np.testing.assert_array_equal(a, b)


def test_a_reset_of_the_same_configuration_starts_as_a_fresh_env(validation_env_id):
    """A reset of the configuration the env ran last restores its kept start (`ScenarioEnv.load`: parameters,
    state and prediction computed once, the state copied back into the episode's MjData): the same state, observation,
    info and next steps as a fresh env's first reset, bit for bit."""
    env = gym.make(validation_env_id).unwrapped
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-0.5, 0.5, (6, *env.action_space.shape))
    for action in actions[:3]:
        env.step(action)
    again, fresh = env.reset(), gym.make(validation_env_id).unwrapped.reset()
    assert data_equivalence(again, fresh, exact=True)
    env2 = gym.make(validation_env_id).unwrapped
    env2.reset()
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    states = [np.empty(mujoco.mj_stateSize(e.model, spec)) for e in (env, env2)]
    for e, state in zip((env, env2), states, strict=True):
        mujoco.mj_getState(e.model, e.data, state, spec)
    np.testing.assert_array_equal(states[0], states[1])
    assert env.params is not env2.params and env.params == env2.params
    for action in actions[3:]:
        assert data_equivalence(env.step(action), env2.step(action), exact=True)


def test_a_template_set_to_float32_after_construction_loads_the_float32_model():
    """`VectorScenarioEnv` on a float32 engine sets its template's precision after the template's constructor loaded
    the float64 model of the same parameters; the next reset must load the model rounded to float32 (the body the
    engine simulates and the theory predicts for), not the float64 one kept from the constructor."""
    env = gym.make("rigidbench/HeavyTop-v0").unwrapped
    env._precision, env._engine_name = "float32", "mjx"
    env.reset()
    for values in (env.model.body_mass, env.model.body_inertia, env.model.body_ipos):
        np.testing.assert_array_equal(values, values.astype(np.float32))
    assert env.model.opt.timestep == float(np.float32(env.model.opt.timestep))


def test_a_reset_never_writes_an_mjdata_assigned_from_outside():
    """`rigidbench.suite` binds its env to dm_control's own MjData; a reset of the same configuration puts the start
    back into the MjData the env installed, never into the one assigned to it (it wiped dm_control's task state)."""
    env = gym.make("rigidbench/HeavyTop-v0").unwrapped
    env.reset()
    own = env.data
    other = mujoco.MjData(env.model)
    before = (other.qpos.copy(), other.qvel.copy(), other.time)
    env.data = other
    env.reset()
    assert env.data is own
    assert np.array_equal(other.qpos, before[0]) and np.array_equal(other.qvel, before[1]) and other.time == before[2]


def test_a_copy_of_one_that_blows_up_ends_as_a_sync_env_of_one_does():
    """N = 1's diverged step (`ScenarioEnv._diverged_step` through `_step_one`) and the autoreset after it: the
    outputs of a sync vector env of one, bit for bit."""
    sync = gym.make_vec("rigidbench/HeavyTop-v0", num_envs=1, vectorization_mode="sync")
    batched = gym.make_vec("rigidbench/HeavyTop-v0", num_envs=1, vectorization_mode="vector_entry_point")
    sync.reset(seed=0), batched.reset(seed=0)
    zero = np.zeros(sync.action_space.shape)
    for t in range(4):
        if t == 2:  # what a blown-up integrator leaves behind, in both
            sync.envs[0].unwrapped.data.qvel[:] = np.nan
            batched.unwrapped.env.data.qvel[:] = np.nan
        out_s, out_b = sync.step(zero), batched.step(zero)
        for name, a, b in zip(("obs", "reward", "terminated", "truncated"), out_s[:4], out_b[:4], strict=True):
            np.testing.assert_array_equal(b, a, err_msg=f"step {t}: {name}")
        _assert_infos_equal(out_s[4], out_b[4], f"step {t}")
        assert bool(out_b[2][0]) == (t == 2) and bool(out_b[4]["diverged"][0]) == (t == 2)


def _leaves(info: dict, where: str = "") -> dict[str, np.ndarray]:
    out = {}
    for key, value in info.items():
        if isinstance(value, dict):
            out.update(_leaves(value, f"{where}/{key}"))
        elif not key.startswith("_"):  # the masks are one read-only array (`rigidbench.envs.vector._MASK`)
            out[f"{where}/{key}"] = value
    return out


def test_a_copy_of_ones_outputs_are_independent_arrays():
    """`_step_one` returns the reward and the info's numbers as views of one array: writing any one of them
    changes no other output (each is its own element)."""
    envs = gym.make_vec("rigidbench/StruckStick-v0", num_envs=1, vectorization_mode="vector_entry_point")
    envs.reset(seed=0)
    obs, reward, terminated, truncated, info = envs.step(np.zeros(envs.action_space.shape))
    outputs = {"obs": obs, "reward": reward, "terminated": terminated, "truncated": truncated, **_leaves(info)}
    # obs, reward, terminated, truncated; time, deviation, reward_deviation, diverged; measured and predicted
    assert len(outputs) == 4 + 4 + 2 * len(envs.unwrapped.env._observable_names)
    for name, array in outputs.items():
        before = {key: value.copy() for key, value in outputs.items()}
        array[0] = 1.0 - array[0] if array.dtype == bool else -12345.0
        for key, value in outputs.items():
            if key != name:
                np.testing.assert_array_equal(value, before[key], err_msg=f"writing {name} changed {key}")
        assert not np.array_equal(array, before[name])
