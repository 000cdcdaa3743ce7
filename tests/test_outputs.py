"""Results a CI can trust (issue 20): output paths checked before simulating, devices and FIFOs never replaced,
symlinks followed, modes kept, failed writes leaving the previous file, interrupted runs marked incomplete."""

import json
import os
import stat
import subprocess
import sys
import threading

import pytest

from rigidbench import cli, outputs, runner

FAST = "pendulum:one-radian"


@pytest.fixture
def no_simulation(monkeypatch):
    """Fail the test if anything is simulated."""

    def refuse(*args, **kwargs):
        raise AssertionError("a case was simulated")

    monkeypatch.setattr(runner, "run_job", refuse)


def _main(argv, capsys):
    status = cli.main(argv)
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize(
    "make_path, words",
    [
        (lambda tmp: str(tmp), "is a directory"),
        (lambda tmp: str(tmp / "file.txt" / "out.json"), "Not a directory"),
        (lambda tmp: str(tmp / ("x" * 300 + ".json")), "long"),
    ],
    ids=["directory", "parent-is-a-file", "name-too-long"],
)
def test_a_bad_output_path_exits_2_in_one_line_before_anything_is_simulated(
    tmp_path, capsys, no_simulation, make_path, words
):
    (tmp_path / "file.txt").write_text("x")
    path = make_path(tmp_path)
    for option in ("--json", "--junit", "--jsonl"):
        status, _, err = _main(["run", FAST, option, path], capsys)
        assert status == 2
        assert err.count("\n") == 1 and words in err and option in err


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes to any directory")
def test_an_unwritable_directory_is_refused_before_simulating(tmp_path, capsys, no_simulation):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    status, _, err = _main(["run", FAST, "--json", str(locked / "out.json")], capsys)
    assert status == 2 and "not writable" in err


def test_one_file_given_to_two_outputs_is_refused(tmp_path, capsys, no_simulation):
    path = str(tmp_path / "same")
    status, _, err = _main(["run", FAST, "--json", path, "--jsonl", path], capsys)
    assert status == 2 and "same file" in err


def test_dev_null_stays_a_device_and_dev_full_fails_in_one_line(tmp_path, capsys):
    status, _, err = _main(["run", FAST, "--quiet", "--junit", "/dev/null", "--json", "/dev/null"], capsys)
    assert status == 0, err
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    status, _, err = _main(["run", FAST, "--quiet", "--json", "/dev/full"], capsys)
    assert status == 2 and err.count("\n") == 1 and "/dev/full" in err
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode)


def test_dash_writes_the_json_to_standard_output_and_the_table_to_standard_error():
    proc = subprocess.run(
        [sys.executable, "-m", "rigidbench", "run", FAST, "--quiet", "--json", "-"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["complete"] is True and len(doc["results"]) == 3
    assert "period" in proc.stderr


def test_a_fifo_is_written_in_place(tmp_path, capsys):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got = {}

    def reader():
        with open(fifo) as f:
            got["text"] = f.read()

    thread = threading.Thread(target=reader)
    thread.start()
    status, _, err = _main(["run", FAST, "--quiet", "--json", str(fifo)], capsys)
    thread.join(timeout=30)
    assert status == 0, err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert len(json.loads(got["text"])["results"]) == 3


def test_a_symlink_is_followed_and_kept_and_modes_are_kept(tmp_path, capsys):
    target = tmp_path / "target.json"
    target.write_text("old")
    target.chmod(0o640)
    link = tmp_path / "link.json"
    link.symlink_to(target)
    assert _main(["run", FAST, "--quiet", "--json", str(link)], capsys)[0] == 0
    assert link.is_symlink() and json.loads(target.read_text())["complete"] is True
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    umask = os.umask(0o027)
    try:
        assert _main(["run", FAST, "--quiet", "--json", str(tmp_path / "new.json")], capsys)[0] == 0
    finally:
        os.umask(umask)
    assert stat.S_IMODE((tmp_path / "new.json").stat().st_mode) == 0o640  # 0666 less the umask, not 0600


def _limited(limit: int):
    def preexec():
        import resource

        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return preexec


def test_a_write_failure_leaves_the_previous_file_whole_and_no_temporary_file(tmp_path):
    previous = tmp_path / "out.json"
    previous.write_text("previous results\n")
    proc = subprocess.run(
        [sys.executable, "-m", "rigidbench", "run", FAST, "--quiet", "--json", str(previous)],
        capture_output=True,
        text=True,
        check=False,
        preexec_fn=_limited(1000),  # the document is ~3 kB: the write fails with EFBIG
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "File too large" in proc.stderr and "Traceback" not in proc.stderr
    assert previous.read_text() == "previous results\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]


def test_a_journal_that_cannot_take_a_whole_job_stops_the_run_loudly(tmp_path):
    command = [sys.executable, "-m", "rigidbench", "run", "pendulum", "--quiet", "--jobs", "1", "--jsonl"]
    whole = tmp_path / "whole.jsonl"
    subprocess.run([*command, str(whole)], capture_output=True, check=True)
    lines = whole.read_bytes().splitlines(keepends=True)
    first = json.loads(lines[1])["job"]
    size = len(lines[0]) + sum(len(x) for x in lines[1:] if json.loads(x)["job"] == first)
    path = tmp_path / "run.jsonl"
    proc = subprocess.run(
        [*command, str(path)],
        capture_output=True,
        text=True,
        check=False,
        preexec_fn=_limited(size + 200),  # the header and the first job fit, not the second one whole
    )
    assert proc.returncode == 2, proc.stderr
    assert "cannot append to journal" in proc.stderr and "Traceback" not in proc.stderr
    from rigidbench import journal

    record = journal.read(str(path), "run")
    assert 1 <= len(record.done) < 4 and not record.warnings  # whole jobs only, nothing torn


def test_an_interrupted_run_writes_files_that_say_so(tmp_path, monkeypatch, capsys):
    real = runner.run_job
    calls = []

    def stop_on_third(job, settings):
        calls.append(job.key)
        if len(calls) == 3:
            raise runner.Interrupted(2)
        return real(job, settings)

    monkeypatch.setattr(runner, "run_job", stop_on_third)
    out, xml = tmp_path / "r.json", tmp_path / "r.xml"
    argv = ["run", "pendulum", "--quiet", "--jobs", "1", "--json", str(out), "--junit", str(xml)]
    status, _, err = _main(argv, capsys)
    assert status == 130 and "interrupted by SIGINT after 2 of 4 cases" in err
    doc = json.loads(out.read_text())
    assert doc["complete"] is False and doc["interrupted_by"] == "SIGINT"
    assert doc["not_run"] == ["pendulum:large-amplitude", "pendulum:near-inverted"]
    assert len(doc["results"]) == 6
    junit = xml.read_text()
    assert 'name="run-complete"' in junit and "interrupted by SIGINT after 2 of 4 cases" in junit


def test_check_all_accepts_standard_output_twice_and_devices():
    outputs.check_all([("--json", "-"), ("--junit", "-"), ("--jsonl", "/dev/null")])
