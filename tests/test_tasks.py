"""Control task envs: targets per episode, reward terms, regret against the theory action, and each task's claim.

Random-policy figures are printed (``pytest -s``) so that they can be reported; the assertions are the claims.
"""

import gymnasium as gym
import numpy as np
import pytest

from rigidbench.envs.task import TaskEnv


def _episode(env, policy, *, seed=None, options=None):
    """Run one episode; return (return, summed regret, last info)."""
    _obs, _info = env.reset(seed=seed, options=options)
    total = regret = 0.0
    while True:
        _obs, reward, terminated, truncated, info = env.step(policy(env))
        total += reward
        regret += info["regret"]
        if terminated or truncated:
            return total, regret, info


def _random(env):
    return env.action_space.sample()


def _theory(env):
    return env.theory_action()


# ---- every task --------------------------------------------------------------------------------------------


def test_reward_terms_add_up_to_the_reward_and_regret_is_reported(task_env_id):
    env = gym.make(task_env_id).unwrapped
    env.reset(seed=0)
    env.action_space.seed(0)
    for _ in range(5):
        _obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        terms = [info[f"reward_{name}"] for name in env.reward_terms]
        assert reward == pytest.approx(sum(terms), rel=1e-12, abs=1e-15)
        assert np.isfinite(info["regret"]) and info["target"] == env.target
        if terminated or truncated:
            env.reset()


def test_targets_are_sampled_from_the_seed_and_can_be_fixed(task_env_id):
    env = gym.make(task_env_id).unwrapped
    first = env.reset(seed=11)[1]["target"]
    assert env.reset(seed=11)[1]["target"] == first
    assert env.reset(seed=12)[1]["target"] != first
    assert set(first) == set(env.target_names)
    given = {name: first[name] for name in env._target_ranges()}
    assert env.reset(options={"target": given})[1]["target"] == first
    low = {name: lo - 1.0 for name, (lo, _hi) in env._target_ranges().items()}
    with pytest.raises(ValueError, match="outside the valid range"):
        env.reset(options={"target": low})
    with pytest.raises(ValueError, match="target must give"):
        env.reset(options={"target": {"no_such_target": 1.0}})


def test_theory_action_lies_in_the_action_space(task_env_id):
    env = gym.make(task_env_id).unwrapped
    for seed in range(5):
        env.reset(seed=seed)
        action = env.theory_action()  # float64, as precise as the theory: inside the bounds, in float32 too
        assert action.dtype == np.float64 and action.shape == env.action_space.shape
        assert np.all(np.abs(action) <= 1.0) and env.action_space.contains(action.astype(np.float32))


def test_every_task_is_a_task_env_with_its_own_id(task_env_id):
    env = gym.make(task_env_id).unwrapped
    assert isinstance(env, TaskEnv) and type(env).env_id == task_env_id != env.scenario.env_id


# ---- TopPrecession-v0 (docs/theory.md T4) ------------------------------------------------------------------------


def test_top_precession_baseline_ends_in_T4_steady_precession_needing_no_torque():
    """The target is T4's slow steady precession at the initial tilt: a free motion, so a baseline that reaches
    it ends with ~zero torque. After 1 s the feedback residuals observed are <= 1.3e-8 (rate, relative),
    <= 3e-6 rad (tilt) and <= 1.4e-6 N m (torque) over the tilt range: the bounds leave 30-100x."""
    env = gym.make("rigidbench/TopPrecession-v0").unwrapped
    for tilt in (0.3, 0.75, 1.2):
        _total, regret, _info = _episode(env, _theory, options={"target": {"tilt": tilt}})
        state = env._state()
        assert abs(state["phi_dot"] / env.target["precession"] - 1) < 1e-6
        assert abs(state["theta"] - tilt) < 1e-4
        assert np.abs(env.theory_action()).max() < 1e-4  # of max_torque: the action is normalised
        # The regret reference is the same policy simulated on a copy at reset: bit-for-bit the same episode.
        assert regret == pytest.approx(0.0, abs=1e-9)


