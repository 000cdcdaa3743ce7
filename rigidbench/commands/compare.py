"""``rigidbench compare``: regressions between two runs' results."""

from __future__ import annotations

import argparse

from rigidbench.commands import shared
from rigidbench.exits import EXIT_FAIL, EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser(
        "compare",
        help="regressions between two runs: each check's error before and after, newly failing or passing",
        description="Match the checks of two 'rigidbench run --json' results (e.g. a pinned baseline and a run on a "
        "new MuJoCo) and print each one that changed: newly failing or passing, error grown or shrunk by more than "
        "the noise band (errors at round-off never count), rows missing on either side. Exit 1 when anything is "
        "newly failing, regressed or missing, 0 otherwise.",
    )
    p.add_argument("base", metavar="BASE.json", help="the baseline results")
    p.add_argument("new", metavar="NEW.json", help="the results to check against it")
    p.add_argument(
        "--band",
        type=float,
        default=2.0,
        metavar="FACTOR",
        help="noise band: an error counts as changed when it moves by more than this factor (default 2)",
    )
    p.add_argument("--markdown", metavar="PATH", help="also write the table as Markdown (a CI job summary)")
    p.add_argument("--json", metavar="PATH", help="also write every check's comparison as JSON")


def main(args: argparse.Namespace) -> int:
    from rigidbench import compare, outputs

    outputs.check_all([("--markdown", args.markdown), ("--json", args.json)])
    try:
        base, new = compare.load(args.base), compare.load(args.new)
        changes = compare.compare(base["results"], new["results"], args.band)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    print(compare.table(changes, base, new, args.band), file=shared.human(args.markdown, args.json))
    if args.markdown:
        outputs.write(args.markdown, compare.markdown(changes, base, new, args.band), "--markdown")
    if args.json:
        doc = {"kind": "compare", "band": args.band, "changes": [c.record() for c in changes]}
        outputs.write(args.json, shared.dumps(doc), "--json")
    return EXIT_FAIL if compare.regressed(changes) else EXIT_OK
