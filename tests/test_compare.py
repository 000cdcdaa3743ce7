"""`rigidbench compare`: regressions between two runs (issue 14)."""

from __future__ import annotations

import copy
import json

import pytest

from rigidbench import cli


@pytest.fixture(scope="module")
def run_doc(tmp_path_factory):
    path = tmp_path_factory.mktemp("compare") / "base.json"
    assert cli.main(["run", "--quiet", "pendulum", "heavy-top:nutation", "--json", str(path)]) == 0
    return json.loads(path.read_text())


def _write(tmp_path, name, doc):
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return str(path)


def test_two_identical_runs_compare_the_same_and_exit_0(tmp_path, run_doc, capsys):
    base, new = _write(tmp_path, "a.json", run_doc), _write(tmp_path, "b.json", run_doc)
    assert cli.main(["compare", base, new]) == 0
    assert "no regression: 19 same (19 checks" in capsys.readouterr().out


def test_a_check_that_fails_in_the_new_run_is_named_and_exits_1(tmp_path, run_doc, capsys):
    worse = copy.deepcopy(run_doc)
    row = next(r for r in worse["results"] if r["case"] == "nutation" and r["check"] == "theta-max")
    row["error"], row["status"], row["passed"] = 1e-3, "fail", False
    markdown = tmp_path / "summary.md"
    code = cli.main(
        ["compare", _write(tmp_path, "a.json", run_doc), _write(tmp_path, "b.json", worse), "--markdown", str(markdown)]
    )
    out = capsys.readouterr().out
    assert code == 1 and "newly failing" in out and "heavy-top:nutation" in out and "theta-max" in out
    text = markdown.read_text()
    assert text.startswith("## rigidbench: comparison") and "| newly failing | heavy-top:nutation | theta-max |" in text


def test_an_error_that_grows_beyond_the_noise_band_is_a_regression(tmp_path, run_doc, capsys):
    worse = copy.deepcopy(run_doc)
    row = next(r for r in worse["results"] if r["case"] == "nutation" and r["check"] == "nutation-period")
    row["error"] = row["error"] * 50  # still passing, but 50x worse
    assert cli.main(["compare", _write(tmp_path, "a.json", run_doc), _write(tmp_path, "b.json", worse)]) == 1
    assert "regressed" in capsys.readouterr().out


def test_a_check_missing_from_the_new_run_exits_1(tmp_path, run_doc, capsys):
    fewer = copy.deepcopy(run_doc)
    fewer["results"] = [r for r in fewer["results"] if r["check"] != "energy-drift"]
    assert cli.main(["compare", _write(tmp_path, "a.json", run_doc), _write(tmp_path, "b.json", fewer)]) == 1
    assert "missing" in capsys.readouterr().out