def test_top_precession_random_and_zero_policies_have_positive_regret():
    env = gym.make("rigidbench/TopPrecession-v0").unwrapped
    env.action_space.seed(0)
    random = [_episode(env, _random, seed=s)[1] for s in range(3)]
    zero = [_episode(env, lambda e: np.zeros(3), seed=s)[1] for s in range(3)]
    print(
        f"\nTopPrecession-v0: mean regret over 3 episodes (1000 steps): random {np.mean(random):.1f}, "
        f"zero {np.mean(zero):.1f}"
    )
    # Left alone the top nutates (T3) with phi_dot between 0 and ~2 phi_dot*: relative rate errors O(1) per step.
    assert min(random) > 100 and min(zero) > 100


# ---- PendulumEnergyTransfer-v0 (docs/theory.md O3, O4) ----------------------------------------------------------


def test_pendulum_energy_transfer_baseline_reaches_the_linear_optimum():
    """The bang-bang schedule is the exact optimum of the linearised, zero-order-hold model: simulated, the
    nonlinear pendulums (sin th, spring geometry) deliver E2(T) within O(th^2) of it; at <= 0.03 rad the
    relative shortfall measured is ~4e-4, and 2e-3 bounds it."""
    env = gym.make("rigidbench/PendulumEnergyTransfer-v0").unwrapped
    for fraction in (0.5, 1.0):
        t_x = env.prediction["transfer-time"]
        total, regret, _info = _episode(env, _theory, options={"target": {"duration": fraction * t_x}})
        assert abs(total - 1) < 2e-3
        assert abs(env.energy2() / env._optimum - 1) < 2e-3
        assert regret == pytest.approx(0.0, abs=1e-12)  # the reference is this very policy, on a copy


def test_pendulum_energy_transfer_baseline_beats_other_drives():
    """Driving pendulum 1 in resonance with either normal mode, or at the carrier, or at random, leaves less
    energy in pendulum 2 than the beat-phased bang-bang baseline (by more than the 2e-3 nonlinear tolerance)."""
    env = gym.make("rigidbench/PendulumEnergyTransfer-v0").unwrapped
    env.reset(seed=0)
    ws, wa = env.prediction["omega-in-phase"], env.prediction["omega-anti-phase"]
    drives = {
        "in-phase": lambda e: np.sign(np.sin(ws * e.data.time)) * np.ones(1),
        "anti-phase": lambda e: np.sign(np.sin(wa * e.data.time)) * np.ones(1),
        "carrier": lambda e: np.sign(np.sin((ws + wa) / 2 * e.data.time)) * np.ones(1),
        "zero": lambda e: np.zeros(1),
    }
    env.action_space.seed(0)
    regrets = {name: _episode(env, drive, seed=0)[1] for name, drive in {**drives, "random": _random}.items()}
    print(f"\nPendulumEnergyTransfer-v0 regret (1 episode, T = {env.episode_duration:.1f} s): {regrets}")
    assert min(regrets.values()) > 2e-3


# ---- CueShot-v0 (docs/theory.md B1, B2) ---------------------------------------------------------------------------

# Bound on the theory action's regret: the cue-strike scenario's own tolerance on the final speed (1e-5 relative);
# the no-skid blow leaves a slip of ~3e-7 m/s, far below the 1e-3 v* that counts as skidding, so its skid term is
# exactly 0. Measured at the task's 50 us step: 4.9e-8.
CUE_TOLERANCE = 1e-5


def test_cue_shot_theory_action_is_optimal_up_to_the_scenario_tolerances():
    env = gym.make("rigidbench/CueShot-v0").unwrapped
    regrets = [_episode(env, _theory, seed=s)[1] for s in range(6)]
    env.action_space.seed(0)
    random = [_episode(env, _random, seed=s)[1] for s in range(6)]
    print(f"\nCueShot-v0 mean regret over 6 episodes: theory {np.mean(regrets):.3g}, random {np.mean(random):.3g}")
    assert 0 <= np.mean(regrets) < CUE_TOLERANCE and max(regrets) < CUE_TOLERANCE
    assert min(random) > -CUE_TOLERANCE  # nothing does better than the optimum (beyond the tolerance)
    assert np.mean(random) > 0.1


