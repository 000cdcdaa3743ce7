"""cut-shot in MuJoCo: what the checks do not say (docs/theory.md B4)."""

import math

import pytest

from rigidbench import registry
from rigidbench.analytic import cut_shot


@pytest.fixture(scope="module")
def thirty():
    return registry.get("cut-shot").run("thirty", keep_trajectory=True)


def test_thirty_degree_cut_passes_and_deflects_about_33_7_degrees(thirty):
    assert all(o.passed for o in thirty.outcomes), [(o.check.name, o.error) for o in thirty.outcomes if not o.passed]
    delta = next(o.measured for o in thirty.outcomes if o.check.name == "deflection")
    assert math.degrees(delta) == pytest.approx(33.7, abs=0.1)


def test_deflection_check_catches_a_wrong_ball(thirty):
    """A hollow ball's rule (gamma = 2/3) is off by more than the closed-form check's tolerance: the check can fail."""
    outcome = next(o for o in thirty.outcomes if o.check.name == "deflection-closed-form")
    wrong = float(cut_shot.deflection(math.pi / 6, gamma=2 / 3))
    assert abs(outcome.measured - wrong) > 5 * outcome.check.tolerance


def test_final_speeds_catch_a_missing_contact_friction(thirty):
    """Without the friction impulse mu M g t_c the impact adds (predicted), the object ball's final speed misses by
    more than the reported error: the prediction's correction is needed, and the check resolves it."""
    p = thirty.prediction
    outcome = next(o for o in thirty.outcomes if o.check.name == "object-final-speed")
    shot = p["_shot"]
    bare = math.hypot(*shot.object_final) - 5 / 7 * p["_mu"] * 9.81 * p["_t_c"]
    assert abs(outcome.measured - bare) > 10 * abs(outcome.measured - outcome.expected)
