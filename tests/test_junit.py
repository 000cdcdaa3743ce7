"""JUnit XML from `rigidbench run`: one testcase per check, failures and divergences marked, versions stamped."""

import json
import xml.etree.ElementTree as ET

from rigidbench import cli, theory


def test_junit_has_one_testcase_per_check_grouped_by_scenario(tmp_path):
    xml_path, json_path = tmp_path / "r.xml", tmp_path / "r.json"
    args = ["run", "--quiet", "heavy-top:nutation", "free-symmetric-top:prolate", "--profile", "mujoco-default"]
    cli.main([*args, "--junit", str(xml_path), "--json", str(json_path)])
    rows = json.loads(json_path.read_text())["results"]
    root = ET.parse(xml_path).getroot()
    assert root.tag == "testsuites"
    suites = root.findall("testsuite")
    assert [s.get("name") for s in suites] == list(dict.fromkeys(r["scenario"] for r in rows))
    cases = [c for s in suites for c in s.findall("testcase")]
    assert len(cases) == len(rows)
    for case, row in zip(cases, rows, strict=True):
        assert (
            case.get("classname") == f"rigidbench.{row['scenario']}.{row['case']}" and case.get("name") == row["check"]
        )
        failed = case.find("failure") is not None
        errored = case.find("error") is not None
        assert failed == (row["status"] == "fail") and errored == (row["status"] == "diverged")
        if failed:
            assert "expected" in case.find("failure").get("message")
        # the check's theory ID (the JSON row's theory_ref) as a per-case property
        props = {p.get("name"): p.get("value") for p in case.iterfind("properties/property")}
        assert row["theory_ref"] == theory.theory_ref(row["theory"]) != ""
        assert props == {"theory_ref": row["theory_ref"]}
    for suite in suites:
        group = [r for r in rows if r["scenario"] == suite.get("name")]
        assert int(suite.get("tests")) == len(group)
        assert int(suite.get("failures")) == sum(r["status"] == "fail" for r in group)
        assert int(suite.get("errors")) == sum(r["status"] == "diverged" for r in group)
        props = {p.get("name"): p.get("value") for p in suite.find("properties")}
        assert props["mujoco"] and json.loads(props["settings"])["integrator"] == "Euler"
