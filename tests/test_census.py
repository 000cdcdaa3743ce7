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
