"""Nothing lost, nothing hidden: interrupted runs, resuming, divergence, determinism (issue 9)."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np

from rigidbench import cli, journal, registry
from rigidbench.settings import Settings, profile

VOLATILE = ("wall_time",)


def _stable(rows):
    return [{k: v for k, v in r.items() if k not in VOLATILE} for r in rows]


def test_sigterm_mid_run_leaves_a_valid_journal_and_resume_equals_an_uninterrupted_run(tmp_path):
    targets = [
        "heavy-top:nutation",
        "heavy-top:looping",
        "free-asymmetric-top:intermediate-axis",
        "heavy-top:sleeping",
        "free-symmetric-top",
    ]
    path = tmp_path / "run.jsonl"
    proc = subprocess.Popen(
        [sys.executable, "-m", "rigidbench", "run", "--quiet", "--jsonl", str(path), *targets],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    # A wait that ends when its condition holds: a long limit costs nothing, a short one fails on a
    # loaded machine (issue 36).
    deadline = time.monotonic() + 600
    while time.monotonic() < deadline:  # wait until at least one case is journaled, then kill mid-run
        if path.exists() and len(path.read_text().splitlines()) > 1:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    status = proc.wait(timeout=120)
    assert status == 143, proc.stderr.read()
    partial = journal.read(str(path), "run")
    assert 1 <= len(partial.done) < 6  # some, not all, of the six cases
    assert all(json.loads(line) for line in path.read_text().splitlines())  # every line is valid JSON

    assert cli.main(["run", "--quiet", "--resume", str(path), "--json", str(tmp_path / "resumed.json")]) == 0
    resumed = json.loads((tmp_path / "resumed.json").read_text())["results"]
    assert cli.main(["run", "--quiet", *targets, "--json", str(tmp_path / "whole.json")]) == 0
    whole = json.loads((tmp_path / "whole.json").read_text())["results"]
    assert _stable(resumed) == _stable(whole)
    assert len(journal.read(str(path), "run").done) == 6


def test_a_torn_last_line_is_ignored_and_its_job_redone(tmp_path):
    path = str(tmp_path / "run.jsonl")
    assert cli.main(["run", "--quiet", "--jsonl", path, "heavy-top:nutation", "heavy-top:looping"]) == 0
    text = open(path).read()
    with open(path, "w") as f:
        f.write(text[: len(text) - 40])  # power loss in the middle of the last row
    last = json.loads(text.splitlines()[-1])["job"]  # jobs are journaled as they complete, in any order
    record = journal.read(path, "run")
    assert record.done == {"heavy-top:nutation", "heavy-top:looping"} - {last}
    assert cli.main(["run", "--quiet", "--resume", path]) == 0
    assert journal.read(path, "run").done == {"heavy-top:nutation", "heavy-top:looping"}


def test_resume_refuses_other_targets_and_non_journals(tmp_path, capsys):
    path = str(tmp_path / "run.jsonl")
    assert cli.main(["run", "--quiet", "--jsonl", path, "heavy-top:nutation"]) == 0
    assert cli.main(["run", "--quiet", "--resume", path, "heavy-top:looping"]) == 2
    bogus = tmp_path / "x.jsonl"
    bogus.write_text("hello\n")
    assert cli.main(["run", "--quiet", "--resume", str(bogus)]) == 2
    assert "not a rigidbench journal" in capsys.readouterr().err


def test_blown_up_simulation_is_reported_as_diverged_and_never_scored(tmp_path):
    """A huge timestep on a spinning top: MuJoCo resets the state (bad QACC); the run says so, with the time. (The
    falling top at 20 ms Euler: its run, the longest of heavy-top's at the defaults, sees the energy Euler pumps in
    blow up at ~3.4 s.)"""
    huge = profile("mujoco-default").merged(Settings(timestep=0.02))
    run = registry.get("heavy-top").run("falling", settings=huge)
    assert run.diverged_at is not None and 0 < run.diverged_at < run.duration
    assert run.outcomes == []
    path = tmp_path / "r.json"
    args = ["run", "--quiet", "heavy-top:falling", "--profile", "mujoco-default", "--timestep", "0.02"]
    status = cli.main([*args, "--json", str(path)])
    assert status == 1
    (row,) = json.loads(path.read_text())["results"]
    assert row["status"] == "diverged" and row["passed"] is None and row["diverged_at"] > 0


def test_env_ends_the_episode_when_the_simulation_diverges():
    import gymnasium as gym

    env = gym.make("rigidbench/HeavyTop-v0", profile="mujoco-default", timestep=0.02, frame_skip=5)
    env.reset(options={"case": "falling"})  # blows up at ~3.4 s of its 5.4 s (see the test above)
    for _ in range(10_000):
        obs, reward, terminated, truncated, info = env.step(np.zeros(3))
        if terminated or truncated:
            break
    # issue 20: the diverged step never pays; it scores the worst the rest of the episode could have scored
    from rigidbench.envs.base import DEVIATION_CAP

    assert terminated and info["diverged"] and np.isfinite(obs).all() and reward <= -DEVIATION_CAP


def test_same_inputs_same_results_bit_for_bit():
    a = registry.get("free-asymmetric-top").run("intermediate-axis", keep_trajectory=True)
    b = registry.get("free-asymmetric-top").run("intermediate-axis", keep_trajectory=True)
    np.testing.assert_array_equal(a.trajectory.qpos, b.trajectory.qpos)
    assert [o.measured for o in a.outcomes] == [o.measured for o in b.outcomes]


def test_overridden_settings_are_recorded_as_compiled():
    run = registry.get("heavy-top").run("nutation", settings=Settings(integrator="implicit", timestep=2e-4))
    assert run.settings["integrator"] == "implicit" and run.settings["timestep"] == 2e-4
    assert run.nstep == round(run.duration / 2e-4)


def test_journal_lines_are_fsynced_per_case(tmp_path, monkeypatch):
    calls = []
    real = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (calls.append(fd), real(fd)))
    cli.main(["run", "--quiet", "--jsonl", str(tmp_path / "j.jsonl"), "heavy-top:nutation", "heavy-top:looping"])
    assert len(calls) >= 3  # header + one per case
