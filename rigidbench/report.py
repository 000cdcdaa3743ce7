"""The HTML report: one self-contained page (figures embedded as base64 PNG, inline CSS and JS, no external
resource), for people.

Contents: the MuJoCo and rigidbench versions; the settings of each scenario's results; the results table with
pass/fail colouring and a filter by scenario; per scenario the figures of its plot function
(`rigidbench.plots`), simulated under the settings of the results; and, for each sweep document given, the
log-log convergence figures with the fitted orders and a table of the orders.

A small inline script checks on load that every image decoded (``naturalWidth > 0``) and records the count and
any script error in the page's footer (``#selfcheck``, ``data-images-ok``, ``data-errors``): what a headless
browser test reads back.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import mujoco

from rigidbench import plots, registry
from rigidbench.results import DIVERGED, PASS
from rigidbench.settings import Settings
from rigidbench.theory import THEORY_PAGE, theory_link, theory_ref


def load(paths: Sequence[str]) -> tuple[list[dict[str, Any]], list[dict[str, Any]], list[dict[str, Any]]]:
    """Read result documents (`rigidbench run --json`), sweep documents (`rigidbench sweep --json`), and the
    documents of `rigidbench power --json` and `rigidbench census --json`.

    Returns
    -------
    runs, sweeps, audits : list of dict
        ``audits`` are the power and census documents, in the order given.

    Raises
    ------
    ValueError
        If a file is missing, not JSON, or not a rigidbench document of one of these kinds (naming what is wrong).
    """
    runs, sweeps, audits = [], [], []
    for path in paths:
        try:
            with open(path) as f:
                doc = json.load(f)
        except (OSError, json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ValueError(f"--from {path}: {exc}") from None
        if not isinstance(doc, dict) or "mujoco" not in doc:
            raise ValueError(f"--from {path}: not a rigidbench results document (no 'mujoco')")
        if doc.get("kind") == "power":
            _check_list(path, doc.get("limits"), "limits", {"scenario": str, "quantity": str, "caught_by": list})
            audits.append(doc)
            continue
        if doc.get("kind") == "frontier":
            _check_list(path, doc.get("settings"), "settings", {"scenario": str, "integrator": str})
            audits.append(doc)
            continue
        if doc.get("kind") == "census":
            _check_list(path, doc.get("draws"), "draws", {"scenario": str, "case": str, "status": str})
            if not isinstance(doc.get("scenarios"), dict):
                raise ValueError(f"--from {path}: a census document needs 'scenarios'")
            audits.append(doc)
            continue
        if "results" not in doc:
            raise ValueError(f"--from {path}: not a rigidbench results or sweep document (no 'results')")
        _check_rows(path, doc["results"])
        (sweeps if doc.get("kind") == "sweep" else runs).append(doc)
    return runs, sweeps, audits


# What every result row must hold for the report to read it (`rigidbench.results.rows_of`), with its type.
_ROW_FIELDS = {"scenario": str, "case": str, "check": str, "status": str, "settings": dict}


def _check_rows(path: str, rows: Any) -> None:
    """Refuse a document whose ``results`` is not a list of rows with the fields the report reads.

    Raises
    ------
    ValueError
        Naming the file, the row's index and the field.
    """
    _check_list(path, rows, "results", _ROW_FIELDS)


def _check_list(path: str, items: Any, key: str, fields: Mapping[str, type]) -> None:
    if not isinstance(items, list):
        raise ValueError(f"--from {path}: {key!r} must be a list, not {type(items).__name__}")
    for i, item in enumerate(items):
        if not isinstance(item, dict):
            raise ValueError(f"--from {path}: {key}[{i}] is not an object")
        for name, kind in fields.items():
            if not isinstance(item.get(name), kind):
                raise ValueError(f"--from {path}: {key}[{i}] has no valid {name!r}")


def png(figure: Any, dpi: int = 110) -> bytes:
    """A matplotlib figure as PNG bytes (the figure is closed)."""
    buf = io.BytesIO()
    figure.savefig(buf, format="png", dpi=dpi)
    plots.pyplot().close(figure)
    return buf.getvalue()


def _img(data: bytes, alt: str) -> str:
    mime = "image/gif" if data[:3] == b"GIF" else "image/png"
    return f'<img alt="{html.escape(alt)}" src="data:{mime};base64,{base64.b64encode(data).decode()}">'


def _num(x: Any) -> str:
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    return f"{x:.10g}" if math.isfinite(x) else str(x)


def _clip(scenario, settings: Settings | None) -> tuple[plots.Figure, bytes]:
    """A small GIF of the scenario's first case, or an empty payload with the reason it could not be made."""
    import os
    import tempfile

    from rigidbench import render

    target = f"{scenario.slug}:{scenario.cases[0].name}"
    title = f"Clip: {target}"
    try:
        clip = render.render_clip(target, settings=settings, frames=48, fps=16, width=320, height=240)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "clip.gif")
            summary = render.write(clip, path)
            with open(path, "rb") as f:
                data = f.read()
    except (render.RenderError, ValueError) as exc:
        return plots.Figure(title, f"not rendered here ({exc})", None), b""
    caption = (
        f"The whole run of {target} rendered headless: {summary.split(': ', 1)[1]}. The yellow line trails the tip "
        "of each moving body (the point of its geoms farthest from its joint) over the last quarter of the run."
    )
    return plots.Figure(title, caption, None), data


