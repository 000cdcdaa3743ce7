"""``rigidbench list``: the catalogue (scenarios, cases, parameters with units and ranges, domains, checks with
their tolerances and theory)."""

from __future__ import annotations

import argparse

from rigidbench.exits import EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser("list", help="scenarios, cases, parameters (unit, default, range) and checks")
    p.add_argument("scenarios", nargs="*", metavar="SCENARIO", help="only these scenarios")


def main(args: argparse.Namespace) -> int:
    from rigidbench import registry

    try:
        chosen = [registry.get(s) for s in args.scenarios] if args.scenarios else list(registry.scenarios().values())
        for sc in chosen:
            print_scenario(sc)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return EXIT_OK


def print_scenario(sc) -> None:
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
        print(f"    {ch.name:<24} tol {ch.tolerance:.3g} {ch.kind:<3}  [{ch.theory}]")
    print()
