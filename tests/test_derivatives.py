"""Derivatives under the same theory (issue 37): the checks pass under the reference and each Euler-family integrator,
each catches a 1e-6 error of a force constant or a mass, and ``rigidbench derivatives`` writes rows, JSON, JUnit and
exit statuses as ``run`` does."""

import json
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest
from scipy.linalg import expm

from rigidbench import cli, derivatives, power, registry
from rigidbench.analytic import linearised as lin
from rigidbench.analytic.pendulum import pendulum_period
from rigidbench.results import PASS, rows_of
from rigidbench.runner import settings_for

TARGETS = (
    "pendulum:one-radian",
    "coupled-pendulums:beats",
    "pendulum-chain:end-released",
    "double-pendulum:unequal",
    "free-symmetric-top:prolate",
    "free-symmetric-top:oblate",
)
INTEGRATORS = ("RK4", "Euler", "implicit", "implicitfast")


def _rows(target, integrator, perturb=None):
    scenario, (case,) = registry.parse_target(target)
    return rows_of(derivatives.run_case(scenario, case, None, settings_for("reference", integrator), perturb=perturb))


# ---- the theory --------------------------------------------------------------------------------------------------


def test_rk4_map_is_the_flow_to_fifth_order_and_euler_map_keeps_unit_eigenvalues():
    T, V, h = np.diag([1.0, 2.0]), np.array([[10.0, -1.0], [-1.0, 12.0]]), 2e-3
    flow = expm(lin.first_order(np.linalg.solve(T, V)) * h)
    rk4 = lin.transition_map("RK4", T, V, h)
    assert np.abs(rk4 - flow).max() < (np.sqrt(12 / 1) * h) ** 5 / 120 * 10
    lam = np.linalg.eigvals(lin.transition_map("Euler", T, V, h))
    np.testing.assert_allclose(np.abs(lam), 1.0, atol=1e-13)
    omega = np.sqrt(np.linalg.eigvals(np.linalg.solve(T, V)).real)
    np.testing.assert_allclose(
        np.sort(np.angle(lam[np.angle(lam) > 0])) / h, np.sort(lin.map_frequency("Euler", omega, h)), rtol=1e-12
    )


def test_pendulum_transition_at_equilibrium_is_the_linear_map():
    for integrator in INTEGRATORS:
        np.testing.assert_allclose(
            lin.pendulum_transition(integrator, 9.81, 0.0, 0.0, 2e-3),
            lin.transition_map(integrator, [[1.0]], [[9.81]], 2e-3),
            rtol=1e-14,
            atol=1e-16,
        )


@pytest.mark.parametrize("amplitude", [0.01, 1.0, 2.5])
def test_period_amplitude_slope_is_the_derivative_of_the_elliptic_period(amplitude):
    da = 1e-4
    fd = (pendulum_period(1.0, 9.81, amplitude + da) - pendulum_period(1.0, 9.81, amplitude - da)) / (2 * da)
    assert lin.period_amplitude_slope(1.0, 9.81, amplitude) == pytest.approx(fd, rel=1e-6)


# ---- the checks pass, and catch a wrong derivative ----------------------------------------------------------------


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("target", TARGETS)
def test_every_derivative_check_passes_against_the_integrators_own_map(target, integrator):
    rows = _rows(target, integrator)
    assert rows
    failed = [(r["check"], r["error"], r["tolerance"]) for r in rows if r["status"] != PASS]
    assert not failed
    assert all(r["settings"]["integrator"] == integrator for r in rows)


# Which checks a 1e-6 relative error of the simulated model fails (measured; docs/derivatives.md), per quantity of
# `rigidbench.power`. The theory keeps the unperturbed model.
CATCHES = [
    ("pendulum:one-radian", "g", {"transition-map", "map-omega", "inverse-omega", "period-amplitude-slope"}),
    ("pendulum:one-radian", "mass:pendulum", {"inverse-mass"}),
    ("coupled-pendulums:beats", "spring-k", {"transition-map", "map-omega-fastest", "inverse-omega-fastest"}),
    ("coupled-pendulums:beats", "g", {"transition-map", "map-omega-slowest", "inverse-omega-slowest"}),
    ("coupled-pendulums:beats", "mass:pendulum1", {"map-mode-shapes", "inverse-mass"}),
    ("pendulum-chain:end-released", "spring-k", {"transition-map", "map-omega-fastest", "inverse-omega-fastest"}),
    ("pendulum-chain:end-released", "mass:pendulum1", {"transition-map", "inverse-mass"}),
    ("double-pendulum:unequal", "mass:pendulum2", {"transition-map", "map-omega-fastest", "map-mode-shapes"}),
    ("double-pendulum:unequal", "g", {"transition-map", "map-omega-slowest", "inverse-omega-fastest"}),
]


@pytest.mark.parametrize("integrator", ["RK4", "Euler"])
@pytest.mark.parametrize(("target", "quantity", "catchers"), CATCHES)
def test_a_one_in_a_million_error_of_the_simulated_model_fails_the_checks_that_see_it(
    target, quantity, catchers, integrator
):
    if quantity == "g" and target.startswith("pendulum:") and integrator != "RK4":
        catchers = catchers - {"period-amplitude-slope"}  # the Euler family's period error (1e-6 of T) hides it
    if quantity == "g" and integrator == "RK4":
        catchers = catchers | {"transition-flow"}
    rows = _rows(target, integrator, perturb=power.Perturbation(quantity, 1e-6))
    failed = {r["check"] for r in rows if r["status"] != PASS}
    assert catchers <= failed, f"{quantity}: failed {sorted(failed)}"


