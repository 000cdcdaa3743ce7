"""Fault injection (issue 20): the CLI driven the way a CI and a careless user drive it.

Signals at random moments (start-up and planning included), file-size limits, outputs that are directories,
devices or symlinks, journals edited at random and written by two runs at once. Whatever happens:

- the exit status is one the README names: 0, 1, 2, 130 or 143;
- stderr holds no traceback;
- a previous results file is either untouched or replaced by a whole document (never half a file), and no
  temporary file is left behind;
- no result mixes settings: every row of a resumed run has the settings a fresh run of its case has;
- no process is left behind (each command runs in its own process group, checked empty afterwards).

The moments and edits are drawn from a seeded generator, so a failure is reproducible; ``RIGIDBENCH_FAULT_SEED``
picks another sequence and ``RIGIDBENCH_FAULT_TRIALS`` runs more (CI runs the slow variant with more trials).
"""

import json
import os
import random
import signal
import subprocess
import sys
import time

import pytest

STATUSES = {0, 1, 2, 130, 143}


def _interpreter_start_up() -> float:
    """How long Python takes to start here before it runs any of rigidbench's code (the longest of three)."""
    longest = 0.0
    for _ in range(3):
        t0 = time.monotonic()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        longest = max(longest, time.monotonic() - t0)
    return longest


# Python's own start-up (before any rigidbench code runs: ~0.05 s on an idle machine, several times that on a busy
# one) handles signals its own way: a SIGINT there is the interpreter's KeyboardInterrupt traceback, a SIGTERM
# kills it outright. Moments start after twice that, measured here.
START = max(0.15, 2 * _interpreter_start_up())
TARGETS = ["pendulum:one-radian", "heavy-top:nutation", "free-symmetric-top:oblate", "pendulum:near-inverted"]
SEED = int(os.environ.get("RIGIDBENCH_FAULT_SEED", "20"))
TRIALS = int(os.environ.get("RIGIDBENCH_FAULT_TRIALS", "4"))


def _run(args, *, signal_at=None, sig=signal.SIGINT, fsize=None, timeout=300):
    """Run the CLI in its own session; optionally signal it after `signal_at` s or limit the file size."""

    def preexec():
        if fsize is not None:
            import resource

            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))

    proc = subprocess.Popen(
        [sys.executable, "-m", "rigidbench", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=preexec,
    )
    if signal_at is not None:
        time.sleep(signal_at)
        _wait_for_handlers(proc)
        if proc.poll() is None:
            proc.send_signal(sig)
    out, err = proc.communicate(timeout=timeout)
    _assert_group_empty(proc.pid)
    # A shell (and a CI runner) reports a process killed by signal N as 128 + N: a SIGTERM in the last milliseconds,
    # when CPython's finalization has restored the default handlers, is status 143 like any other.
    status = 128 - proc.returncode if proc.returncode < 0 else proc.returncode
    return status, out, err


def _handlers_installed(pid: int) -> bool | None:
    """Whether process `pid` catches SIGTERM (its `SigCgt` mask in /proc), which bare Python never does and
    `rigidbench._early_signals` does with SIGINT, from the package's first line to the process's end (SIGINT alone
    goes back to the default at exit, `cli.entry`); None where /proc cannot tell (not Linux, or the process is gone)."""
    try:
        with open(f"/proc/{pid}/status") as status:
            for line in status:
                if line.startswith("SigCgt:"):
                    caught = int(line.split()[1], 16)
                    return bool(caught >> (signal.SIGTERM - 1) & 1)
    except OSError:
        return None
    return None


def _wait_for_handlers(proc, limit: float = 120.0) -> None:
    """Hold a drawn moment back until the command catches SIGINT and SIGTERM (issue 36). Before rigidbench's first
    line runs (`rigidbench._early_signals`) the interpreter itself is starting, and a signal then is Python's own
    KeyboardInterrupt traceback or a plain kill: not what these tests examine. `START` (twice the interpreter's
    measured start-up) kept the moments out of that window on an idle machine, but a start-up slowed by load (five
    processes on two cores) outlasted it, and one draw in a few hundred landed inside: a verdict that depended on
    the load. Waiting for the handlers (Linux: /proc; elsewhere the timing alone) makes it depend on nothing."""
    deadline = time.monotonic() + limit
    while proc.poll() is None and time.monotonic() < deadline:
        if _handlers_installed(proc.pid) is not False:
            return
        time.sleep(0.005)


def _assert_group_empty(pgid):
    # 60 s, not 10: worker processes exiting on a loaded machine (five processes on two cores) can take seconds;
    # a group that really outlives the command stays past any deadline.
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.1)
    pytest.fail(f"processes of group {pgid} outlived the command")


