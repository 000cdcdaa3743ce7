"""Issue 35: the skidding ball's slip deceleration (7/2) mu g, read with the hops' normal impulse put back, sees
g, friction and the ball's inertia at 1e-6 (cue-strike) and g and friction at 1e-6 (cushion-rebound)."""

from __future__ import annotations

import pytest

from rigidbench import registry
from rigidbench.power import Perturbation


def _deceleration(slug: str, case: str, perturb: Perturbation | None = None):
    run = registry.get(slug).run(case, perturb=perturb)
    (outcome,) = [o for o in run.outcomes if o.check.name == "slip-deceleration"]
    return outcome


@pytest.mark.parametrize(("slug", "case"), [("cue-strike", "centre"), ("cushion-rebound", "equator")])
def test_slip_deceleration_passes_unperturbed_and_fails_at_1e_6(slug, case):
    base = _deceleration(slug, case)
    assert base.passed
    # d ln((1 + 1/gamma) mu g) / d ln q: 1 for g and mu, -(1/gamma) / (1 + 1/gamma) = -5/7 for the inertia.
    quantities = {"g": 1.0, "friction": 1.0} | ({"inertia:ball": -5 / 7} if slug == "cue-strike" else {})
    signed_base = (base.measured - base.expected) / base.expected
    for name, share in quantities.items():
        o = _deceleration(slug, case, Perturbation(name, 1e-6))
        assert not o.passed, name
        moved = (o.measured - o.expected) / o.expected - signed_base
        assert moved == pytest.approx(share * 1e-6, rel=0.2), name
