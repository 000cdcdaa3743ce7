"""The command line: exit statuses, JSON and JUnit outputs, listing, bad input."""

import json
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

from rigidbench import cli


def test_run_writes_json_with_every_row_field(tmp_path, capsys):
    path = tmp_path / "r.json"
    assert cli.main(["run", "--quiet", "heavy-top:nutation", "--json", str(path)]) == 0
    doc = json.loads(path.read_text())
    assert doc["rigidbench"] and doc["mujoco"]
    rows = doc["results"]
    assert rows and all(r["passed"] for r in rows)
    for key in (
        "scenario",
        "case",
        "check",
        "unit",
        "measured",
        "expected",
        "error",
        "tolerance",
        "passed",
        "settings",
        "params",
        "tolerance_reason",
        "theory",
    ):
        assert key in rows[0], key
    assert rows[0]["settings"]["integrator"] == "RK4" and rows[0]["settings"]["timestep"] == 1e-4
    out = capsys.readouterr().out
    assert "theta-max" in out and "PASS" in out


def test_failing_checks_exit_1_and_write_junit_failures(tmp_path):
    path = tmp_path / "r.xml"
    status = cli.main(["run", "--quiet", "heavy-top:nutation", "--profile", "mujoco-default", "--junit", str(path)])
    assert status == 1
    suite = ET.parse(path).getroot().find("testsuite")
    assert suite.get("name") == "heavy-top" and int(suite.get("failures")) > 0
    cases = suite.findall("testcase")
    assert len(cases) == int(suite.get("tests"))
    assert any(c.find("failure") is not None for c in cases)