def _settings_of(rows: Sequence[Mapping[str, Any]]) -> Settings | None:
    """The integrator and timestep of a scenario's results (identical across its rows), to re-simulate under."""
    if not rows:
        return None
    s = rows[0]["settings"]
    return Settings(integrator=s.get("integrator"), timestep=s.get("timestep"))


def build(
    runs: Sequence[Mapping[str, Any]],
    sweeps: Sequence[Mapping[str, Any]] = (),
    audits: Sequence[Mapping[str, Any]] = (),
    *,
    progress: Callable[[str], None] | None = None,
    figure_dir: str | None = None,
    clips: bool = False,
) -> str:
    """The report's HTML text.

    Parameters
    ----------
    runs : sequence of result documents
        Their rows make the results table; each scenario present gets its figures.
    sweeps : sequence of sweep documents
        Each gets its convergence figures and order table.
    audits : sequence of power and census documents
        Each gets its table: the detection limits, or the census's tally and refusal reasons.
    figure_dir : str, optional
        Also write every figure there as ``NN-<slug>.png`` (for looking at them one by one).
    clips : bool
        Also embed a short GIF of each scenario's first case (`rigidbench.render`; needs OpenGL and Pillow). A
        scenario that cannot be rendered here gets a line saying why instead.

    Raises
    ------
    plots.MissingDependency
        If matplotlib is not installed.
    """
    plots.pyplot()  # fail early, with the install hint, before any simulation
    rows = [r for doc in runs for r in doc["results"]]
    versions = sorted({doc["mujoco"] for doc in (*runs, *sweeps)}) or [mujoco.__version__]
    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    say = progress or (lambda _msg: None)
    figures: list[tuple[str, plots.Figure, bytes]] = []
    for slug in scenarios:
        try:
            scenario = registry.get(slug)
        except ValueError:
            continue  # results from a scenario this install does not have: table only
        ctx = plots.PlotContext(scenario, _settings_of([r for r in rows if r["scenario"] == slug]))
        if clips:
            say(f"clip: {slug}")
            figures.append((slug, *_clip(scenario, ctx.settings)))
        for fn in plots.plots_for(slug):
            say(f"figures: {slug} ({fn.__name__})")
            for fig in fn(ctx):
                figures.append((slug, fig, png(fig.figure)))
    from rigidbench.plots.convergence import convergence_figures

    for doc in sweeps:
        say(f"figures: convergence (mujoco {doc['mujoco']})")
        for fig in convergence_figures(doc):
            slug = fig.title.split(": ", 1)[1].split(":", 1)[0]
            figures.append((slug, fig, png(fig.figure)))
    if figure_dir is not None:
        import os

        os.makedirs(figure_dir, exist_ok=True)
        for i, (slug, _fig, data) in enumerate(figures):
            if not data:
                continue
            ext = "gif" if data[:3] == b"GIF" else "png"
            with open(os.path.join(figure_dir, f"{i:02d}-{slug}.{ext}"), "wb") as f:
                f.write(data)
    return _page(rows, runs, sweeps, versions, figures, audits)


