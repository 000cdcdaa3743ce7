"""Census of bad and random input per scenario: how many were tried, refused cleanly, ran, and crashed.

    python benchmarks/fuzz_census.py [--valid 40] [--seed 0]

For every scenario and parameter: the invalid values (NaN, +-inf, below and above the range, the wrong number
of components, text, None) must each raise ValueError naming the parameter; then `--valid` random parameter sets
drawn inside the ranges (several parameters at once, any case) must either be refused by a cross-parameter
check (ValueError) or compile and step 200 times with finite states or a divergence flag. For every env: NaN
and wrong-shaped actions must raise ValueError, and random in-range actions must give finite observations.
Anything else is a crash. The property tests in tests/test_fuzz.py make the same claims with hypothesis; this
script counts.
"""

from __future__ import annotations

import argparse
import math
import sys

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import registry
from rigidbench.simulate import get_state, split_states


def invalid_values(p):
    high = p.valid.high * 10 + 1 if math.isfinite(p.valid.high) else None
    low = p.valid.low - 10 * (abs(p.valid.low) + 1) if math.isfinite(p.valid.low) else None
    scalars = [float("nan"), float("inf"), float("-inf"), "abc", None]
    scalars += [v for v in (high, low) if v is not None]
    if p.size == 1:
        return [*scalars, [1.0, 2.0]]
    return [[v] * p.size for v in scalars if isinstance(v, float)] + ["abc", None, [1.0] * (p.size - 1)]


def random_valid(p, rng):
    lo = p.valid.low if math.isfinite(p.valid.low) else -1e3
    hi = p.valid.high if math.isfinite(p.valid.high) else 1e3
    draw = rng.uniform(lo, hi, p.size)
    if getattr(p, "integer", False):
        draw = np.clip(np.round(draw), math.ceil(lo), math.floor(hi))
    draw = np.clip(
        draw, np.nextafter(lo, hi) if p.valid.low_open else lo, np.nextafter(hi, lo) if p.valid.high_open else hi
    )
    return float(draw[0]) if p.size == 1 else [float(x) for x in draw]


def census(slug, n_valid, rng):
    scenario = registry.get(slug)
    tried = refused = ran = crashed = 0
    for p in scenario.params:
        for value in invalid_values(p):
            tried += 1
            try:
                scenario.resolve(scenario.cases[0], {p.name: value})
            except ValueError as exc:
                refused += p.name in str(exc)
                crashed += p.name not in str(exc)
            except Exception:  # noqa: BLE001 - the census counts every other exception as a crash
                crashed += 1
            else:
                crashed += 1  # an invalid value accepted silently counts as a crash
    cross_refused = 0
    for _ in range(n_valid):
        case = scenario.cases[rng.integers(len(scenario.cases))]
        k = rng.integers(1, min(3, len(scenario.params)) + 1)
        chosen = rng.choice(len(scenario.params), size=k, replace=False)
        overrides = {scenario.params[i].name: random_valid(scenario.params[i], rng) for i in chosen}
        try:
            params = scenario.resolve(case, overrides)
            model = scenario.build(params)
        except ValueError:
            cross_refused += 1
            continue
        except Exception:  # noqa: BLE001
            crashed += 1
            continue
        try:
            data = scenario.start(model)
            state = get_state(model, data)
            states, _ = mujoco.rollout.rollout(model, mujoco.MjData(model), state[None], nstep=200)
            traj = split_states(model, np.concatenate([state[None], states[0]]))
            finite = np.isfinite(traj.qpos).all() and np.isfinite(traj.qvel).all()
            crashed += not (finite or traj.diverged_at is not None)
            ran += 1
        except Exception:  # noqa: BLE001
            crashed += 1
    return tried, refused, n_valid, cross_refused, ran, crashed


def env_census(env_id, rng, n=20):
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    tried = refused = crashed = 0
    shape = env.action_space.shape
    for bad in (np.full(shape, np.nan), np.full(shape, np.inf), np.zeros(shape[0] + 1), "x"):
        tried += 1
        try:
            env.step(bad)
        except ValueError:
            refused += 1
        except Exception:  # noqa: BLE001
            crashed += 1
    for _ in range(n):
        obs, _r, terminated, truncated, info = env.step(env.action_space.sample())
        crashed += not (np.isfinite(obs).all() or info.get("diverged"))
        if terminated or truncated:
            env.reset()
    return tried, refused, n, crashed


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--valid", type=int, default=40, help="random valid parameter sets per scenario")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    print(
        "| scenario | invalid tried | refused cleanly (ValueError naming it) | random valid sets | refused by a "
        "cross-parameter check | simulated | crashes |"
    )
    print("|---|---|---|---|---|---|---|")
    total_crashes = 0
    for slug in registry.scenarios():
        t, r, v, x, ran, c = census(slug, args.valid, rng)
        total_crashes += c
        print(f"| {slug} | {t} | {r} | {v} | {x} | {ran} | {c} |")
    print("\n| env | invalid actions tried | refused (ValueError) | random actions | crashes |")
    print("|---|---|---|---|---|")
    for env_id in sorted(registry.env_classes()):
        t, r, n, c = env_census(env_id, rng)
        total_crashes += c
        print(f"| {env_id} | {t} | {r} | {n} | {c} |")
    print(f"\ntotal crashes: {total_crashes}")
    return 1 if total_crashes else 0


if __name__ == "__main__":
    sys.exit(main())
