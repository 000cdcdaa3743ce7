"""Regressions between two runs (`rigidbench compare BASE.json NEW.json`): a MuJoCo upgrade, a settings change,
another machine, checked check by check against a pinned baseline.

Rows are matched by scenario, case, check and the parameters they ran with. For each pair, the error before and
after and their ratio, and what changed:

- ``newly failing``: passed in BASE, fails or diverged in NEW (a regression, whatever the errors);
- ``newly passing``: the reverse;
- ``regressed`` / ``improved``: both pass (or both fail), and the error grew / shrank by more than the noise band
  `BAND` (a factor, ``--band``) while above its round-off floor on the larger side. The floor is
  `rigidbench.sweep.roundoff_floor`: 100 machine epsilons times the square root of the steps, times the value's
  scale: errors at round-off are noise, never regressions, however their ratio moves;
- ``same``: within the band, or both at round-off;
- ``missing in new`` / ``only in new``: a row on one side only (a case that vanished is a regression; a new one is
  not).

The command exits 1 when anything is newly failing, regressed or missing in NEW, 0 otherwise; ``--markdown PATH``
writes the table for a CI job summary (e.g. ``$GITHUB_STEP_SUMMARY``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from rigidbench.results import PASS

BAND = 2.0

NEWLY_FAILING, NEWLY_PASSING = "newly failing", "newly passing"
REGRESSED, IMPROVED, SAME = "regressed", "improved", "same"
MISSING, ADDED = "missing in new", "only in new"
BAD = (NEWLY_FAILING, REGRESSED, MISSING)
ORDER = (NEWLY_FAILING, MISSING, REGRESSED, NEWLY_PASSING, IMPROVED, ADDED, SAME)


@dataclass(frozen=True)
class Change:
    """One check compared between the two runs."""

    key: tuple[str, str, str, str]  # scenario, case, check, parameters (JSON)
    kind: str
    base: Mapping[str, Any] | None
    new: Mapping[str, Any] | None

    @property
    def ratio(self) -> float | None:
        b, n = _error(self.base), _error(self.new)
        if b is None or n is None:
            return None
        if b == 0:
            return math.inf if n > 0 else 1.0
        return n / b

    def record(self) -> dict[str, Any]:
        return {
            "scenario": self.key[0],
            "case": self.key[1],
            "check": self.key[2],
            "change": self.kind,
            "base_error": _error(self.base),
            "new_error": _error(self.new),
            "ratio": self.ratio,
            "base_status": self.base and self.base["status"],
            "new_status": self.new and self.new["status"],
        }


def _error(row: Mapping[str, Any] | None) -> float | None:
    if row is None or row.get("error") is None:
        return None
    value = row["error"]
    return math.inf if value == "inf" else float(value)


def load(path: str) -> dict[str, Any]:
    """A results document (`rigidbench run --json`).

    Raises
    ------
    ValueError
        Naming the file if it is not one (one line).
    """
    from rigidbench.report import _check_rows

    try:
        with open(path) as f:
            doc = json.load(f)
    except (OSError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: {exc}") from None
    if not isinstance(doc, dict) or "results" not in doc or doc.get("kind") in ("sweep", "power", "census"):
        raise ValueError(f"{path}: not the results of 'rigidbench run --json'")
    _check_rows(path, doc["results"])
    return doc


def _key(row: Mapping[str, Any]) -> tuple[str, str, str, str]:
    params = json.dumps(row.get("params") or {}, sort_keys=True)
    return (row["scenario"], row["case"], row["check"], params)


def _floor(row: Mapping[str, Any]) -> float:
    from rigidbench.sweep import roundoff_floor

    return roundoff_floor(row)


def compare(base: Sequence[Mapping[str, Any]], new: Sequence[Mapping[str, Any]], band: float = BAND) -> list[Change]:
    """Every check of either run, classified (module docstring), in the order of BASE then NEW's extras.

    Raises
    ------
    ValueError
        If `band` is not > 1.
    """
    if not (math.isfinite(band) and band > 1):
        raise ValueError(f"--band = {band!r} must be a factor > 1")
    old = {_key(r): r for r in base}
    now = {_key(r): r for r in new}
    out = []
    for key in [*old, *(k for k in now if k not in old)]:
        b, n = old.get(key), now.get(key)
        if n is None:
            out.append(Change(key, MISSING, b, None))
            continue
        if b is None:
            out.append(Change(key, ADDED, None, n))
            continue
        passed_before, passed_now = b["status"] == PASS, n["status"] == PASS
        if passed_before and not passed_now:
            kind = NEWLY_FAILING
        elif passed_now and not passed_before:
            kind = NEWLY_PASSING
        else:
            kind = _drift(b, n, band)
        out.append(Change(key, kind, b, n))
    return out


def _drift(b: Mapping[str, Any], n: Mapping[str, Any], band: float) -> str:
    eb, en = _error(b), _error(n)
    if eb is None or en is None:
        return SAME
    if max(eb, en) <= max(_floor(b), _floor(n)):
        return SAME  # both at round-off
    if en > band * max(eb, _floor(b)):
        return REGRESSED
    if eb > band * max(en, _floor(n)):
        return IMPROVED
    return SAME


def regressed(changes: Sequence[Change]) -> bool:
    return any(c.kind in BAD for c in changes)


def counts(changes: Sequence[Change]) -> dict[str, int]:
    return {kind: sum(c.kind == kind for c in changes) for kind in ORDER}


def _version(doc: Mapping[str, Any]) -> str:
    return f"rigidbench {doc.get('rigidbench', '?')}, mujoco {doc.get('mujoco', '?')}"


def _fmt(x: float | None) -> str:
    if x is None:
        return "-"
    return f"{x:.2e}" if math.isfinite(x) else str(x)


def _lines(changes: Sequence[Change], everything: bool) -> list[tuple[str, ...]]:
    rows = []
    for kind in ORDER:
        for c in changes:
            if c.kind != kind or (kind == SAME and not everything):
                continue
            ratio = c.ratio
            rows.append(
                (
                    kind,
                    f"{c.key[0]}:{c.key[1]}",
                    c.key[2],
                    _fmt(_error(c.base)),
                    _fmt(_error(c.new)),
                    "-" if ratio is None else (f"{ratio:.3g}" if math.isfinite(ratio) else "inf"),
                    f"{c.base['status'] if c.base else '-'} -> {c.new['status'] if c.new else '-'}",
                )
            )
    return rows


HEADER = ("change", "target", "check", "base error", "new error", "ratio", "status")


def summary(changes: Sequence[Change], band: float) -> str:
    n = counts(changes)
    parts = [f"{v} {k}" for k, v in n.items() if v]
    verdict = "REGRESSED" if regressed(changes) else "no regression"
    return f"{verdict}: {', '.join(parts) or 'nothing to compare'} ({len(changes)} checks; noise band x{band:g})"


def table(changes: Sequence[Change], base: Mapping[str, Any], new: Mapping[str, Any], band: float) -> str:
    """The comparison as text: every check that changed beyond the band, then the summary line."""
    lines = _lines(changes, everything=False)
    out = [f"base: {_version(base)}", f"new:  {_version(new)}", ""]
    if lines:
        widths = [max(len(x) for x in col) for col in zip(HEADER, *lines, strict=True)]
        fmt = "  ".join(f"{{:<{w}}}" for w in widths)
        out += [fmt.format(*HEADER), fmt.format(*("-" * w for w in widths))]
        out += [fmt.format(*line).rstrip() for line in lines]
        out.append("")
    out.append(summary(changes, band))
    return "\n".join(out)


def markdown(changes: Sequence[Change], base: Mapping[str, Any], new: Mapping[str, Any], band: float) -> str:
    """The comparison as GitHub-flavoured Markdown, for a CI job summary."""
    verdict = ":x: **regressed**" if regressed(changes) else ":white_check_mark: **no regression**"
    n = counts(changes)
    out = [
        "## rigidbench: comparison against the baseline",
        "",
        f"{verdict}: " + ", ".join(f"{v} {k}" for k, v in n.items() if v) + f" ({len(changes)} checks)",
        "",
        f"- base: {_version(base)}",
        f"- new: {_version(new)}",
        f"- noise band: an error counts as changed when it moves by more than x{band:g} above its round-off floor "
        "(100 eps sqrt(steps) times its scale)",
        "",
    ]
    lines = _lines(changes, everything=False)
    if lines:
        out += ["| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
        out += ["| " + " | ".join(x.replace("|", "\\|") for x in line) + " |" for line in lines]
    else:
        out.append("Every check is within the noise band of the baseline.")
    return "\n".join(out) + "\n"