def _page(rows, runs, sweeps, versions, figures, audits=()) -> str:
    from rigidbench import __version__

    all_slugs = list(dict.fromkeys([*(r["scenario"] for r in rows), *(s for s, _f, _d in figures)]))
    n_pass = sum(r["status"] == PASS for r in rows)
    n_div = sum(r["status"] == DIVERGED for r in rows)
    out = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        "<title>rigidbench report</title>",
        f"<style>{_CSS}</style></head><body>",
        "<h1>rigidbench: MuJoCo against classical mechanics</h1>",
        f"<p class=meta>rigidbench {html.escape(__version__)} &middot; MuJoCo {html.escape(', '.join(versions))}"
        f" &middot; {len(rows)} checks: {n_pass} passed, {len(rows) - n_pass - n_div} failed, {n_div} diverged</p>",
        '<p><label for=filter>Scenario: </label><select id=filter><option value="">all</option>',
        *[f'<option value="{html.escape(s)}">{html.escape(s)}</option>' for s in all_slugs],
        "</select></p>",
    ]
    if rows:
        out += [
            "<h2>Settings</h2>",
            _settings_table(rows),
            "<h2>Results</h2>",
            f"<p class=meta>Each theory ID links to its entry (closed form, conventions, domain, source) in "
            f"<code>{THEORY_PAGE}</code> of the rigidbench repository. The links are relative to the repository's "
            f"root: they open from a report written there (<code>rigidbench report --out report.html</code> in a "
            f"clone); elsewhere, open <code>{THEORY_PAGE}</code> and find the ID's heading. Hover a row for the "
            f"check's theory and tolerance in words.</p>",
            _results_table(rows),
        ]
    for slug in all_slugs:
        mine = [(f, d) for s, f, d in figures if s == slug]
        if not mine:
            continue
        out.append(f'<section class=scenario data-scenario="{html.escape(slug)}"><h2>{html.escape(slug)}</h2>')
        for fig, data in mine:
            if not data:  # a clip that could not be rendered here
                out.append(f"<p class=meta>{html.escape(fig.title)}: {html.escape(fig.caption)}</p>")
                continue
            out.append(
                f"<figure>{_img(data, fig.title)}<figcaption><b>{html.escape(fig.title)}.</b> "
                f"{html.escape(fig.caption)}</figcaption></figure>"
            )
        out.append("</section>")
    for doc in sweeps:
        out += [f"<h2>Observed orders of convergence (mujoco {html.escape(doc['mujoco'])})</h2>", _orders_table(doc)]
        if doc.get("fit_rule"):
            out.append(f"<details><summary>Fit rule</summary><pre>{html.escape(doc['fit_rule'])}</pre></details>")
    for doc in audits:
        sections = {"power": _power_section, "census": _census_section, "frontier": _frontier_section}
        out += sections[doc["kind"]](doc)
    out += [
        '<footer id=selfcheck data-images-ok="" data-errors="">checking images...</footer>',
        f"<script>{_JS}</script>",
        "</body></html>",
    ]
    return "\n".join(out) + "\n"


def _table(header: Sequence[str], lines: Sequence[Sequence[Any]]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in line) + "</tr>" for line in lines)
    return f"<table><tr>{head}</tr>{body}</table>"


def _power_section(doc: Mapping[str, Any]) -> list[str]:
    """The detection limits of `rigidbench power`: one row per scenario and simulated quantity."""
    lines = []
    for lim in doc["limits"]:
        detected = f"{lim['detected']:.0e}" if lim.get("detected") else "> 1e-02"
        theory = lim.get("theory_sensitivity")
        lines.append(
            (
                lim["scenario"],
                lim["quantity"],
                detected,
                ", ".join(lim["caught_by"][:3]) or "-",
                f"{theory:.0e}" if theory else "> 1e-02 (independent of it)",
            )
        )
    intro = (
        "Each quantity of the simulated model was scaled by 1 + delta while the prediction and the measurement kept "
        "the unperturbed model (a rate: or load: quantity is a parameter the simulated start state or controls "
        "were computed from); <i>detected at</i> is the smallest delta (1e-2 .. 1e-8, by decades) at which some "
        "check failed; <i>theory moves at</i> is the delta at which the prediction itself moves by a tolerance."
    )
    complete = "" if doc.get("complete", True) else " (interrupted: incomplete)"
    return [
        f"<h2>Detection limits: rigidbench power (mujoco {html.escape(doc['mujoco'])}, profile "
        f"{html.escape(str(doc.get('profile')))}){complete}</h2>",
        f"<p>{intro}</p>",
        _table(("scenario", "quantity", "detected at", "caught by", "theory moves at"), lines),
    ]