def test_overrides_override_integrator_and_timestep(tmp_path):
    path = tmp_path / "r.json"
    cli.main(
        [
            "run",
            "--quiet",
            "heavy-top:nutation",
            "--integrator",
            "implicitfast",
            "--timestep",
            "5e-4",
            "--json",
            str(path),
        ]
    )
    settings = json.loads(path.read_text())["results"][0]["settings"]
    assert settings["integrator"] == "implicitfast" and settings["timestep"] == 5e-4


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["--set", "mass=-1", "heavy-top"], "'mass'"),
        (["--set", "bogus=1", "heavy-top"], "unknown parameter 'bogus'"),
        (["--set", "I1=1", "--set", "I2=1.2", "--set", "I3=3", "free-asymmetric-top"], "triangle inequality"),
        (["--set", "I3=5", "heavy-top"], "triangle inequality"),
        (["--integrator", "leapfrog", "heavy-top"], "integrator 'leapfrog'"),
        (["heavy-top:no-such-case"], "unknown case"),
        (["no-such-scenario"], "unknown scenario"),
        (["--set", "omega=1,2", "free-symmetric-top"], "'omega'"),
        (["--set", "tilt", "heavy-top"], "NAME=VALUE"),
        (["--profile", "fastest", "heavy-top"], "profile 'fastest'"),
        (["--set", "tilt=4", "heavy-top"], "'tilt'"),
    ],
)
def test_bad_input_exits_2_with_one_line_naming_the_problem(args, named, capsys):
    assert cli.main(["run", "--quiet", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and named in err[0] and "Traceback" not in err[0]


def test_list_shows_parameters_with_units_defaults_and_ranges(capsys):
    assert cli.main(["list", "heavy-top"]) == 0
    out = capsys.readouterr().out
    assert "spin" in out and "[rad/s]" in out and "default 150" in out and "range" in out
    assert "nutation-period" in out and "sleeping" in out


def test_list_prints_each_checks_theory_link(capsys):
    assert cli.main(["list", "heavy-top"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if "tol " in line]
    assert lines and all("docs/theory.md#" in line for line in lines)


def test_list_json_is_the_catalogue_for_programs(capfd):
    from rigidbench import registry
    from rigidbench.theory import theory_link, theory_ref

    assert cli.main(["list", "--json"]) == 0  # no PATH: standard output, written to its descriptor
    doc = json.loads(capfd.readouterr().out)
    assert doc["kind"] == "catalogue"
    assert [s["slug"] for s in doc["scenarios"]] == list(registry.scenarios())
    for sc in doc["scenarios"]:
        assert sc["title"] and sc["doc"] and "env_id" in sc
        names = {ch["name"] for ch in sc["checks"]}
        assert sc["checks"] and sc["cases"] and sc["parameters"]
        for ch in sc["checks"]:
            assert ch["tolerance"] > 0 and ch["kind"] in ("rel", "abs") and ch["unit"] is not None
            assert ch["reason"] and ch["theory_ref"], (sc["slug"], ch["name"])
            assert ch["theory_ref"] == theory_ref(ch["theory"]) and ch["theory_link"] == theory_link(ch["theory_ref"])
        for case in sc["cases"]:
            assert case["name"] and set(case["checks"]) <= names
            for bound in case["ranges"].values():
                assert bound["text"]
            assert not case["ranges"] or case["regime"]
        for p in sc["parameters"]:
            assert {"name", "unit", "doc", "default", "range", "valid"} <= set(p) and p["range"]
        for d in sc["domains"]:
            assert d["name"] and d["text"] and d["theory"] and d["theory_ref"] == theory_ref(d["theory"])


def test_list_json_writes_a_file_and_refuses_a_directory(tmp_path, capsys):
    path = tmp_path / "catalogue.json"
    assert cli.main(["list", "--json", str(path), "heavy-top"]) == 0
    doc = json.loads(path.read_text())
    assert [s["slug"] for s in doc["scenarios"]] == ["heavy-top"]
    assert capsys.readouterr().out == ""
    assert cli.main(["list", "--json", str(tmp_path)]) == 2
    assert "--json" in capsys.readouterr().err


def test_run_brief_prints_only_what_did_not_pass_and_the_summary(capsys):
    assert cli.main(["run", "--quiet", "--brief", "heavy-top:nutation", "--profile", "mujoco-default"]) == 1
    out = capsys.readouterr().out.strip().splitlines()
    rows = [line for line in out if line.startswith("heavy-top:")]
    assert rows and not any("PASS" in line for line in rows) and all("FAIL" in line for line in rows)
    assert "passed," in out[-1] and "failed" in out[-1]
    assert cli.main(["run", "--quiet", "--brief", "heavy-top:nutation"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and " 0 failed" in out[0]


def test_python_dash_m_runs_the_same_cli():
    done = subprocess.run([sys.executable, "-m", "rigidbench", "list"], capture_output=True, text=True, check=False)
    assert done.returncode == 0 and "free-asymmetric-top" in done.stdout


def test_listing_the_scenarios_does_not_import_scipy():
    """Start-up (issue 14): scipy (~0.3 s to import) is imported on first use (`rigidbench.lazy`), so `rigidbench
    list`, `--help` and registering the envs never pay for it."""
    code = (
        "import sys\n"
        "from rigidbench import registry\n"
        "registry.scenarios(); registry.register_envs()\n"
        "print(sorted(m for m in sys.modules if m == 'scipy' or m.startswith('scipy.')))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "[]", proc.stdout


def test_headless_gl_is_one_that_loads_or_none(monkeypatch):
    """MUJOCO_GL=egl on a machine without libEGL made `import mujoco` itself fail (seen on a GPU machine with no EGL
    libraries): the backend is chosen only if its library loads, else MuJoCo keeps its default."""
    import ctypes

    import rigidbench

    loads = set()

    def cdll(name, *args, **kwargs):
        if not any(name.startswith(lib) for lib in loads):
            raise OSError(f"{name}: cannot open shared object file")

    monkeypatch.setattr(ctypes, "CDLL", cdll)
    assert rigidbench._headless_gl() is None
    loads.add("libOSMesa")
    assert rigidbench._headless_gl() == "osmesa"
    loads.add("libEGL")
    assert rigidbench._headless_gl() == "egl"
