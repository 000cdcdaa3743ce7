"""Fidelity sweeps: the order-fitting rule on synthetic data of known order, then a small real sweep."""

import json

import mujoco
import numpy as np
import pytest

from rigidbench import cli, registry, sweep
from rigidbench.contact import elastic_contact
from rigidbench.envs.heavy_top import HeavyTop
from rigidbench.params import Numeric, Param, positive
from rigidbench.scenario import _model_xml

H = 1e-4 * 2.0 ** np.arange(10)


@pytest.mark.parametrize("order", [1.0, 2.0, 4.0, 5.0])
def test_fit_recovers_the_order_of_a_clean_power_law(order):
    errors = 3e-2 * (H / H[-1]) ** order
    observed, used, reason = sweep.observed_order(H, errors)
    assert observed == pytest.approx(order, abs=1e-9)
    assert reason == "" and len(used) >= 3


def test_fit_drops_round_off_points_and_saturated_points():
    """A 4th-order law sinking into round-off at small steps and saturating at large ones: both ends dropped."""
    clean = 0.1 * (H / 2.56e-2) ** 4  # 2.3e-11 at H[0], 1.6 at H[-1]
    floors = np.full(len(H), 1e-10)
    errors = np.where(clean < 1e-10, 0.5e-10 * (1 + 0.5 * np.sin(np.arange(len(H)))), clean)  # round-off noise
    errors = np.where(clean > 0.1, 0.5, errors)  # saturated (the method has left any asymptotic regime)
    observed, used, _ = sweep.observed_order(H, errors, floors=floors)
    assert observed == pytest.approx(4.0, abs=1e-9)
    assert min(used) > H[0] and max(used) < H[-1]
    assert all(clean[np.isin(H, used)] > 1e-10) and all(clean[np.isin(H, used)] <= 0.1)


def test_fit_uses_only_the_straight_range_before_the_asymptotic_regime_breaks():
    """Second order at small steps, then a kink to a flatter pre-asymptotic curve: the fit keeps the straight part."""
    errors = np.where(H <= 1.6e-3, 1e-3 * (H / 1.6e-3) ** 2, 1e-3 * (H / 1.6e-3) ** 0.3)
    observed, used, _ = sweep.observed_order(H, errors)
    assert observed == pytest.approx(2.0, abs=1e-9)
    assert max(used) == pytest.approx(1.6e-3)


def test_a_plateau_has_no_order():
    observed, used, reason = sweep.observed_order(H, np.full(len(H), 3e-9))
    assert observed is None and "plateau" in reason


def test_two_points_give_no_order_but_say_their_slope():
    errors = [np.nan] * 8 + [1e-4, 2e-4]
    observed, used, reason = sweep.observed_order(H, errors)
    assert observed is None and len(used) == 2 and "slope 1.00" in reason


def test_everything_at_round_off_or_diverged_is_said_so():
    assert sweep.observed_order(H, np.zeros(len(H)))[2] == "at round-off"
    assert "diverged" in sweep.observed_order(H, np.full(len(H), np.nan))[2]


def test_bad_fit_input_is_refused():
    with pytest.raises(ValueError, match="positive"):
        sweep.observed_order([0.0, 1.0, 2.0], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="one length"):
        sweep.observed_order([1.0, 2.0], [1.0])


def test_default_ladder_goes_up_from_the_reference_step_and_down_only_for_short_runs():
    assert sweep.ladder(1e-4)[0] == 1e-4 and sweep.ladder(1e-4)[-1] == pytest.approx(1e-4 * 2**sweep.LADDER_TOP)
    short = sweep.ladder(1e-4, duration=0.4)  # 4e3 steps at dt_ref: room for finer steps
    long = sweep.ladder(1e-4, duration=40.0)  # 4e5 steps: none
    assert short[0] == pytest.approx(1e-4 * 2.0**sweep.LADDER_BOTTOM) and long[0] == 1e-4


def test_small_real_sweep_rk4_fourth_order_euler_first_order():
    """heavy-top:nutation (0.43 s): RK4 above round-off and Euler below saturation show their nominal orders."""
    points = sweep.plan(["heavy-top:nutation"], integrators=["RK4"], timesteps=[4e-4, 8e-4, 1.6e-3, 3.2e-3])
    points += sweep.plan(["heavy-top:nutation"], integrators=["Euler"], timesteps=[1.25e-5, 2.5e-5, 5e-5, 1e-4])
    result = sweep.execute(points, workers=1)
    orders = {(o.integrator, o.check): o for o in result.orders}
    assert orders[("RK4", "nutation-period")].observed == pytest.approx(4.0, abs=0.3)
    assert orders[("RK4", "mean-precession")].observed == pytest.approx(4.0, abs=0.3)
    assert orders[("Euler", "p-phi-drift")].observed == pytest.approx(1.0, abs=0.3)
    assert orders[("Euler", "nutation-period")].observed == pytest.approx(1.0, abs=0.3)
    for row in result.rows:  # every point records what was simulated
        s = row["settings"]
        assert s["integrator"] == row["point"]["integrator"] and s["timestep"] == row["point"]["timestep"]
        assert s["mujoco"] and "cone" in s


