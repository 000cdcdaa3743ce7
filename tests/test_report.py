"""The HTML report: self-contained (every image an embedded PNG that decodes), the results table with verdict
colours and a scenario filter, the plot registry; and, in headless Chromium, a page that loads cleanly."""

import base64
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import pytest

from rigidbench import cli, plots, sweep

IMG = re.compile(r'<img alt="[^"]*" src="data:image/png;base64,([A-Za-z0-9+/=]+)">')


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    """A run of two heavy-top cases (one profile passing, one failing) and a small sweep, as JSON files."""
    d = tmp_path_factory.mktemp("report")
    run = d / "run.json"
    cli.main(["run", "--quiet", "heavy-top:nutation", "heavy-top:looping", "--json", str(run)])
    fail = d / "fail.json"
    cli.main(["run", "--quiet", "heavy-top:nutation", "--profile", "mujoco-default", "--json", str(fail)])
    points = sweep.plan(["heavy-top:nutation"], integrators=["RK4", "Euler"], timesteps=[4e-4, 8e-4, 1.6e-3])
    sw = d / "sweep.json"
    sweep.write_json(str(sw), sweep.execute(points, workers=1))
    return [str(run), str(fail), str(sw)]


@pytest.fixture(scope="module")
def page(documents, tmp_path_factory):
    out = tmp_path_factory.mktemp("page") / "report.html"
    assert cli.main(["report", "--quiet", "--out", str(out), "--from", *documents]) == 0
    return out.read_text()


def test_page_is_self_contained(page):
    assert "<img" in page
    assert not re.search(r"""(src|href)=["']?(https?:|//|file:)""", page), "an external resource"
    assert "<link" not in page and "@import" not in page and "url(" not in page
    imgs = re.findall(r"<img[^>]*>", page)
    assert len(imgs) == len(IMG.findall(page)), "an image that is not an embedded base64 PNG"
    assert len(imgs) == page.count("<img ")


def test_every_image_is_a_png_that_decodes(page):
    from PIL import Image

    for data in IMG.findall(page):
        with Image.open(io.BytesIO(base64.b64decode(data))) as im:
            assert im.format == "PNG" and im.size[0] > 100 and im.size[1] > 100
            im.load()


def test_results_table_colours_verdicts_and_filters_by_scenario(page):
    assert 'class="pass" data-scenario="heavy-top"' in page
    assert 'class="fail" data-scenario="heavy-top"' in page
    assert "tr.pass td.verdict{background" in page and "tr.fail td.verdict{background" in page
    assert '<select id=filter><option value="">all</option>' in page and '<option value="heavy-top">' in page
    assert "addEventListener('change'" in page


def test_results_table_links_each_theory_id_to_its_entry_on_the_theory_page(page, documents):
    rows = json.loads(open(documents[0]).read())["results"]
    for ref in {r["theory_ref"] for r in rows}:
        assert f'<td><a href="docs/theory.md#{ref.lower()}">{ref}</a></td>' in page
    assert "<th>theory</th>" in page and "<code>docs/theory.md</code>" in page  # and says where the page is


def test_page_states_versions_settings_figures_and_orders(page):
    import mujoco

    assert f"MuJoCo {mujoco.__version__}" in page
    assert "<h2>Settings</h2>" in page and "RK4" in page and "Euler" in page
    assert "Heavy top, nutation: theta(t) and its turning points" in page
    assert "Convergence: heavy-top:nutation" in page
    assert "Observed orders of convergence" in page and "RK4 (4)" in page


def test_plot_registry_covers_the_tops_and_takes_a_new_scenario_in_one_function():
    assert {"heavy-top", "free-asymmetric-top", "free-symmetric-top"} <= set(plots.registered())

    @plots.plot("a-future-scenario")
    def _future(ctx):
        return []

    assert plots.plots_for("a-future-scenario") == [_future]


def test_report_without_matplotlib_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(plots.MissingDependency, match=r"rigidbench\[report\]"):
        plots.pyplot()


def test_bad_report_input_exits_2(tmp_path, capsys):
    bogus = tmp_path / "x.json"
    bogus.write_text(json.dumps({"hello": 1}))
    assert cli.main(["report", "--out", str(tmp_path / "r.html"), "--from", str(bogus)]) == 2
    assert "not a rigidbench results" in capsys.readouterr().err
    assert cli.main(["report", "--out", str(tmp_path / "r.html"), "--from", str(tmp_path / "missing.json")]) == 2


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