def _frontier_section(doc: Mapping[str, Any]) -> list[str]:
    """Speed against accuracy: one figure per scenario and the cheapest settings per target error."""
    from rigidbench.plots.frontier import frontier_figures

    m = doc.get("machine", {})
    out = [
        f"<h2>Speed against accuracy (mujoco {html.escape(doc['mujoco'])}; {html.escape(str(m.get('cpu')))}, "
        f"{m.get('cpus')} CPUs)</h2>"
    ]
    for fig in frontier_figures(doc):
        slug = fig.title.split(": ", 1)[1]
        out.append(
            f'<figure data-scenario="{html.escape(slug)}">{_img(png(fig.figure), fig.title)}<figcaption><b>'
            f"{html.escape(fig.title)}.</b> {html.escape(fig.caption)}</figcaption></figure>"
        )
    lines = []
    for a in doc.get("answers", []):
        pick = a.get("cheapest")
        where = f"{pick['integrator']} x{pick['scale']:g}" if pick else f"none (best {a['best_error']:.2e})"
        cost = f"{pick['cpu_per_sim_second']:.3g}" if pick else "-"
        speed = a.get("times_cheaper_than_reference")
        lines.append(
            (
                a["scenario"],
                a.get("check") or "all",
                f"{a['target_error']:g}",
                where,
                cost,
                f"{speed:.3g}" if speed else "-",
            )
        )
    if lines:
        header = ("scenario", "check", "target error", "cheapest setting", "CPU s/sim s", "x cheaper than reference")
        out += ["<p>The cheapest setting whose error is at most the target:</p>", _table(header, lines)]
    return out


def _census_section(doc: Mapping[str, Any]) -> list[str]:
    """The tally of `rigidbench census` and its refusals by reason."""
    keys = ("drawn", "refused", "passed", "failed", "crashed")
    lines = [(slug, *(t.get(k, 0) for k in keys)) for slug, t in doc["scenarios"].items()]
    reasons = [(slug, reason, n) for slug, t in doc["scenarios"].items() for reason, n in t.get("refusals", {}).items()]
    bad = [d for d in doc["draws"] if d["status"] in ("failed", "crashed")]
    out = [
        f"<h2>Census: {doc.get('n')} draws per scenario, seed {doc.get('seed')} (mujoco "
        f"{html.escape(doc['mujoco'])})</h2>",
        _table(("scenario", *keys), lines),
    ]
    if reasons:
        out += ["<p>Refused before simulating, by reason:</p>", _table(("scenario", "reason", "draws"), reasons)]
    if bad:
        out += [
            "<p>Failed or crashed draws:</p>",
            _table(("status", "command"), [(d["status"], d.get("command", "")) for d in bad]),
        ]
    return out


def _settings_table(rows) -> str:
    keys = ["integrator", "timestep", "cone", "solref", "solimp", "disabled", "mujoco"]
    seen: dict[tuple, tuple[str, dict]] = {}  # one line per scenario and distinct settings
    for r in rows:
        key = (r["scenario"], *(json.dumps(r["settings"].get(k)) for k in keys))
        seen.setdefault(key, (r["scenario"], r["settings"]))
    head = "".join(f"<th>{k}</th>" for k in ["scenario", *keys])
    body = []
    for slug, s in seen.values():
        cells = "".join(f"<td>{html.escape(_setting(s.get(k)))}</td>" for k in keys)
        body.append(f'<tr data-scenario="{html.escape(slug)}"><td>{html.escape(slug)}</td>{cells}</tr>')
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _setting(value) -> str:
    """A settings cell: a number, a tuple of numbers, or names (the disabled stages: "-" when none)."""
    if isinstance(value, (list, tuple)):
        if all(isinstance(v, str) for v in value):
            return ", ".join(value) or "-"
        return str(tuple(value))
    return _num(value)


def _results_table(rows) -> str:
    head = "".join(
        f"<th>{h}</th>"
        for h in (
            "scenario:case",
            "check",
            "theory",
            "measured",
            "expected",
            "unit",
            "error",
            "tolerance",
            "verdict",
            "mujoco",
        )
    )
    body = []
    for r in rows:
        tol = "-" if r.get("tolerance") is None else f"{r['tolerance']:.0e} {r['tolerance_kind']}"
        err = "-" if r.get("error") is None else f"{r['error']:.2e}"
        verdict = r["status"].upper()
        if r["status"] == DIVERGED:
            verdict += f" at t = {r['diverged_at']:.4g} s"
        title = html.escape(f"{r.get('theory') or ''} | tolerance: {r.get('tolerance_reason') or ''}")
        body.append(
            f'<tr class="{html.escape(r["status"])}" data-scenario="{html.escape(r["scenario"])}" title="{title}">'
            f"<td>{html.escape(r['scenario'])}:{html.escape(r['case'])}</td><td>{html.escape(r['check'])}</td>"
            f"<td>{_theory_cell(r)}</td>"
            f"<td class=n>{_num(r.get('measured'))}</td><td class=n>{_num(r.get('expected'))}</td>"
            f"<td>{html.escape(r.get('unit') or '')}</td><td class=n>{err}</td><td>{tol}</td>"
            f"<td class=verdict>{verdict}</td><td>{html.escape(str(r['settings'].get('mujoco', '')))}</td></tr>"
        )
    return f"<table id=results><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _theory_cell(row: Mapping[str, Any]) -> str:
    """The row's theory ID as a link to its entry on the theory page (`rigidbench.theory.theory_link`), relative
    to the repository root; a document written before rows carried ``theory_ref`` gets it from ``theory``."""
    ref = row.get("theory_ref") or theory_ref(row.get("theory") or "")
    if not ref:
        return "-"
    # an identity (exact by symmetry or construction, `Check.identity`) or a statistical test (`Check.false_alarm`)
    # says so beside its ID
    claim = f" <small>{row['claim']}</small>" if row.get("claim") in ("identity", "statistical") else ""
    return f'<a href="{html.escape(theory_link(ref))}">{html.escape(ref)}</a>{claim}'