def test_worker_processes_give_the_same_rows_in_the_same_order():
    points = sweep.plan(["heavy-top:nutation"], integrators=["RK4", "Euler"], timesteps=[8e-4, 1.6e-3])
    serial = sweep.execute(points, workers=1)
    parallel = sweep.execute(points, workers=2)
    key = [(r["point"]["integrator"], r["point"]["timestep"], r["check"], r["error"]) for r in serial.rows]
    assert key == [(r["point"]["integrator"], r["point"]["timestep"], r["check"], r["error"]) for r in parallel.rows]


def test_any_numeric_parameter_can_be_swept():
    points = sweep.plan(
        ["heavy-top:nutation"], integrators=["RK4"], timesteps=[8e-4, 1.6e-3, 3.2e-3], params={"spin": [120, 150]}
    )
    assert len(points) == 6 and {p.param for p in points} == {(("spin", 120.0),), (("spin", 150.0),)}
    result = sweep.execute(points, workers=1)
    assert {r["params"]["spin"] for r in result.rows} == {120.0, 150.0}
    assert {o.param for o in result.orders} == {(("spin", 120.0),), (("spin", 150.0),)}


def test_cli_sweep_prints_orders_and_writes_json(tmp_path, capsys):
    path = tmp_path / "s.json"
    args = ["sweep", "heavy-top:nutation", "--integrators", "RK4", "--timesteps", "4e-4", "8e-4", "1.6e-3"]
    assert cli.main([*args, "--workers", "1", "--quiet", "--errors", "--json", str(path)]) == 0
    out = capsys.readouterr().out
    assert "RK4 (nominal 4)" in out and "nutation-period" in out and "mujoco" in out
    doc = json.loads(path.read_text())
    assert doc["kind"] == "sweep" and doc["mujoco"] and doc["orders"] and "straight" in doc["fit_rule"]


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["no-such-scenario"], "unknown scenario"),
        (["heavy-top", "--integrators", "leapfrog"], "integrator 'leapfrog'"),
        (["heavy-top", "--param", "bogus=1,2"], "unknown parameter 'bogus'"),
        (["heavy-top", "--param", "spin=a,b"], "comma-separated numbers"),
        (["heavy-top", "--param", "spin=1e9"], "'spin'"),
        (["heavy-top", "--stiffness", "1e5"], "unknown parameter 'stiffness'"),
        (["heavy-top", "--timesteps", "2000"], "timestep"),  # above MAX_TIMESTEP (1000 s)
    ],
)
def test_bad_sweep_input_exits_2_naming_the_problem(args, named, capsys):
    assert cli.main(["sweep", "--quiet", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and named in err[0]


class _StiffTop(HeavyTop):
    """The heavy top with a made-up contact `stiffness` (1/s^2) that refuses timesteps too coarse for it, as the
    contact scenarios do (`rigidbench.contact.elastic_contact`): a stand-in until those scenarios are merged."""

    slug = "stiff-top"
    params = (*HeavyTop.params, Param("stiffness", "1/s^2", "contact stiffness", positive(1e12), Numeric("stiffness")))

    def spec(self):
        spec = mujoco.MjSpec.from_string(_model_xml("heavy_top"))
        numeric = spec.add_numeric()
        numeric.name, numeric.data = "stiffness", [1e6]
        return spec

    def check_model(self, model):
        elastic_contact(timestep=model.opt.timestep, stiffness=float(model.numeric("stiffness").data[0]))


@pytest.fixture
def stiff_top(monkeypatch):
    fake, original = _StiffTop(), registry.get
    monkeypatch.setattr(registry, "get", lambda slug: fake if slug == fake.slug else original(slug))
    return fake


def test_a_stiffness_parameter_is_swept_by_default_and_too_coarse_steps_are_refused(stiff_top):
    """k = 1e5, 1e6, 1e7 1/s^2: the contact lasts pi/sqrt(k) ~ 1 ms at 1e7, fewer than 4 steps of 4e-4 s."""
    points = sweep.plan(["stiff-top:nutation"], integrators=["RK4"], timesteps=[1e-4, 2e-4, 4e-4])
    assert sorted({p.param for p in points}) == [(("stiffness", k),) for k in (1e5, 1e6, 1e7)]
    result = sweep.execute(points, workers=1)
    refused = [r for r in result.rows if r["status"] == sweep.REFUSED]
    assert {(r["point"]["param"]["stiffness"], r["point"]["timestep"]) for r in refused} == {(1e7, 4e-4)}
    assert "stiffness" in refused[0]["reason"] and refused[0]["settings"]["mujoco"]
    scored = [r for r in result.rows if r["status"] != sweep.REFUSED]
    assert {r["params"]["stiffness"] for r in scored} == {1e5, 1e6, 1e7}
    assert "ref" in sweep.error_table(result)
    explicit = sweep.plan(["stiff-top:nutation"], integrators=["RK4"], timesteps=[1e-4], params={"stiffness": [2e5]})
    assert [p.param for p in explicit] == [(("stiffness", 2e5),)]
