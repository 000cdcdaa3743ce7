"""Result rows and their formats: JSON for machines, JUnit XML for CI, a text table for people.

One row per check (DESIGN.md "Results"): scenario, case, check, unit, measured, expected, error, tolerance
(with its kind and reason), theory (the check's words) and theory_ref (its first equation ID, whose entry is
``docs/theory.md#<id lowercased>``), status, settings, params, and the MuJoCo and rigidbench versions. A case whose
simulation diverged yields a single row with status ``"diverged"``, ``passed = None`` and the time it
happened: it is never scored against theory. A case whose run raised an exception (a defect of rigidbench, never
of the physics) yields a single row with status ``"error"`` and the exception in ``message``.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import mujoco

from rigidbench.scenario import CaseRun
from rigidbench.theory import theory_ref

PASS, FAIL, DIVERGED, ERROR = "pass", "fail", "diverged", "error"
# A check the engine's float precision cannot resolve (`rigidbench.scenario.UNRESOLVED_FRACTION`): reported, not
# scored.
UNRESOLVED = "unresolved"
# A case the engine in effect cannot simulate (`rigidbench.engines.EngineRefused`): one row, nothing scored.
UNSUPPORTED = "unsupported"


def rows_of(run: CaseRun) -> list[dict[str, Any]]:
    """The result rows of one simulated case."""
    common = {
        "scenario": run.scenario,
        "case": run.case,
        "settings": run.settings,
        "params": run.params,
        "duration": run.duration,
        "nstep": run.nstep,
        "wall_time": run.wall_time,
    }
    if run.timing is not None:
        common["cost"] = run.timing.record(float(run.settings["timestep"]))
    if run.diverged_at is not None:
        return [
            {
                **common,
                "check": "diverged",
                "unit": "s",
                "measured": run.diverged_at,
                "expected": None,
                "error": None,
                "tolerance": None,
                "tolerance_kind": None,
                "tolerance_reason": None,
                "theory": None,
                "theory_ref": None,
                "claim": None,
                "status": DIVERGED,
                "passed": None,
                "diverged_at": run.diverged_at,
            }
        ]
    return [
        {
            **common,
            "check": o.check.name,
            "unit": o.check.unit,
            "measured": o.measured,
            "expected": o.expected,
            "error": o.error,
            "tolerance": o.check.tolerance,
            "tolerance_kind": o.check.kind,
            "tolerance_reason": o.check.reason,
            "theory": o.check.theory,
            "theory_ref": theory_ref(o.check.theory),
            # an identity (exact by symmetry or construction) or an accuracy check (`Check.identity`), and a relative
            # error's floor where it has one (`Check.floor`)
            "claim": o.check.claim,
            **({"tolerance_floor": o.check.floor} if o.check.floor else {}),
            **({"false_alarm": o.check.false_alarm} if o.check.false_alarm else {}),
            "status": UNRESOLVED if o.unresolved else PASS if o.passed else FAIL,
            "passed": None if o.unresolved else o.passed,
            "diverged_at": None,
        }
        for o in run.outcomes
    ]


@dataclass(frozen=True)
class Completion:
    """Whether a run finished: an interrupted run's files say so (issue 20), so that a CI never publishes a
    partial result as a complete one.

    Attributes
    ----------
    total : int
        Cases the run planned.
    not_run : tuple of str
        The cases that did not finish (``scenario:case``, with the job's own parameters if it had any).
    interrupted_by : str or None
        The signal's name (``"SIGINT"``), None for a run that finished.
    """

    total: int
    not_run: tuple[str, ...] = ()
    interrupted_by: str | None = None

    @property
    def complete(self) -> bool:
        return not self.not_run and self.interrupted_by is None

    def line(self) -> str:
        return (
            f"the run was interrupted by {self.interrupted_by} after {self.total - len(self.not_run)} of "
            f"{self.total} cases; not run: {', '.join(self.not_run)}"
        )


def document(rows: Sequence[dict[str, Any]], completion: Completion | None = None) -> dict[str, Any]:
    """The JSON document of a run: versions, whether it is complete (and what was not run), the rows."""
    from rigidbench import __version__

    doc: dict[str, Any] = {"rigidbench": __version__, "mujoco": mujoco.__version__}
    if completion is not None:
        doc["complete"] = completion.complete
        if not completion.complete:
            doc["interrupted_by"] = completion.interrupted_by
            doc["not_run"] = list(completion.not_run)
    doc["results"] = list(rows)
    return doc


def _jsonable(x: Any) -> Any:
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    return x


def atomic_write(path: str, text: str, option: str = "output") -> None:
    """Write `text` to `path` so that a reader never sees half a file (`rigidbench.outputs.write`).

    Raises
    ------
    rigidbench.outputs.OutputError
        If it cannot be written (the previous file is left as it was).
    """
    from rigidbench import outputs

    outputs.write(path, text, option)


def json_text(rows: Sequence[dict[str, Any]], completion: Completion | None = None) -> str:
    return json.dumps(_jsonable(document(rows, completion)), indent=1) + "\n"


def write_json(path: str, rows: Sequence[dict[str, Any]], completion: Completion | None = None) -> None:
    atomic_write(path, json_text(rows, completion), "--json")


def write_junit(path: str, rows: Sequence[dict[str, Any]], completion: Completion | None = None) -> None:
    atomic_write(path, junit_text(rows, completion), "--junit")


def junit_text(rows: Sequence[dict[str, Any]], completion: Completion | None = None) -> str:
    """JUnit XML: one testsuite per scenario, one testcase per check (``case:check``); an interrupted run adds a
    testsuite ``rigidbench`` whose one testcase is an error saying how far it got, so a CI goes red."""
    suites = ET.Element("testsuites", name="rigidbench")
    by_scenario: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        by_scenario.setdefault(row["scenario"], []).append(row)
    for scenario, group in by_scenario.items():
        failures = sum(r["status"] == FAIL for r in group)
        errors = sum(r["status"] in (DIVERGED, ERROR) for r in group)
        suite = ET.SubElement(
            suites,
            "testsuite",
            name=scenario,
            tests=str(len(group)),
            failures=str(failures),
            errors=str(errors),
            time=f"{sum({(r['case']): r.get('wall_time') or 0.0 for r in group}.values()):.3f}",
        )
        props = ET.SubElement(suite, "properties")
        ET.SubElement(props, "property", name="mujoco", value=mujoco.__version__)
        ET.SubElement(props, "property", name="settings", value=json.dumps(group[0]["settings"]))
        for row in group:
            case = ET.SubElement(suite, "testcase", classname=f"rigidbench.{scenario}.{row['case']}", name=row["check"])
            if row.get("theory_ref"):  # the check's entry on the theory page (docs/theory.md), as in the JSON row
                ET.SubElement(ET.SubElement(case, "properties"), "property", name="theory_ref", value=row["theory_ref"])
            if row["status"] == FAIL:
                ET.SubElement(case, "failure", message=_verdict_line(row)).text = row["tolerance_reason"]
            elif row["status"] == DIVERGED:
                ET.SubElement(case, "error", message=f"simulation diverged at t = {row['diverged_at']:.6g} s")
            elif row["status"] == ERROR:
                ET.SubElement(case, "error", message=row["message"])
            elif row["status"] == UNSUPPORTED:
                ET.SubElement(case, "skipped", message=row["message"])
            elif row["status"] == UNRESOLVED:
                ET.SubElement(case, "skipped", message=row["tolerance_reason"])
            ET.SubElement(case, "system-out").text = json.dumps(_jsonable({"params": row["params"]}))
    if completion is not None and not completion.complete:
        suite = ET.SubElement(suites, "testsuite", name="rigidbench", tests="1", failures="0", errors="1")
        case = ET.SubElement(suite, "testcase", classname="rigidbench", name="run-complete")
        ET.SubElement(case, "error", message=completion.line())
    ET.indent(suites)
    return ET.tostring(suites, encoding="unicode", xml_declaration=True) + "\n"


def _verdict_line(row: dict[str, Any]) -> str:
    return (
        f"measured {row['measured']:.10g} {row['unit']}, expected {row['expected']:.10g}: "
        f"{row['tolerance_kind']} error {row['error']:.2e} > tolerance {row['tolerance']:.1e}"
    )


def _num(x: float | None) -> str:
    if x is None:
        return "-"
    return f"{x:.10g}" if math.isfinite(x) else str(x)


def table(rows: Iterable[dict[str, Any]]) -> str:
    """A fixed-width text table: target, check, measured, expected, error, tolerance, verdict."""
    header = ("target", "check", "measured", "expected", "unit", "error", "tolerance", "verdict")
    lines = []
    for r in rows:
        tol = "-" if r["tolerance"] is None else f"{r['tolerance']:.3g} {r['tolerance_kind']}"
        err = "-" if r["error"] is None else f"{r['error']:.2e}"
        if r["status"] == DIVERGED:
            verdict = f"DIVERGED at t={r['diverged_at']:.4g} s"
        elif r["status"] == ERROR:
            verdict = f"ERROR {r['message']}"
        elif r["status"] == UNSUPPORTED:
            verdict = f"UNSUPPORTED {r['message'][r['message'].find('engine ') :]}"
        else:
            verdict = r["status"].upper()
        lines.append(
            (
                f"{r['scenario']}:{r['case']}",
                r["check"],
                _num(r["measured"]),
                _num(r["expected"]),
                r["unit"],
                err,
                tol,
                verdict,
            )
        )
    widths = [max(len(str(x)) for x in col) for col in zip(header, *lines, strict=False)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    out = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    out += [fmt.format(*line) for line in lines]
    return "\n".join(out)


def summary(rows: Sequence[dict[str, Any]]) -> str:
    n = {s: sum(r["status"] == s for r in rows) for s in (PASS, FAIL, DIVERGED, ERROR, UNSUPPORTED, UNRESOLVED)}
    errors = f", {n[ERROR]} errors" if n[ERROR] else ""
    errors += f", {n[UNRESOLVED]} unresolved at the engine's precision" if n[UNRESOLVED] else ""
    unsupported = f", {n[UNSUPPORTED]} case(s) unsupported by the engine" if n[UNSUPPORTED] else ""
    return (
        f"{n[PASS]} passed, {n[FAIL]} failed, {n[DIVERGED]} diverged{errors}{unsupported} "
        f"({len(rows) - n[UNSUPPORTED]} checks)"
    )