def _axial_moment(model):
    """I3 of the free top scaled by 1 + 1e-6 (power's ``inertia:top`` scales all three, which Euler's equations
    cannot see: they depend on I3 / I1 only)."""
    model.body_inertia[model.jnt_bodyid[0], 2] *= 1 + 1e-6
    mujoco.mj_setConst(model, mujoco.MjData(model))  # MuJoCo 4 caches the joint-space inertia (dof_M0)


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("case", ["prolate", "oblate"])
def test_a_one_in_a_million_error_of_the_tops_axial_moment_fails_its_rate_map(case, integrator):
    rows = _rows(f"free-symmetric-top:{case}", integrator, perturb=_axial_moment)
    assert {r["check"] for r in rows if r["status"] != PASS} == {"rotation-map", "map-body-rate"}


def test_implicitfast_keeps_the_free_bodys_gyroscopic_derivative():
    # measured: implicitfast's (and discrete's) rate map is implicit's, 3e-4 of the step's change from Euler's
    scenario = registry.get("free-symmetric-top")
    prep = scenario.prepare("prolate", None, settings_for("reference", "implicitfast"))
    data = mujoco.MjData(prep.model)
    data.qpos[:], data.qvel[:] = prep.data.qpos, prep.data.qvel
    mujoco.mj_forward(prep.model, data)
    A = derivatives.transition(prep.model, data, derivatives.EPS_RATES)[9:12, 9:12]
    inertia, omega, h = prep.model.body_inertia[1], prep.data.qvel[3:6], prep.model.opt.timestep
    implicit, euler = (lin.rotation_map(i, inertia, omega, h) for i in ("implicit", "Euler"))
    change = np.linalg.norm(implicit - np.eye(3))
    assert np.linalg.norm(A - implicit) / change < 1e-7 < 1e-4 < np.linalg.norm(A - euler) / change


# ---- the command ---------------------------------------------------------------------------------------------------


def test_derivatives_writes_json_and_junit_like_run_and_exits_0(tmp_path, capsys):
    js, xml = tmp_path / "d.json", tmp_path / "d.xml"
    status = cli.main(["derivatives", "--quiet", "coupled-pendulums:beats", "--json", str(js), "--junit", str(xml)])
    assert status == 0
    doc = json.loads(js.read_text())
    assert doc["complete"] and doc["mujoco"]
    rows = doc["results"]
    assert {r["check"] for r in rows} >= {"transition-map", "map-omega-fastest", "inverse-mass"}
    for key in ("measured", "expected", "error", "tolerance", "tolerance_reason", "theory_ref", "passed", "settings"):
        assert key in rows[0], key
    assert rows[0]["settings"]["integrator"] == "RK4" and rows[0]["theory_ref"] == "O7"
    suite = ET.parse(xml).getroot().find("testsuite")
    assert suite.get("name") == "coupled-pendulums" and int(suite.get("tests")) == len(rows)
    assert "transition-map" in capsys.readouterr().out


def test_derivatives_exits_1_on_a_failed_check(tmp_path):
    # MuJoCo's `discrete` integrator does not solve the chain's velocity update in T + h^2 V_s (docs/derivatives.md)
    path = tmp_path / "d.xml"
    status = cli.main(
        ["derivatives", "--quiet", "pendulum-chain:strong-coupling", "--integrator", "discrete", "--junit", str(path)]
    )
    assert status == 1
    suite = ET.parse(path).getroot().find("testsuite")
    assert int(suite.get("failures")) > 0


@pytest.mark.parametrize("target", ["heavy-top", "no-such-scenario", "pendulum:no-such-case"])
def test_derivatives_refuses_what_it_cannot_differentiate_with_exit_2(target, capsys):
    assert cli.main(["derivatives", "--quiet", target]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rigidbench: error:") and len(err.strip().splitlines()) == 1


def test_a_census_of_the_derivative_checks_is_clean_and_reproducible(tmp_path, capsys):
    path = tmp_path / "c.json"
    assert cli.main(["derivatives", "--quiet", "--census", "3", "--seed", "1", "--json", str(path)]) == 0
    doc = json.loads(path.read_text())
    assert doc["kind"] == "derivatives-census" and doc["n"] == 3
    counts = doc["scenarios"]
    assert set(counts) == set(derivatives.SCENARIOS)
    assert all(t["failed"] == 0 and t["crashed"] == 0 and t["passed"] >= 2 for t in counts.values())
    again = derivatives.census(["pendulum"], n=3, seed=1, settings=None)
    assert [d.params for d in again] == [d["params"] for d in doc["draws"] if d["scenario"] == "pendulum"]


def test_an_interrupted_derivatives_run_writes_what_finished_and_says_it_is_incomplete(tmp_path, monkeypatch):
    """Ctrl-C between cases: exit 128 + SIGINT, the JSON keeps the finished rows and names the cases not run."""
    import json
    import signal

    from rigidbench.interrupt import Interrupted

    real, calls = derivatives.run_case, []

    def second_is_interrupted(*args, **kwargs):
        calls.append(args[1])
        if len(calls) == 2:
            raise Interrupted(signal.SIGINT)
        return real(*args, **kwargs)

    monkeypatch.setattr(derivatives, "run_case", second_is_interrupted)
    path = tmp_path / "d.json"
    assert cli.main(["derivatives", "--quiet", "pendulum", "--json", str(path)]) == 128 + signal.SIGINT
    doc = json.loads(path.read_text())
    assert doc["complete"] is False and doc["interrupted_by"] == "SIGINT"
    assert {r["case"] for r in doc["results"]} == {calls[0]}
    assert f"pendulum:{calls[1]}" in doc["not_run"]