def _sane(status, err):
    assert status in STATUSES, err
    assert "Traceback" not in err, err


def _whole_or_untouched(path, before):
    if not path.exists():
        return
    text = path.read_text()
    if text == before:
        return
    doc = json.loads(text)  # a whole document, never half a file
    assert "results" in doc and isinstance(doc["complete"], bool)
    if not doc["complete"]:
        assert doc["not_run"]


def _no_temporary_files(directory):
    assert not [p.name for p in directory.iterdir() if p.name.startswith(".rigidbench-")]


def test_signals_at_random_moments_end_in_one_line_and_leave_whole_files(tmp_path):
    rng = random.Random(SEED)
    for trial in range(TRIALS):
        out = tmp_path / f"r{trial}.json"
        out.write_text("previous\n")
        jsonl = tmp_path / f"r{trial}.jsonl"
        sig = rng.choice([signal.SIGINT, signal.SIGTERM])
        moment = rng.uniform(START, 3.0)
        status, _, err = _run(
            ["run", "--quiet", "--jobs", "1", "--json", str(out), "--jsonl", str(jsonl), *TARGETS],
            signal_at=moment,
            sig=sig,
        )
        _sane(status, err)
        if status in (130, 143):
            # Silent only when the signal came during CPython's finalization (default handlers restored, `_run`):
            # the run had finished and written its files, which the checks below still examine.
            lines = err.strip().splitlines()
            assert not lines or lines[-1].startswith("rigidbench: interrupted by"), err
        _whole_or_untouched(out, "previous\n")
        _no_temporary_files(tmp_path)
        if jsonl.exists() and jsonl.read_text():
            status, _, err = _run(["run", "--quiet", "--resume", str(jsonl), "--json", str(out)])
            _sane(status, err)
            assert status in (0, 2), err  # finished, or a journal that never got its header (killed first)
            if status == 0:
                _same_settings_as_a_fresh_run(json.loads(out.read_text())["results"])


def test_signals_during_census_and_sweep_planning_and_running(tmp_path):
    rng = random.Random(SEED + 1)
    commands = [
        ["census", "pendulum", "heavy-top", "--n", "4", "--quiet", "--jobs", "1"],
        ["sweep", "pendulum:one-radian", "--integrators", "RK4", "Euler", "--workers", "2", "--quiet"],
    ]
    for trial in range(TRIALS):
        args = commands[trial % 2] + ["--jsonl", str(tmp_path / f"j{trial}.jsonl")]
        status, _, err = _run(args, signal_at=rng.uniform(START, 4.0), sig=rng.choice([signal.SIGINT, signal.SIGTERM]))
        _sane(status, err)


def test_file_size_limits_give_one_line_and_leave_the_previous_file(tmp_path):
    rng = random.Random(SEED + 2)
    for trial in range(TRIALS):
        out = tmp_path / f"out{trial}.json"
        out.write_text("previous\n")
        limit = rng.choice([0, 200, 2000, 6000, 20000, 10**7])
        status, _, err = _run(
            ["run", "--quiet", "--json", str(out), "--jsonl", str(tmp_path / f"j{trial}.jsonl"), *TARGETS[:2]],
            fsize=limit,
        )
        _sane(status, err)
        if status == 2:
            assert err.count("\n") == 1, err
        _whole_or_untouched(out, "previous\n")
        _no_temporary_files(tmp_path)


def test_outputs_that_are_directories_devices_or_symlinks(tmp_path):
    (tmp_path / "dir").mkdir()
    (tmp_path / "target.json").write_text("previous\n")
    (tmp_path / "link.json").symlink_to(tmp_path / "target.json")
    cases = {
        str(tmp_path / "dir"): 2,
        "/dev/null": 0,
        "/dev/full": 2,
        str(tmp_path / "link.json"): 0,
        "-": 0,
    }
    for path, expected in cases.items():
        status, _, err = _run(["run", "--quiet", TARGETS[0], "--json", path])
        _sane(status, err)
        assert status == expected, (path, err)
    assert (tmp_path / "link.json").is_symlink()
    assert json.loads((tmp_path / "target.json").read_text())["complete"] is True


