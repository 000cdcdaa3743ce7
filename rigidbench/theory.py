"""The repository's theory page (``docs/theory.md``): the IDs that checks cite, and links to their entries.

Every check and domain names its theory in words that begin with the equation IDs it tests, such as ``O1`` or
``T4`` (a family letter and a number), before the first colon or bracket: ``"O3/O4 measured in MuJoCo: ..."``,
``"C2, C8 vs C5: ..."``. Symbols later in the text (``T0``, ``I1``, ``E0``) are the formula's, not IDs. Each ID
is a heading of ``docs/theory.md`` with an explicit anchor, so a result row (its ``theory_ref``), ``rigidbench
list`` and the HTML report can point a reader at the closed form, its conventions, its domain and its source.
"""

from __future__ import annotations

import re

# Where the page lives, relative to the repository root (and to the docs of an installed copy's source).
THEORY_PAGE = "docs/theory.md"
# How an ID is written: a capital family letter and a number from 1 (``T4``, ``A2``); read from the leading clause.
_ID = re.compile(r"\b([A-Z][1-9][0-9]?)\b")
# The leading clause of a theory text: everything before its first colon, bracket or semicolon.
_LEADING = re.compile(r"^[^:(\[;]*")


def theory_ids(text: str) -> list[str]:
    """Every equation ID a check's or domain's theory text cites (in its leading clause), in order, no repeats."""
    seen: list[str] = []
    for found in _ID.findall(_LEADING.match(text).group(0)):
        if found not in seen:
            seen.append(found)
    return seen


def theory_ref(text: str) -> str:
    """The first equation ID of a theory text (the entry the prediction comes from), or ``""`` if it names none."""
    ids = theory_ids(text)
    return ids[0] if ids else ""


def anchor(ref: str) -> str:
    """The anchor of an ID's heading on the theory page (``"O1"`` -> ``"o1"``)."""
    return ref.lower()


def theory_link(ref: str, page: str = THEORY_PAGE) -> str:
    """A link to an ID's entry: ``docs/theory.md#o1`` (relative to the repository root by default)."""
    return f"{page}#{anchor(ref)}" if ref else page