def test_cue_shot_strike_at_seven_tenths_of_the_diameter_does_not_skid():
    """B1: struck at h = 2R/5 (H = 0.7 of the diameter) the ball rolls at once; struck through the centre it
    skids with u0 = v0 and rolls at 5/7 v0 (B2)."""
    env = gym.make("rigidbench/CueShot-v0").unwrapped
    env.reset(options={"target": {"speed": 1.0}})
    action = env.theory_action()
    assert env._physical(action)[0] == pytest.approx(0.4 * env.params["radius"], rel=1e-12)
    _obs, _r, _te, _tr, info = env.step(action)
    assert info["skid_time"] == 0.0 and info["final_speed"] == pytest.approx(1.0, rel=1e-5)
    env.reset(options={"target": {"speed": 1.0}})
    _obs, reward, _te, _tr, info = env.step(np.array([0.0, action[1]]))
    # Skid time to the slip's fall below 1e-3 v0: B2's t_r (1 - 1e-3), and MuJoCo's friction, a velocity-level
    # constraint, lets the last of the slip decay exponentially (the scenario's time-to-roll: <= 0.7 ms late).
    assert info["skid_time"] == pytest.approx(info["predicted_skid_time"], abs=1e-3)
    assert info["final_speed"] == pytest.approx(5 / 7, rel=1e-5) and reward < -0.2


# ---- PercussionStrike-v0 (docs/theory.md P2, P5, P6) -------------------------------------------------------------

# Bound on the theory action's regret: the marble-shot scenario's tolerance on C's speed (5e-5 relative: C is hit
# when the stick has turned ~1e-3 rad) and the same geometry for A's end (~1e-5 of u*). Measured: <= 4.6e-6.
PERCUSSION_TOLERANCE = 1e-4


def test_percussion_strike_theory_action_is_optimal_up_to_the_scenario_tolerances():
    env = gym.make("rigidbench/PercussionStrike-v0").unwrapped
    regrets = [_episode(env, _theory, seed=s)[1] for s in range(5)]
    env.action_space.seed(0)
    random = [_episode(env, _random, seed=s)[1] for s in range(5)]
    print(
        f"\nPercussionStrike-v0 mean regret over 5 episodes: theory {np.mean(regrets):.3g}, "
        f"random {np.mean(random):.3g}"
    )
    assert 0 <= np.mean(regrets) < PERCUSSION_TOLERANCE and max(regrets) < PERCUSSION_TOLERANCE
    assert min(random) > -PERCUSSION_TOLERANCE and np.mean(random) > 0.1


def test_percussion_strike_at_the_textbook_centre_of_percussion_pushes_a_through_cs_recoil():
    """P6's h = L/6 leaves A's end at rest after the blow, but C's recoil (P5) then pushes A; the theory action,
    h* = (L/6)(1 + r)/(1 - r) with r = 4m/(4m + M), leaves A untouched."""
    env = gym.make("rigidbench/PercussionStrike-v0").unwrapped
    env.reset(options={"target": {"speed": 10.0}})
    action = env.theory_action()
    m, big_m = 0.005, 0.25
    r = 4 * m / (4 * m + big_m)
    assert env._physical(action)[0] == pytest.approx((1 + r) / (1 - r) / 6, rel=1e-9)
    info = env.step(action)[4]
    assert info["marble_a_speed"] == 0.0 and abs(info["stick_at_a"]) < 1e-5 * 10
    assert info["marble_c_speed"] == pytest.approx(10.0, rel=5e-5)
    env.reset(options={"target": {"speed": 10.0}})
    textbook = np.array([env._unlinear(1 / 6, env.offset_range), action[1]])
    info = env.step(textbook)[4]
    assert info["marble_a_speed"] > 0.05 * info["marble_c_speed"]  # A is pushed after all