def test_randomly_edited_journals_are_refused_in_one_line_or_resume_without_mixing(tmp_path):
    rng = random.Random(SEED + 3)
    base = tmp_path / "base.jsonl"
    status, _, err = _run(["run", "--quiet", "--jsonl", str(base), *TARGETS[:3]])
    assert status == 0, err
    lines = base.read_text().splitlines()
    for trial in range(TRIALS * 2):
        edited = list(lines)
        i = rng.randrange(len(edited))
        kind = rng.choice(["flip", "cut", "field", "drop", "duplicate"])
        if kind == "flip":
            chars = list(edited[i])
            j = rng.randrange(len(chars))
            chars[j] = rng.choice('0129.,:{}"ae\\')
            edited[i] = "".join(chars)
        elif kind == "cut":
            edited[i] = edited[i][: rng.randrange(len(edited[i]))]
        elif kind == "field":
            value = json.loads(edited[i])
            target = value.get("settings") or value.get("invocation") or value
            key = rng.choice(sorted(target))
            target[key] = rng.choice([None, "abc", 0.004, [1, 2], 42])
            edited[i] = json.dumps(value)
        elif kind == "drop":
            del edited[i]
        else:
            edited.insert(i, edited[i])
        path = tmp_path / f"e{trial}.jsonl"
        path.write_text("\n".join(edited) + "\n")
        out = tmp_path / f"e{trial}.json"
        status, _, err = _run(["run", "--quiet", "--resume", str(path), "--json", str(out)])
        _sane(status, err)
        if status == 2:
            assert err.strip().splitlines()[-1].startswith("rigidbench: error:"), err
        elif status in (0, 1):
            _same_settings_as_a_fresh_run(json.loads(out.read_text())["results"])


def _same_settings_as_a_fresh_run(rows):
    """Every row ran with the settings its case runs with today (read back from a fresh compile)."""
    from rigidbench import registry

    fresh = {}
    for row in rows:
        key = (row["scenario"], row["case"])
        if key not in fresh:
            scenario = registry.get(row["scenario"])
            prep = scenario.prepare(row["case"])
            fresh[key] = json.loads(json.dumps(scenario.settings_record(prep.model, None)))
        assert row["settings"] == fresh[key], (key, row["settings"], fresh[key])


@pytest.mark.slow
def test_many_more_faults(tmp_path, monkeypatch):
    """The same claims over many more random moments and edits (CI's slow run)."""
    global TRIALS
    monkeypatch.setattr(sys.modules[__name__], "TRIALS", 30)
    for test in (
        test_signals_at_random_moments_end_in_one_line_and_leave_whole_files,
        test_file_size_limits_give_one_line_and_leave_the_previous_file,
        test_randomly_edited_journals_are_refused_in_one_line_or_resume_without_mixing,
    ):
        directory = tmp_path / test.__name__
        directory.mkdir()
        test(directory)


def test_a_signal_whose_exception_was_swallowed_stops_the_run_at_the_next_case(capsys):
    """JAX's garbage-collection callback swallows an exception raised in it (a SIGTERM during `import jax` printed
    "Exception ignored" and the run went on to the end, past `timeout`): the noted signal stops the run loop."""
    from rigidbench import interrupt, runner
    from rigidbench.settings import Settings

    interrupt.clear()
    interrupt.note(signal.SIGTERM)  # what the handler does before raising; its exception is taken to be lost
    try:
        jobs = runner.plan(["pendulum:one-radian", "pendulum:small-amplitude"], None, Settings())
        result = runner.run_jobs(jobs, None)
    finally:
        interrupt.clear()
    assert result.interrupted is not None and result.interrupted.status == 143
    assert len(result.missing) == 2


def test_a_sigint_while_the_interpreter_exits_is_status_130_without_a_traceback(tmp_path):
    """After the command, Python's exit runs atexit callbacks (the worker pools join there). A SIGINT then used to be
    Python's KeyboardInterrupt, printed with its traceback ("Exception ignored in atexit callback"); `entry` leaves
    SIGINT at the system default once the command is done, so it ends the process like SIGTERM: 130, no output."""
    code = (
        "import atexit, sys, time\n"
        "atexit.register(lambda: (print('exiting', file=sys.stderr, flush=True), time.sleep(30)))\n"
        "from rigidbench.cli import entry\n"
        "sys.argv = ['rigidbench', 'list']\n"
        "entry()\n"
    )
    listing = tmp_path / "list.txt"
    with listing.open("w") as stdout:  # a file: a pipe this test did not read could fill and stop the command
        proc = subprocess.Popen(
            [sys.executable, "-c", code], stdout=stdout, stderr=subprocess.PIPE, text=True, start_new_session=True
        )
        assert proc.stderr.readline() == "exiting\n"  # the command is done and the interpreter is exiting
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=20)
    assert proc.returncode == -signal.SIGINT, err
    assert err == ""
    assert "pendulum" in listing.read_text()  # the command's own output was whole
