"""Journals a CI can trust (issue 20): resume restores what to run and never where to write; rows keyed by their job
and settings; a journal knows its kind and versions; malformed journals are one line; one writer at a time."""

import json
import os
import subprocess
import sys
import time

import pytest

from rigidbench import __version__, cli, journal

TARGETS = ["pendulum:one-radian", "pendulum:small-amplitude", "heavy-top:nutation"]


@pytest.fixture
def done(tmp_path):
    """A finished run journal of three cases."""
    path = tmp_path / "run.jsonl"
    assert cli.main(["run", "--quiet", "--jsonl", str(path), *TARGETS]) == 0
    return path


def _lines(path):
    return path.read_text().splitlines()


def _edit(path, number, change):
    lines = _lines(path)
    value = json.loads(lines[number - 1])
    change(value)
    lines[number - 1] = json.dumps(value)
    path.write_text("\n".join(lines) + "\n")


def _resume(path, capsys, *extra):
    status = cli.main(["run", "--quiet", "--resume", str(path), *extra])
    return status, capsys.readouterr().err


def test_resume_restores_what_to_run_never_where_to_write(done, tmp_path, capsys):
    _edit(done, 1, lambda h: h["invocation"].update(junit=str(tmp_path / "chosen-by-the-journal.xml")))
    status, err = _resume(done, capsys)
    assert status == 2 and "run.jsonl:1" in err and "'junit'" in err
    assert not (tmp_path / "chosen-by-the-journal.xml").exists()


@pytest.mark.parametrize("line", [2, 5], ids=["row-of-the-first-job", "row-of-the-second-job"])
def test_a_row_edited_to_another_timestep_is_refused_naming_its_line(done, capsys, line):
    _edit(done, line, lambda r: r["settings"].update(timestep=0.004))
    status, err = _resume(done, capsys)
    assert status == 2 and f"run.jsonl:{line}" in err and "timestep" in err and "mix settings" in err


def test_a_header_edited_to_another_timestep_is_refused(done, capsys):
    _edit(done, 1, lambda h: h["invocation"].update(timestep=0.004))
    status, err = _resume(done, capsys)
    assert status == 2 and "mix settings" in err


def test_run_resume_of_a_sweep_journal_is_refused(tmp_path, capsys):
    path = tmp_path / "sweep.jsonl"
    sweep = ["sweep", "--quiet", "pendulum:one-radian", "--integrators", "RK4", "--timesteps", "0.004"]
    sweep += ["--workers", "1"]
    assert cli.main([*sweep, "--jsonl", str(path)]) == 0
    status, err = _resume(path, capsys)
    assert status == 2 and "is a sweep journal" in err


def test_a_journal_of_another_rigidbench_version_is_refused_naming_both(done, capsys):
    _edit(done, 1, lambda h: h.update(rigidbench="0.0.1"))
    status, err = _resume(done, capsys)
    assert status == 2 and "0.0.1" in err and __version__ in err


@pytest.mark.parametrize(
    "content, words",
    [
        (b"[1, 2]\n", "run.jsonl:1"),
        (b"null\n", "run.jsonl:1"),
        (None, "run.jsonl:2"),  # a row 42
        (b"\xff\xfe\n", "run.jsonl:1"),
    ],
    ids=["header-list", "header-null", "row-42", "not-utf8"],
)
def test_malformed_journals_exit_2_naming_the_file_and_line(done, capsys, content, words):
    if content is None:
        lines = _lines(done)
        done.write_text(lines[0] + "\n42\n" + "\n".join(lines[1:]) + "\n")
    else:
        done.write_bytes(content)
    status, err = _resume(done, capsys)
    assert status == 2 and words in err and err.count("\n") == 1


@pytest.mark.parametrize("field", ["job", "mujoco", "invocation"])
def test_a_journal_missing_a_required_field_is_refused(done, capsys, field):
    line = 2 if field == "job" else 1
    _edit(done, line, lambda v: v.pop(field))
    status, err = _resume(done, capsys)
    assert status == 2 and f"run.jsonl:{line}" in err


def test_a_non_numeric_timestep_is_refused(done, capsys):
    _edit(done, 1, lambda h: h["invocation"].update(timestep="abc"))
    status, err = _resume(done, capsys)
    assert status == 2 and "timestep" in err


def test_a_damaged_middle_line_is_named_and_the_rows_after_it_kept(done, capsys):
    lines = _lines(done)
    first = json.loads(lines[1])["job"]  # the jobs are journaled as they complete, in any order
    lines[1] = '{"damaged'  # the first row of the first job written
    done.write_text("\n".join(lines) + "\n")
    record = journal.read(str(done), "run")
    assert any("run.jsonl:2" in w for w in record.warnings)
    assert record.done == set(TARGETS) - {first}  # the jobs after it are kept
    status, err = _resume(done, capsys)
    assert status == 0 and "run.jsonl:2: a damaged line" in err
    assert journal.read(str(done), "run").done == set(TARGETS)


def test_a_forged_job_of_the_wrong_size_cannot_pass_as_done(done, capsys):
    lines = _lines(done)
    row = json.loads(lines[1])
    row["job_size"] = 1
    done.write_text("\n".join([lines[0], json.dumps(row), *lines[4:]]) + "\n")  # one row stands for three
    status, err = _resume(done, capsys)
    assert status == 2 and "has 1 rows, its case has 3 checks" in err


def test_a_second_run_on_the_same_journal_is_refused_naming_the_holder(tmp_path):
    path = tmp_path / "busy.jsonl"
    slow = ["free-asymmetric-top", "free-symmetric-top", "heavy-top"]  # ~6 s on one thread: outlasts a start-up
    first = subprocess.Popen(
        [sys.executable, "-m", "rigidbench", "run", "--quiet", "--jobs", "1", "--jsonl", str(path), *slow],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        # A wait that ends when its condition holds: a long limit costs nothing, a short one fails on a
        # loaded machine (issue 36).
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline and not (path.exists() and path.read_text()):
            time.sleep(0.05)
        second = subprocess.run(
            [sys.executable, "-m", "rigidbench", "run", "--quiet", "--jsonl", str(path), "pendulum"],
            capture_output=True,
            text=True,
            check=False,
        )
        assert second.returncode == 2 and f"process {first.pid}" in second.stderr
    finally:
        first.wait(timeout=600)
    assert first.returncode == 0
    assert {json.loads(line)["scenario"] for line in _lines(path)[1:]} == set(slow)  # nothing merged in


def test_a_missing_journal_is_one_line(tmp_path, capsys):
    status, err = _resume(tmp_path / "nothere.jsonl", capsys)
    assert status == 2 and "no journal at" in err
    assert not os.path.exists(tmp_path / "nothere.jsonl")
