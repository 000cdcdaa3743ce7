"""``rigidbench list``: the catalogue (scenarios, cases, parameters with units and ranges, domains, checks with
their tolerances and theory), as text for people or as JSON for programs (``--json``)."""

from __future__ import annotations

import argparse
import inspect
from typing import Any

from rigidbench.exits import EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser("list", help="scenarios, cases, parameters (unit, default, range) and checks")
    p.add_argument("scenarios", nargs="*", metavar="SCENARIO", help="only these scenarios")
    p.add_argument(
        "--json",
        nargs="?",
        const="-",
        metavar="PATH",
        help="write the catalogue as JSON to PATH (- or no PATH: standard output) instead of the text",
    )


def main(args: argparse.Namespace) -> int:
    from rigidbench import outputs, registry

    if args.json:
        outputs.check_all([("--json", args.json)])
    try:
        chosen = [registry.get(s) for s in args.scenarios] if args.scenarios else list(registry.scenarios().values())
        if args.json:
            from rigidbench.commands.shared import dumps

            outputs.write(args.json, dumps(catalogue(chosen)), "--json")
            return EXIT_OK
        for sc in chosen:
            print_scenario(sc)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return EXIT_OK


def print_scenario(sc) -> None:
    from rigidbench.theory import theory_link, theory_ref

    print(f"{sc.slug}  ({sc.env_id or 'no gymnasium env'})\n  {sc.title}")
    defaults = sc.defaults()
    print("  parameters:")
    for p in sc.params:
        d = defaults[p.name]
        dtext = ",".join(f"{x:g}" for x in d) if isinstance(d, tuple) else f"{d:g}"
        budget = " (budget: a census draws it up to its default)" if p.budget else ""
        print(f"    {p.name:<14} [{p.unit}]  default {dtext}  range {p.range_text()}{budget}  {p.doc}")
    print("  cases:")
    for c in sc.cases:
        print(f"    {c.name:<18} {c.doc}")
        if c.ranges:
            ranges = ", ".join(f"{name} in {bound}" for name, bound in c.ranges.items())
            print(f"    {'':<18} regime: {ranges} ({c.regime})")
    if sc.domains:
        print("  domains (refused outside, before simulating):")
        for d in sc.domains:
            where = f" [cases {', '.join(d.cases)}]" if d.cases else ""
            print(f"    {d.name}{where}: {d.text} ({d.theory})")
    print("  checks:")
    for ch in sc.checks:
        ref = theory_ref(ch.theory)
        link = f" {theory_link(ref)}" if ref else ""
        claim = f" ({ch.claim})" if ch.claim != "accuracy" else ""
        print(f"    {ch.name:<24} tol {ch.tolerance:.3g} {ch.kind:<3}{claim}  [{ch.theory}]{link}")
    print()


def catalogue(scenarios) -> dict[str, Any]:
    """The catalogue as one JSON document: every scenario with its parameters, cases, domains and checks."""
    from rigidbench import __version__
    from rigidbench.theory import THEORY_PAGE

    return {
        "kind": "catalogue",
        "rigidbench": __version__,
        "theory_page": THEORY_PAGE,
        "scenarios": [scenario_record(sc) for sc in scenarios],
    }


def scenario_record(sc) -> dict[str, Any]:
    from rigidbench.theory import theory_link, theory_ref

    defaults = sc.defaults()
    return {
        "slug": sc.slug,
        "title": sc.title,
        "doc": inspect.cleandoc(type(sc).__doc__ or ""),
        "env_id": sc.env_id,
        "parameters": [
            {
                "name": p.name,
                "unit": p.unit,
                "doc": p.doc,
                "default": list(defaults[p.name]) if isinstance(defaults[p.name], tuple) else defaults[p.name],
                "range": p.range_text(),
                "valid": _range(p.valid),
                "within": None if p.within is None else _range(p.within),
                "size": p.size,
                "integer": p.integer,
                "budget": p.budget,
            }
            for p in sc.params
        ],
        "cases": [
            {
                "name": c.name,
                "doc": c.doc,
                "checks": list(c.checks),
                "ranges": {name: _range(bound) for name, bound in c.ranges.items()},
                "regime": c.regime,
            }
            for c in sc.cases
        ],
        "domains": [
            {
                "name": d.name,
                "theory": d.theory,
                "theory_ref": theory_ref(d.theory),
                "theory_link": theory_link(theory_ref(d.theory)),
                "text": d.text,
                "cases": list(d.cases),
            }
            for d in sc.domains
        ],
        "checks": [
            {
                "name": ch.name,
                "unit": ch.unit,
                "tolerance": ch.tolerance,
                "kind": ch.kind,
                "claim": ch.claim,
                "reason": ch.reason,
                "theory": ch.theory,
                "theory_ref": theory_ref(ch.theory),
                "theory_link": theory_link(theory_ref(ch.theory)),
            }
            for ch in sc.checks
        ],
    }


def _range(bound) -> dict[str, Any]:
    """A `Range` (numbers) or a `Bound` (in words, on other parameters) as JSON."""
    from rigidbench.params import Range

    if isinstance(bound, Range):
        return {
            "text": str(bound),
            "low": bound.low,
            "high": bound.high,
            "low_open": bound.low_open,
            "high_open": bound.high_open,
            "magnitude": bound.magnitude,
        }
    return {"text": bound.text, "needs": list(bound.needs)}
