"""Relative checks whose expected value reaches 0 inside the ranges a user sees (issue 35): scored against a floor
(`Check.floor`) or refused by the case's regime, never an error of ``inf``."""

import math

import pytest

from rigidbench import registry
from rigidbench.contract import Check, OutsideDomain


def test_a_relative_error_is_taken_against_the_floor_where_the_expected_value_is_smaller():
    check = Check("speed", "m/s", 1e-3, "rel", "reason", "P5: theory", floor=2.0)
    assert check.error(1.001, 1.0) == pytest.approx(0.0005)  # |e| = 1 < floor 2: relative to the floor
    assert check.error(4.004, 4.0) == pytest.approx(0.001)  # |e| = 4 > floor: relative to |e|
    assert check.error(0.0, 0.0) == 0.0
    assert math.isinf(Check("speed", "m/s", 1e-3, "rel", "reason", "P5: theory").error(1e-17, 0.0))


def test_a_plastic_cushion_at_the_no_skid_height_stops_the_ball_and_passes():
    run = registry.get("cushion-rebound").run("no-skid", {"restitution": 0.0})
    final = next(o for o in run.outcomes if o.check.name == "final-speed")
    assert abs(final.expected) < 1e-15  # the ball is stopped dead: v_f = 0 up to round-off
    assert final.check.floor > 0 and final.passed, (final.measured, final.expected, final.error)
    assert all(o.passed for o in run.outcomes)


def test_marble_shot_cop_at_a_refuses_an_offset_past_its_reach_naming_the_regime():
    # A draw of issue 35: offset 0.237 L, where C's recoil never reaches A (expected speed 0).
    params = {"mass": 74.79227110379072, "length": 2.100720447635213, "impulse": 41.47428004059938, "offset": 0.498}
    with pytest.raises(OutsideDomain, match="outside the regime of case 'cop-at-a'"):
        registry.get("marble-shot").prepare("cop-at-a", params)


def test_marble_shot_cop_at_a_passes_at_the_end_of_its_reach():
    run = registry.get("marble-shot").run("cop-at-a", {"offset": 1.05 / 6})
    assert all(o.passed for o in run.outcomes), [(o.check.name, o.error) for o in run.outcomes]


def _ends(scenario, case, base):
    """One parameter at a time put at each end of the range a user sees for `case` (its range, its dependent range
    and the case's regime, intersected; just inside an open end), the others at the case's values."""
    from rigidbench.params import Bound

    for p in scenario.params:
        if p.size != 1 or p.budget:
            continue
        ranges = [p.valid]
        if p.within is not None:
            ranges.append(p.within.range(base))
        regime = case.ranges.get(p.name)
        if regime is not None:
            ranges.append(regime.range(base) if isinstance(regime, Bound) else regime)
        if any(r.magnitude for r in ranges):
            continue
        low, high = max(ranges, key=lambda r: r.low), min(ranges, key=lambda r: r.high)
        for r, end, side in ((low, low.low, -1), (high, high.high, 1)):
            if not math.isfinite(end):
                continue
            is_open = r.low_open if side < 0 else r.high_open
            span = (high.high - low.low) if math.isfinite(high.high - low.low) else max(abs(end), 1.0)
            yield {p.name: end - side * 1e-9 * span if is_open else end}


@pytest.mark.slow
def test_every_relative_check_is_bounded_away_from_zero_or_has_a_floor_at_its_range_ends():
    """Issue 35: a relative check whose expected value is 0 has an error of inf. At every range end of every
    parameter of every case (refused sets aside), each relative check either expects a value away from 0 or
    carries a floor (`Check.floor`)."""
    zero = []
    for slug, scenario in registry.scenarios().items():
        relative = {c.name for c in scenario.checks if c.kind == "rel"}
        for case in scenario.cases:
            base = scenario.resolve(case)
            for overrides in _ends(scenario, case, base):
                try:
                    prep = scenario.prepare(case.name, overrides)
                except ValueError:  # refused before simulating (a domain, a regime, a run too long)
                    continue
                floors = prep.prediction.get("_floor", {})
                for name in relative & set(case.checks):
                    expected = float(prep.prediction[name])
                    floor = floors.get(name, scenario.check(name).floor)
                    if not floor > 0 and abs(expected) < 1e-12:  # SI units: 0 up to round-off
                        zero.append((slug, case.name, name, overrides, expected))
    assert not zero, zero


def test_identities_are_labelled_in_rows_and_the_catalogue():
    """Issue 35: a check that holds exactly by symmetry or construction says so (row ``claim``, `list --json`)."""
    from rigidbench.commands.list import catalogue
    from rigidbench.results import rows_of

    run = registry.get("foucault").run("equator")
    claims = {r["check"]: r["claim"] for r in rows_of(run)}
    assert claims["equator-precession"] == "identity" and claims["platform-rate"] == "identity"
    assert set(claims.values()) <= {"identity", "accuracy"}
    doc = catalogue(registry.scenarios().values())
    labelled = {(s["slug"], c["name"]) for s in doc["scenarios"] for c in s["checks"] if c["claim"] == "identity"}
    assert ("bent-axle", "residual-torque") in labelled and ("heavy-top", "p-psi-drift") in labelled
    assert ("heavy-top", "energy-drift") not in labelled


def test_pivoted_stick_refuses_a_strike_nearer_the_pivot_than_l_over_20_and_passes_at_it():
    """Issue 35 (a census drawing the strike found it): [L/1000, L] was printed, and below ~L/30 the angular velocity
    and the pivot's drift fail (1.6 and 2.9 times their tolerances at L/100)."""
    scenario = registry.get("pivoted-stick")
    length = scenario.defaults()["length"]
    with pytest.raises(ValueError, match="outside its range"):
        scenario.prepare("end", {"strike": length / 100})
    run = scenario.run("end", {"strike": length / 20})
    assert all(o.passed for o in run.outcomes), [(o.check.name, o.error / o.check.tolerance) for o in run.outcomes]


def test_double_pendulum_mode_cases_refuse_a_second_amplitude_off_the_modes_shape():
    scenario = registry.get("double-pendulum")
    with pytest.raises(OutsideDomain, match="outside the regime of case 'slow-mode'"):
        scenario.prepare("slow-mode", {"amplitude1": 0.001, "amplitude2": -0.2})
    assert scenario.prepare("slow-mode", {"amplitude1": 0.001}).params["amplitude2"] > 0