@pytest.mark.slow
@pytest.mark.skipif(_chromium() is None, reason="no chromium (Debian: apt-get install chromium)")
def test_full_report_loads_in_headless_chromium_with_every_image_and_no_error(tmp_path):
    """The whole report (every scenario, the reference run, a sweep): no console error, every image decoded,
    and a screenshot that is not blank (saved next to the report for a person to look at)."""
    from PIL import Image

    sw = tmp_path / "sweep.json"
    assert (
        cli.main(["sweep", "--quiet", "heavy-top:nutation", "free-asymmetric-top:major-axis", "--json", str(sw)]) == 0
    )
    html_path = tmp_path / "report.html"
    assert cli.main(["report", "--quiet", "--out", str(html_path), "--from", str(sw)]) == 0
    flags = [
        "--headless",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--enable-logging=stderr",
        "--v=0",
        f"--user-data-dir={tempfile.mkdtemp()}",
    ]
    if os.geteuid() == 0:
        flags.append("--no-sandbox")
    url = html_path.as_uri()
    dom = subprocess.run([_chromium(), *flags, "--dump-dom", url], capture_output=True, text=True, timeout=120)
    assert dom.returncode == 0, dom.stderr[-2000:]
    footer = re.search(r'<footer id="selfcheck" data-images-ok="(\d+)/(\d+)" data-errors="([^"]*)"', dom.stdout)
    assert footer, "the page's load handler did not run"
    ok, total, errors = int(footer[1]), int(footer[2]), footer[3]
    assert total == html_path.read_text().count("<img ") and total >= 8
    assert ok == total, f"{total - ok} images did not decode"
    assert errors == ""
    console = [line for line in dom.stderr.splitlines() if "CONSOLE" in line or "Uncaught" in line]
    assert console == [], console
    shot = tmp_path / "report.png"
    subprocess.run(
        [_chromium(), *flags, f"--screenshot={shot}", "--window-size=1280,2400", url],
        capture_output=True,
        timeout=120,
        check=True,
    )
    with Image.open(shot) as im:
        pixels = im.convert("L")
        assert pixels.getextrema()[1] - pixels.getextrema()[0] > 100  # text and figures, not a blank page
    keep = os.environ.get("RIGIDBENCH_KEEP_REPORT")
    if keep:
        os.makedirs(keep, exist_ok=True)
        shutil.copy(html_path, keep)
        shutil.copy(shot, keep)


def test_clips_embed_a_moving_gif_per_scenario(documents, gl_available):
    from PIL import Image

    from rigidbench import report

    runs, _, _ = report.load(documents[:1])
    page = report.build(runs, clips=True)
    gifs = re.findall(r'<img alt="Clip: heavy-top:nutation" src="data:image/gif;base64,([A-Za-z0-9+/=]+)">', page)
    assert len(gifs) == 1
    with Image.open(io.BytesIO(base64.b64decode(gifs[0]))) as im:
        assert im.n_frames > 1


def test_report_of_fresh_contact_results_renders_their_settings_and_figures():
    """Results simulated in-process (not read back from JSON) carry solref/solimp as tuples; the settings table
    takes them as it takes JSON lists, and the scenario's figures come out."""
    from rigidbench import report, results, runner

    reference = runner.settings_for("reference")
    jobs = runner.plan(["ball-stick:light-ball"], {}, reference)
    rows = [row for _, batch in runner.execute(jobs, reference) for row in batch]
    assert any(isinstance(row["settings"].get("solref"), tuple) for row in rows)
    page = report.build([results.document(rows)])
    assert "<h2>Settings</h2>" in page and "<td>((-100000000.0, 0.0),)</td>" in page
    assert "Ball on a free stick: velocities after the impact" in page


@pytest.mark.parametrize(
    "doc, words",
    [
        ({"mujoco": "4.0.0", "results": {"a": 1}}, "'results' must be a list"),
        ({"mujoco": "4.0.0", "results": [{"scenario": "pendulum", "case": "x", "check": "period"}]}, "'status'"),
        ({"mujoco": "4.0.0", "results": [42]}, "results[0] is not an object"),
        ({"mujoco": "4.0.0", "kind": "power", "limits": [{"scenario": "x"}]}, "limits[0]"),
    ],
    ids=["results-not-a-list", "row-without-status", "row-42", "power-without-quantity"],
)
def test_report_from_a_malformed_document_is_one_line_and_exit_2(tmp_path, capsys, doc, words):
    from rigidbench import cli

    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    assert cli.main(["report", "--from", str(path), "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "bad.json" in err
    assert not (tmp_path / "r.html").exists()


def test_report_shows_the_power_and_census_tables(tmp_path):
    from rigidbench import report, results

    power = {
        "kind": "power",
        "mujoco": "4.0.0",
        "profile": "reference",
        "limits": [
            {
                "scenario": "pendulum",
                "quantity": "g",
                "detected": 1e-8,
                "caught_by": ["one-radian:energy-drift"],
                "theory_sensitivity": 1e-5,
            },
        ],
    }
    census = {
        "kind": "census",
        "mujoco": "4.0.0",
        "n": 2,
        "seed": 1,
        "scenarios": {
            "pendulum": {
                "drawn": 2,
                "refused": 1,
                "passed": 1,
                "failed": 0,
                "crashed": 0,
                "refusals": {"small-oscillation": 1},
            }
        },
        "draws": [{"scenario": "pendulum", "case": "one-radian", "status": "passed"}],
    }
    for name, doc in (("p.json", power), ("c.json", census)):
        (tmp_path / name).write_text(json.dumps(doc))
    runs, sweeps, audits = report.load([str(tmp_path / "p.json"), str(tmp_path / "c.json")])
    page = report.build([results.document([])], sweeps, audits)
    assert "Detection limits" in page and "one-radian:energy-drift" in page
    assert "Census: 2 draws per scenario, seed 1" in page and "small-oscillation" in page
