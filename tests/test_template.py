"""The scenario template a newcomer copies (docs/templates/vertical_throw.py and .xml, docs/scenarios.md) works as
written: both its cases pass every check under `reference`, and its env passes gymnasium's checker.

It runs in a child process: importing the template defines an env class, which the registry (it walks the
subclasses of `ScenarioEnv`) would otherwise find in this process.
"""

import subprocess
import sys
from pathlib import Path

TEMPLATES = Path(__file__).resolve().parents[1] / "docs" / "templates"

CHILD = r"""
import importlib.util, sys
from pathlib import Path
import mujoco, numpy as np
from gymnasium.utils.env_checker import check_env

here = Path(sys.argv[1])
spec = importlib.util.spec_from_file_location("vertical_throw_template", here / "vertical_throw.py")
module = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
# Copied into the repository the model is models/vertical_throw.xml; here it is read from beside the template.
module.VerticalThrow.spec = lambda self: mujoco.MjSpec.from_file(str(here / "vertical_throw.xml"))

scenario = module.VerticalThrow()
for case in scenario.cases:
    run = scenario.run(case.name)
    assert run.diverged_at is None, case.name
    assert len(run.outcomes) == 3, case.name
    for o in run.outcomes:
        assert o.passed, (case.name, o.check.name, o.measured, o.expected, o.error)
        print(case.name, o.check.name, f"{o.error:.2e}", o.check.tolerance)
try:
    scenario.run(overrides={"speed": 1e3})
except ValueError as exc:
    assert "speed" in str(exc), exc
else:
    raise AssertionError("a speed outside its range was not refused")

env = module.VerticalThrowEnv()
check_env(env, skip_render_check=True)
obs, info = env.reset(seed=0)
worst, done = 0.0, False
while not done:
    obs, reward, terminated, truncated, info = env.step(np.zeros(1, dtype=np.float32))
    worst, done = max(worst, info["deviation"]), terminated or truncated
assert worst < 1e-9, worst  # zero action is the textbook throw
print("env ok", worst)
"""


def test_the_template_scenario_passes_its_checks_and_its_env_the_checker():
    out = subprocess.run([sys.executable, "-c", CHILD, str(TEMPLATES)], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "env ok" in out.stdout
