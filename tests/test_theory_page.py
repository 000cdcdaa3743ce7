"""The theory page is in the repository (issue 34): every equation ID a check or a domain cites is a heading of
``docs/theory.md`` with its anchor, and no file points outside the repository for the theory."""

import pathlib
import re

from rigidbench import registry, theory

ROOT = pathlib.Path(__file__).resolve().parents[1]
# An explicit anchor in a heading: ``### <a id="o1"></a>O1 Exact large-amplitude pendulum period``.
HEADING_ANCHOR = re.compile(r'^#+\s*<a id="([^"]+)"></a>', re.MULTILINE)
# What `grep -r "shared/" README.md docs rigidbench envs analytic models` must not find (issue 34, "Done when").
SEARCHED = ("README.md", "docs", "rigidbench", "envs", "analytic", "models")


def _anchors() -> set[str]:
    return set(HEADING_ANCHOR.findall((ROOT / theory.THEORY_PAGE).read_text(encoding="utf-8")))


def _cited() -> dict[str, list[str]]:
    """Every ID named by a check's or a domain's theory text, with where it is cited."""
    cited: dict[str, list[str]] = {}
    for slug, scenario in registry.scenarios().items():
        texts = [(f"{slug} check {c.name}", c.theory) for c in scenario.checks]
        texts += [(f"{slug} domain {d.name}", d.theory) for d in scenario.domains]
        for where, text in texts:
            for ref in theory.theory_ids(text):
                cited.setdefault(ref, []).append(where)
    return cited


def test_every_cited_theory_id_is_an_anchored_heading_of_the_theory_page():
    cited = _cited()
    assert len(cited) > 40  # the walk found the scenarios' citations
    anchors = _anchors()
    missing = {ref: where[:3] for ref, where in cited.items() if theory.anchor(ref) not in anchors}
    assert not missing, f"IDs cited with no heading in {theory.THEORY_PAGE}: {missing}"


def test_every_check_names_an_id_and_its_link_points_at_a_heading():
    anchors = _anchors()
    for slug, scenario in registry.scenarios().items():
        for check in scenario.checks:
            ref = theory.theory_ref(check.theory)
            assert ref, f"{slug} check {check.name} names no theory ID: {check.theory!r}"
            page, _, fragment = theory.theory_link(ref).partition("#")
            assert page == theory.THEORY_PAGE and fragment in anchors


def test_theory_page_anchors_are_unique_and_follow_the_id_convention():
    text = (ROOT / theory.THEORY_PAGE).read_text(encoding="utf-8")
    found = HEADING_ANCHOR.findall(text)
    assert len(found) == len(set(found)), "a repeated anchor"
    for line in text.splitlines():
        m = re.match(r'^#+\s*<a id="([^"]+)"></a>(\S+)', line)
        if m and re.fullmatch(r"[A-Z][0-9]+[a-z]?", m.group(2)):
            assert m.group(1) == theory.anchor(m.group(2)), line


def test_no_file_refers_to_a_theory_outside_the_repository():
    offenders = []
    for name in SEARCHED:
        path = ROOT / name
        files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
        for f in files:
            if "__pycache__" in f.parts:
                continue
            try:
                text = f.read_text(encoding="utf-8")
            except UnicodeDecodeError:
                continue  # a binary file (a figure)
            lines = enumerate(text.splitlines(), 1)
            offenders += [f"{f.relative_to(ROOT)}:{i}" for i, line in lines if "shared/" in line]
    assert not offenders, f'"shared/" (a path outside the repository) in: {offenders[:20]}'