def _orders_table(doc) -> str:
    integrators = list(dict.fromkeys(o["integrator"] for o in doc.get("orders", [])))
    nominal = doc.get("nominal_order", {})
    head = "".join(
        f"<th>{h}</th>" for h in ["scenario:case", "check", *[f"{i} ({nominal.get(i, '?')})" for i in integrators]]
    )
    cells: dict[tuple[str, str, str], dict[str, str]] = {}
    for o in doc.get("orders", []):
        extra = ",".join(f"{k}={v:g}" for k, v in o["param"].items())
        key = (o["scenario"], f"{o['scenario']}:{o['case']}" + (f" [{extra}]" if extra else ""), o["check"])
        if o["observed"] is None:
            text = f"<span class=na>- {html.escape(o['reason'].split(':')[0])}</span>"
        else:
            off = abs(o["observed"] - o["nominal"]) > 0.3
            text = f"<span class={'off' if off else 'on'}>{o['observed']:.2f}</span> ({o['npoints']})"
        cells.setdefault(key, {})[o["integrator"]] = text
    body = [
        f'<tr data-scenario="{html.escape(slug)}"><td>{html.escape(target)}</td><td>{html.escape(check)}</td>'
        + "".join(f"<td>{row.get(i, '')}</td>" for i in integrators)
        + "</tr>"
        for (slug, target, check), row in cells.items()
    ]
    return (
        f"<table class=orders><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"
        "<p class=meta>Observed order (points fitted); nominal order in the header. Green: within 0.3 of nominal; "
        "orange: further off (pre-asymptotic, or a quantity that converges faster or slower than the state).</p>"
    )


def write(path: str, text: str) -> None:
    from rigidbench.results import atomic_write

    atomic_write(path, text, "--out")


def progress_line(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:1.5em auto;max-width:1200px;padding:0 1em;
color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ddd}
.meta{color:#555}
table{border-collapse:collapse;font-size:.85em;margin:.5em 0}
th,td{border:1px solid #ddd;padding:.2em .5em;text-align:left}th{background:#f3f3f3}
td.n{font-family:ui-monospace,monospace;text-align:right}
tr.pass td.verdict{background:#d8f5d8;color:#135e13;font-weight:600}
tr.fail td.verdict{background:#fbd5d5;color:#8a1010;font-weight:600}
tr.diverged td.verdict{background:#fde7c2;color:#7a4a00;font-weight:600}
tr.hidden,section.hidden{display:none}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #eee}
figcaption{font-size:.9em;color:#333;max-width:60em}
span.on{color:#135e13;font-weight:600}span.off{color:#a35a00;font-weight:600}span.na{color:#888}
footer{margin-top:2em;color:#777;font-size:.8em}
"""

_JS = """
(function () {
  var errors = [];
  window.addEventListener('error', function (e) { errors.push(String(e.message)); });
  var filter = document.getElementById('filter');
  filter.addEventListener('change', function () {
    var v = filter.value;
    document.querySelectorAll('[data-scenario]').forEach(function (el) {
      el.classList.toggle('hidden', v !== '' && el.getAttribute('data-scenario') !== v);
    });
  });
  window.addEventListener('load', function () {
    var imgs = document.querySelectorAll('img'), ok = 0;
    imgs.forEach(function (im) { if (im.complete && im.naturalWidth > 0) ok += 1; });
    var foot = document.getElementById('selfcheck');
    foot.setAttribute('data-images-ok', ok + '/' + imgs.length);
    foot.setAttribute('data-errors', errors.join(' | '));
    foot.textContent = ok + ' of ' + imgs.length + ' figures decoded' + (errors.length ? '; errors: ' + errors : '');
  });
})();
"""
