"""The repository layout the user asked for, and the rule that theory never depends on the simulator."""

import ast
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
FORBIDDEN = ("mujoco", "gymnasium", "dm_control", "dm_env", "rigidbench.envs", "rigidbench.scenario")


@pytest.mark.parametrize("path", sorted((ROOT / "analytic").glob("*.py")), ids=lambda p: p.name)
def test_analytic_imports_no_simulator(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            names = [node.module]
        for name in names:
            assert not name.startswith(FORBIDDEN), f"{path.name} imports {name}"


def test_top_level_layout_is_the_users():
    for name in ("pyproject.toml", "README.md", "models", "envs", "analytic", "tests", "rigidbench"):
        assert (ROOT / name).exists(), name


def test_every_scenario_has_a_model_file_of_the_same_stem():
    from rigidbench import registry

    for scenario in registry.scenarios().values():
        assert (ROOT / "models" / f"{scenario.file_stem}.xml").exists()
        assert (ROOT / "envs" / f"{scenario.file_stem}.py").exists()


def test_generic_names_are_not_installed_as_top_level_packages(tmp_path):
    """Outside the checkout, only `rigidbench` is importable: `envs`, `analytic`, `models` are its subpackages."""
    code = (
        "import importlib.util as u; "
        "print([n for n in ('envs', 'analytic', 'models') if u.find_spec(n)]); "
        "print(bool(u.find_spec('rigidbench.envs') and u.find_spec('rigidbench.analytic')))"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["[]", "True"]


def test_models_declare_radians_and_autolimits():
    for xml in (ROOT / "models").glob("*.xml"):
        assert '<compiler angle="radian" autolimits="true"' in xml.read_text(), xml.name


def test_importing_every_analytic_module_loads_no_simulator():
    """The rule above, through every import an analytic module makes (rigidbench's own modules included). The
    package's own import registers every env, so the subprocess stands in bare packages for `rigidbench` and
    `rigidbench.analytic` (their folders, without running their __init__) and imports the analytic modules alone."""
    names = sorted(p.stem for p in (ROOT / "analytic").glob("*.py") if p.stem != "__init__")
    forbidden = ("mujoco", "gymnasium", "dm_control", "dm_env", "rigidbench.envs", "rigidbench.scenario")
    code = (
        "import importlib, sys, types\n"
        "for name, folder in (('rigidbench', 'rigidbench'), ('rigidbench.analytic', 'analytic')):\n"
        "    package = types.ModuleType(name)\n"
        f"    package.__path__ = [{str(ROOT)!r} + '/' + folder]\n"
        "    sys.modules[name] = package\n"
        f"for n in {names!r}: importlib.import_module('rigidbench.analytic.' + n)\n"
        f"print(sorted(m for m in sys.modules if m.startswith({forbidden!r})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"
