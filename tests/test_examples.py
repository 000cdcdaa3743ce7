"""examples/: the cross-entropy optimiser learns the one-shot tasks and ends near the theory's action."""

import importlib.util
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import rigidbench  # noqa: F401  (registers the envs)


def _example(name: str):
    path = Path(__file__).resolve().parents[1] / "examples" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


# (env id, fixed target, bound on the final distance to the theory action in normalised action units). The bounds
# are what a small budget (8 generations of 16, 130 episodes) reaches with margin: measured 0.001-0.018 over seeds
# 0-2 for the cue (the reward is a V in h and a valley in v0 (1 + h/R)) and ~1e-3 for the spheres; the search
# starts 0.2-0.6 away (the centre of the box).
CASES = [
    ("rigidbench/CueShot-v0", {"speed": 1.2}, 0.05),
    ("rigidbench/ScatterToAngle-v0", {"angle": 0.2}, 0.05),  # reachable: the stretch-branch b
    ("rigidbench/ScatterToAngle-v0", {"angle": 0.5}, 0.05),  # beyond psi_max = arcsin(1/3): b0
]


@pytest.mark.parametrize(("task_id", "target", "bound"), CASES, ids=lambda v: str(v))
def test_cross_entropy_search_converges_to_the_theory_action(task_id, target, bound):
    if task_id not in gym.registry:
        pytest.skip(f"{task_id} needs its scenario family")
    cem = _example("cem_shots")
    result = cem.cross_entropy_search(task_id, target, iterations=8, population=16, seed=0)
    start = float(np.linalg.norm(result.theory))  # the search starts at the centre of the box (distance to the
    # nearest optimum)
    print(f"\n{task_id} {target}: CEM ends {result.distance:.3g} from the theory action (started {start:.3g})")
    assert result.distance < bound < start
    # It found nothing better than the theory, beyond MuJoCo's departures from it (the soft spheres' shift, which
    # is smaller on the short branch than on the stretch one the theory lists first: <= 1e-3 rad).
    assert result.reward <= result.theory_reward + 1e-3
