"""benchmarks/task_speed.py runs end to end (issue 36), so it does not rot: a tiny budget, one task of each family."""

import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "task_speed.py"


@pytest.mark.slow
def test_task_speed_script_prints_its_table():
    argv = ["--tasks", "ScatterToAngle-v0", "TopPrecession-v0", "--seeds", "1", "--shots", "4", "--steps", "40"]
    out = subprocess.run(
        [sys.executable, str(SCRIPT), *argv, "--markdown"], capture_output=True, text=True, timeout=900, check=False
    )
    assert out.returncode == 0, out.stderr
    rows = [line for line in out.stdout.splitlines() if line.startswith("| ")]
    assert len(rows) == 3 and "ScatterToAngle-v0" in rows[1] and "TopPrecession-v0" in rows[2]
