"""The census's draws keep the promise `rigidbench list` prints: every set lies inside its ranges."""

from __future__ import annotations

import numpy as np
import pytest

from rigidbench import census, registry
from rigidbench.params import Range
from rigidbench.scenario import OutsideDomain
from rigidbench.settings import round_step


@pytest.mark.parametrize("slug", sorted(registry.scenarios()))
def test_every_drawn_set_resolves_inside_the_printed_ranges(slug):
    scenario = registry.get(slug)
    rng = np.random.default_rng(7)
    for case in scenario.cases:
        for _ in range(5):
            params = census.draw(scenario, case, rng)
            try:  # raises ValueError on a value outside its range or dependent range
                resolved = scenario.resolve(case, params)
            except OutsideDomain:  # a cross-parameter domain of the theory: a refusal the census counts
                continue
            except ValueError as exc:
                # A value the case derives from drawn ones (drawn itself in one draw in four, as a user's --set would
                # be) may leave its own range: a refusal naming that derived parameter, never a drawn one.
                derived = [n for n, v in case.values.items() if callable(v) and n not in params]
                assert any(f"parameter '{n}'" in str(exc) for n in derived), exc
                continue
            assert set(params) <= set(resolved)


def test_a_magnitude_range_holds_values_of_either_sign_and_draws_both():
    r = Range(1e-6, 3.0, magnitude=True)
    assert -2.0 in r and 2.0 in r and 1e-7 not in r and -4.0 not in r
    rng = np.random.default_rng(1)
    values = [census.draw_value(r, rng) for _ in range(200)]
    assert all(v in r for v in values)
    assert min(values) < 0 < max(values)


def test_a_magnitude_range_met_with_a_signed_one_keeps_the_tighter_sizes():
    both = census._intersect(Range(-1.0, 1.0), Range(1e-3, 3.0, magnitude=True))
    assert both == Range(1e-3, 1.0, magnitude=True)


def test_an_empty_dependent_range_is_redrawn_and_an_unsampleable_case_is_named(monkeypatch):
    scenario = registry.get(sorted(registry.scenarios())[0])
    case = scenario.cases[0]
    calls = {"n": 0}

    def once(s, c, rng):
        calls["n"] += 1
        if calls["n"] < 3:
            raise census.EmptyRange("empty")
        return {"ok": 1}

    monkeypatch.setattr(census, "_draw_once", once)
    assert census.draw(scenario, case, np.random.default_rng(0)) == {"ok": 1} and calls["n"] == 3

    monkeypatch.setattr(census, "_draw_once", lambda s, c, rng: (_ for _ in ()).throw(census.EmptyRange("x")))
    with pytest.raises(ValueError, match=f"{scenario.slug}:{case.name}: no parameter set"):
        census.draw(scenario, case, np.random.default_rng(0))


@pytest.mark.parametrize(
    ("h", "expected"),
    [(2.0e-3, 2e-3), (2.0000001e-3, 2e-3), (1.99e-3, 1e-3), (9.7e-5, 9e-5), (0.35, 0.3), (62.0, 60.0)],
)
def test_a_derived_step_is_rounded_down_to_one_significant_digit(h, expected):
    assert round_step(h) == pytest.approx(expected, rel=1e-15)
    assert round_step(h) <= h * (1 + 1e-12) and round_step(h) > h / 2


def _statistical_failure(seed: float) -> census.Draw:
    """A cross-section draw whose first sample failed one goodness-of-fit test (and passed the rest)."""
    scenario = registry.get("cross-section")
    d = census.Draw("cross-section", "equal-mass", 0, {"seed": seed}, status=census.FAILED)
    d.job = census.check_job(census.Job(scenario, "equal-mass", d.params), None)
    d.rows = [
        {"check": "target-distribution-pvalue", "status": "fail", "claim": "statistical", "false_alarm": 1e-3},
        {"check": "total-cross-section", "status": "pass", "claim": "accuracy"},
    ]
    d.reason = "target-distribution-pvalue"
    return d


def test_a_draw_failing_only_a_statistical_test_is_judged_on_an_independent_second_sample():
    """A goodness-of-fit test at level alpha fails one correct set in 1/alpha: the census re-runs such a draw with
    another sampling seed; it passes only if the second sample passes every check."""
    draws = [_statistical_failure(5.0), _statistical_failure(5.0)]
    draws[1].rows[1]["status"] = "fail"  # an accuracy check failed too: no second sample, the failure stands
    jobs = census.second_samples(draws, None)
    assert list(jobs) == [0]
    second = jobs[0].overrides["seed"]
    assert second != 5.0 and second == census.second_sample_seed(5.0)
    passed = census.RunResult(list(jobs.values()), {jobs[0].key: [{"check": "x", "status": "pass"}]})
    census.settle_second(draws, jobs, passed)
    assert draws[0].status == census.PASSED and draws[0].second["first_failed"] == "target-distribution-pvalue"
    again = _statistical_failure(5.0)
    failed = census.RunResult(
        list(jobs.values()), {jobs[0].key: [{"check": "target-distribution-pvalue", "status": "fail"}]}
    )
    census.settle_second([again], {0: jobs[0]}, failed)
    assert again.status == census.FAILED and "second sample" in again.reason
    tests, failed_first, expected = census.statistics([again])
    assert (tests, failed_first) == (1, 1) and expected == pytest.approx(1e-3)


def test_goodness_of_fit_checks_say_they_are_statistical():
    for slug in ("cross-section", "rutherford"):
        pvalues = [c for c in registry.get(slug).checks if c.name.endswith("-pvalue")]
        assert pvalues and all(c.claim == "statistical" and 0 < c.false_alarm < 1 for c in pvalues)
