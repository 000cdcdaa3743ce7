"""The benchmark script runs end to end (issue 8), so it does not rot: a tiny budget, every section, a record."""

import importlib.util
import json
import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
SECTIONS = {"env.step", "runner", "cross-section", "cli", "render"}


def test_benchmark_script_runs_end_to_end_with_a_tiny_budget(tmp_path):
    out = tmp_path / "bench.json"
    done = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "run.py"), "--quick", "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    assert "InvertedPendulum-v5" in done.stdout and "raw mujoco.rollout" in done.stdout  # the table, with peers
    record = json.loads(out.read_text())
    assert record["quick"] and record["machine"]["load_average"] and record["machine"]["mujoco"]
    rows = record["rows"]
    assert {r["section"] for r in rows} == SECTIONS
    for r in rows:  # a figure with a peer comes with the ratio between them, from the same run
        if r["peer"] and r["value"] is not None:
            assert r["peer_value"] > 0 and math.isfinite(r["ratio"]) and r["ratio"] > 0, r
    env_rows = [r for r in rows if r["section"] == "env.step" and "physics_us" in r]
    assert len(env_rows) >= 2 and all(r["physics_us"] > 0 and r["ceiling"] > 0 for r in env_rows)


def test_profile_summary_counts_samples_inside_env_step_by_line(tmp_path):
    """benchmarks/profile_step.py sums py-spy's raw samples under env.step by the line they were executing."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from profile_step import top_lines
    finally:
        sys.path.pop(0)
    raw = tmp_path / "samples.txt"
    raw.write_text(
        "<module> (loop.py:9);OrderEnforcing.step (common.py:424);ScenarioEnv.step (base.py:149) 70\n"
        "<module> (loop.py:9);OrderEnforcing.step (common.py:424);ScenarioEnv._step_info (base.py:272) 20\n"
        "<module> (loop.py:9);OrderEnforcing.step (common.py:424) 10\n"
        "<module> (loop.py:9);reset (base.py:130) 500\n"
        "<module> (loop.py:9);reset (base.py:130);solve_ivp (ivp.py:655);OdeSolver.step (base.py:197);"
        "rk_step (rk.py:63) 300\n"
    )
    total, lines = top_lines(raw)
    assert total == 100  # the reset's samples (its ODE solver's steps included) are outside env.step
    assert lines[0] == ("ScenarioEnv.step (base.py:149)", 70) and len(lines) == 3


def test_vector_env_benchmark_runs_and_records_each_rate(tmp_path):
    """benchmarks/vector_envs.py (issue 15's throughput table): raw engine, batched and sync rates, with ratios."""
    out = tmp_path / "vector.json"
    done = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "vector_envs.py"), "--envs", "SimplePendulum-v0", "--ns", "2",
         "--rounds", "1", "--seconds", "0.05", "--json", str(out)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    (row,) = json.loads(out.read_text())["rows"]
    assert row["n"] == 2 and row["engine"] == "mujoco"
    assert all(row[k] > 0 for k in ("raw", "batched", "sync", "batched_over_raw", "batched_over_sync"))


@pytest.mark.parametrize("actions", ["zero", "random"])
def test_vector_env_benchmarks_raw_step_carries_the_inputs_its_envs_get(actions):
    """With random actions the raw worlds hold one random action's applied forces (C MuJoCo skips zero ones, so a
    raw step without them times cheaper physics than the envs'); with zero actions, none."""
    spec = importlib.util.spec_from_file_location("vector_envs", ROOT / "benchmarks" / "vector_envs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    worlds, step = module.raw_worlds("rigidbench/StruckStick-v0", 2, None, None, actions)
    step()
    applied = np.abs(worlds.xfrc_applied).sum() + np.abs(worlds.qfrc_applied).sum() + np.abs(worlds.ctrl).sum()
    assert (applied > 0) == (actions == "random")
    worlds.close()


def test_vector_env_benchmark_refuses_a_directory_for_json_before_measuring(tmp_path):
    """--json naming a directory: one line naming the option, exit 1, before any env is built."""
    done = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "vector_envs.py"), "--envs", "SimplePendulum-v0", "--ns", "2",
         "--json", str(tmp_path)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 1
    assert done.stderr.strip().splitlines() == [f"vector_envs.py: --json {tmp_path} is a directory; give a file name"]
    assert "raw" not in done.stdout  # nothing measured