# ---- ScatterToAngle-v0 (docs/theory.md C2, C3, C5) ----------------------------------------------------------------


def _soft_bound(env) -> float:
    """The hard-spheres scenario's bound on |psi_simulated - psi_hard| for the shot just taken (rad): the soft
    contact's shift ~ pi (b/a) u / (a sqrt(k)) |d psi/d theta| (C8, first order, with 50 % for higher orders),
    its second-order term near b0 where psi is stationary, and RK4's 5e-6 rad."""
    return float(env.prediction["_tolerance"]["projectile-lab-angle-hard"])


@pytest.mark.parametrize("profile", ["reference", "task"])
def test_scatter_to_angle_theory_action_is_optimal_up_to_the_soft_contact_shift(profile):
    """The hard-sphere optimum misses only by the soft-sphere shift of the simulated contact (a k^-1/2 finding of
    the hard-spheres scenario), episode by episode; reachable or not. At the task settings (Euler at 4 us, issue 36)
    the integration moves the angle by up to the settings' stated error bound either way (measured 5e-5 rad, bound
    1e-4: `task_record`), so the regret may be that much below 0 or above the soft shift."""
    env = gym.make("rigidbench/ScatterToAngle-v0", profile=profile).unwrapped
    slack = env.task_record["error_bound"] if profile == "task" else 1e-12
    regrets = []
    for s in range(12):
        regrets.append(_episode(env, _theory, seed=s)[1])
        assert -slack <= regrets[-1] <= _soft_bound(env) + (slack if profile == "task" else 0.0)
    env.action_space.seed(0)
    random = [_episode(env, _random, seed=s)[1] for s in range(12)]
    print(
        f"\nScatterToAngle-v0 mean regret over 12 episodes: theory {np.mean(regrets):.3g}, random {np.mean(random):.3g}"
    )
    assert np.mean(regrets) < 1e-3 and np.mean(random) > 1e-2
    assert min(random) > -max(_soft_bound(env), 1e-3)


def test_lab_angle_never_exceeds_arcsin_m2_over_m1():
    """C3: with m1/m2 = 3 no impact parameter sends the projectile beyond arcsin(1/3); an unreachable target's
    best is psi_max itself, at b0."""
    # C3 at the scenario's own tolerance: the reference settings it is stated for (the task settings: issue 36)
    env = gym.make("rigidbench/ScatterToAngle-v0", profile="reference").unwrapped
    psi_max = np.arcsin(1 / 3)
    for a in np.linspace(-1, 1, 9):
        env.reset(options={"target": {"angle": 0.5}})
        info = env.step(np.array([a]))[4]
        assert info["lab_angle"] <= psi_max + _soft_bound(env)
    env.reset(options={"target": {"angle": 0.5}})
    _obs, reward, *_ = env.step(env.theory_action())
    assert reward == pytest.approx(-(0.5 - psi_max), abs=_soft_bound(env))


def test_a_heavy_projectile_reaches_a_target_angle_on_both_branches():
    """C3: for x > 1 each psi < psi_max comes from two CM angles (stretch b > b0, short b < b0): both optimal."""
    env = gym.make("rigidbench/ScatterToAngle-v0", profile="reference").unwrapped
    env.reset(options={"target": {"angle": 0.2}})
    actions = env.theory_actions()
    b0 = 2 * np.sqrt((3 - 1) / (2 * 3)) * 0.05  # a sqrt((x - 1)/(2x)), a = 0.1 m
    assert len(actions) == 2 and env._impact(actions[0]) > b0 > env._impact(actions[1])
    for action in actions:
        env.reset(options={"target": {"angle": 0.2}})
        info = env.step(action)[4]
        assert abs(info["lab_angle"] - 0.2) <= _soft_bound(env) and info["regret"] <= _soft_bound(env)
