"""rigidbench's speed, every figure next to its peer, measured in one process on one machine in one run (issue 8).

    python benchmarks/run.py                 # the full table (a few minutes on 2 cores), JSON in results/bench.json
    python benchmarks/run.py --quick         # tiny budget, seconds: what tests/test_benchmarks.py runs

Figures and their peers:

1. ``env.step`` throughput (frame_skip 1) of every registered rigidbench env vs gymnasium's
   ``InvertedPendulum-v5``, both made with ``gym.make`` (the wrappers a user gets); beside each, the physics
   floor: raw ``mj_step`` on the same model and state, in C, so ``step - floor`` is the per-step Python cost.
2. The validation runner: steps/s inside ``Scenario.run`` (resolve, compile, predict, simulate, measure: the
   whole case) vs a raw ``mujoco.rollout`` of the same model, settings, initial state, controls and steps.
3. Cross-section throughput: hard-sphere collisions per second with 1 and 2 rollout threads.
4. Wall time of ``rigidbench run`` (default targets; the thorough profile if there is one) vs its targets,
   with the in-process physics floor (raw rollouts of the same cases) beside it; start-up vs ``import mujoco``.
5. Headless render frames per second at 480x480 vs a bare ``mujoco.Renderer`` and ``InvertedPendulum-v5``.

The machine is shared and noisy: every comparison interleaves the contenders in short blocks, repeats, and
reports the median of the per-repeat ratios (each ratio taken between blocks run back to back), so load that
comes and goes hits both sides. The load average is recorded with the results.
"""

# ruff: noqa: E402 (MUJOCO_GL must be set before mujoco is first imported)
from __future__ import annotations

import os

# Headless rendering: the same default as `import rigidbench`, which comes after gymnasium and mujoco here.
if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
    os.environ["MUJOCO_GL"] = "egl"

import argparse
import inspect
import json
import pathlib
import platform
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
from mujoco import rollout

import rigidbench
from rigidbench import registry
from rigidbench.scenario import Scenario
from rigidbench.settings import PROFILES
from rigidbench.simulate import STATE, final_states, get_state

ROOT = pathlib.Path(__file__).resolve().parents[1]
PEER_ENV = "InvertedPendulum-v5"
# The env the >= 1.5x target is scored on: the model as small as the peer's (one hinge against a slider and a
# hinge) with the peer's integrator (RK4) and frame_skip 1. The other envs are listed with their own physics.
FAIR_ENV = "rigidbench/SimplePendulum-v0"


# ---- timing --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Lap:
    """Elapsed wall-clock and CPU seconds (CPU time of this process: less sensitive to a loaded machine)."""

    wall: float
    cpu: float

    def __add__(self, other: Lap) -> Lap:
        return Lap(self.wall + other.wall, self.cpu + other.cpu)

    def __sub__(self, other: Lap) -> Lap:
        return Lap(self.wall - other.wall, self.cpu - other.cpu)


ZERO = Lap(0.0, 0.0)


def now() -> Lap:
    return Lap(time.perf_counter(), time.process_time())


def interleaved(blocks: dict[str, Callable[[], Lap]], repeats: int) -> dict[str, list[Lap]]:
    """Run each block once per repeat, contenders back to back; each block returns its own elapsed time."""
    out: dict[str, list[Lap]] = {name: [] for name in blocks}
    for _ in range(repeats):
        for name, block in blocks.items():
            out[name].append(block())
    return out


def median(laps: list[Lap], kind: str = "wall") -> float:
    return statistics.median(getattr(lap, kind) for lap in laps)


def paired_ratio(numerator: list[Lap], denominator: list[Lap], kind: str = "wall") -> float:
    """Median over repeats of numerator[i] / denominator[i] (blocks run back to back in repeat i)."""
    return statistics.median(getattr(a, kind) / getattr(b, kind) for a, b in zip(numerator, denominator, strict=True))


def row(
    section: str,
    figure: str,
    value: float,
    unit: str,
    peer: str = "",
    peer_value: float | None = None,
    ratio: float | None = None,
    target: str = "",
    met: bool | None = None,
    ratio_cpu: float | None = None,
    **extra: Any,
) -> dict[str, Any]:
    return {
        "section": section,
        "figure": figure,
        "value": value,
        "unit": unit,
        "peer": peer,
        "peer_value": peer_value,
        "ratio": ratio,
        "ratio_cpu": ratio_cpu,
        "target": target,
        "met": met,
        **extra,
    }


# ---- 1. env.step ---------------------------------------------------------------------------------------------


def _step_block(env: gym.Env, n: int) -> Callable[[], Lap]:
    """n zero-action steps; resets (when an episode ends) are timed and taken out."""
    action = np.zeros(env.action_space.shape)
    step, reset = env.step, env.reset

    def block() -> Lap:
        resets = ZERO
        t0 = now()
        for _ in range(n):
            _, _, terminated, truncated, _ = step(action)
            if terminated or truncated:
                r0 = now()
                reset()
                resets += now() - r0
        return now() - t0 - resets

    return block


def _physics_block(model: mujoco.MjModel, state0: np.ndarray, n: int, chunk: int = 20) -> Callable[[], Lap]:
    """n raw mj_step calls (in C, `chunk` at a time) from the env's reset state: the physics floor of a step.

    Restarting every `chunk` steps keeps each model in the regime its env steps in (the inverted pendulum
    never falls onto its joint limits).
    """
    data = mujoco.MjData(model)

    def block() -> Lap:
        t0 = now()
        for _ in range(n // chunk):
            mujoco.mj_setState(model, data, state0, STATE)
            mujoco.mj_step(model, data, nstep=chunk)
        return now() - t0

    return block


def bench_env_step(quick: bool) -> list[dict[str, Any]]:
    n, repeats = (200, 3) if quick else (2000, 21)
    env_ids = [PEER_ENV]
    for env_id in sorted(registry.env_classes()):
        # One-shot task envs (a step is a whole shot, one step an episode) are not per-step control.
        env = gym.make(env_id, frame_skip=1)
        env.reset(seed=0)
        _, _, terminated, truncated, _ = env.step(np.zeros(env.action_space.shape))
        if not (terminated or truncated):
            env_ids.append(env_id)
    blocks, physics, about = {}, {}, {}
    for env_id in env_ids:
        env = gym.make(env_id, frame_skip=1)
        env.reset(seed=0)
        inner = env.unwrapped
        model = inner.model
        about[env_id] = (
            f"{mujoco.mjtIntegrator(model.opt.integrator).name.removeprefix('mjINT_')} "
            f"dt={model.opt.timestep:g} nq={model.nq} nv={model.nv}"
        )
        blocks[env_id] = _step_block(env, n)
        physics[env_id] = _physics_block(model, get_state(model, inner.data), n)
        blocks[env_id]()  # warm-up: the env checker's first-call checks, caches
    times = interleaved({**blocks, **{f"physics {k}": v for k, v in physics.items()}}, repeats)
    peer = times[PEER_ENV]
    peer_us = median(peer) / n * 1e6
    rows = []
    for env_id in env_ids:
        step_us = median(times[env_id]) / n * 1e6
        floor_us = median(times[f"physics {env_id}"]) / n * 1e6
        extra = {
            "step_us": step_us,
            "physics_us": floor_us,
            "overhead_us": step_us - floor_us,
            "step_us_cpu": median(times[env_id], "cpu") / n * 1e6,
            "physics_us_cpu": median(times[f"physics {env_id}"], "cpu") / n * 1e6,
            # The best ratio any Python layer could reach: the peer's whole step over this env's bare physics.
            "ceiling": peer_us / floor_us,
            "model": about[env_id],
        }
        if env_id == PEER_ENV:
            rows.append(row("env.step", f"{env_id} env.step (peer)", n / median(peer), "steps/s", **extra))
            continue
        ratio = paired_ratio(peer, times[env_id])
        scored = env_id == FAIR_ENV
        rows.append(
            row(
                "env.step",
                f"{env_id} env.step",
                n / median(times[env_id]),
                "steps/s",
                PEER_ENV,
                n / median(peer),
                ratio,
                ">= 1.5x" if scored else "",
                ratio >= 1.5 if scored else None,
                ratio_cpu=paired_ratio(peer, times[env_id], "cpu"),
                **extra,
            )
        )
    if FAIR_ENV in env_ids:
        ours, theirs = next(r for r in rows if r["figure"].startswith(FAIR_ENV)), rows[0]
        rows.append(
            row(
                "env.step",
                f"  {FAIR_ENV}: per-step Python (step - physics floor)",
                ours["overhead_us"],
                "us",
                f"{PEER_ENV} per-step Python",
                theirs["overhead_us"],
                theirs["overhead_us"] / ours["overhead_us"],
            )
        )
        rows.append(
            row(
                "env.step",
                f"  {FAIR_ENV}: ceiling ({PEER_ENV} step / our physics floor)",
                ours["ceiling"],
                "x",
                target=">= 1.5x",
            )
        )
    return rows


# ---- 2. validation runner vs raw rollout ---------------------------------------------------------------------


def _jobs(quick: bool) -> list[tuple[Any, str]]:
    """Every case of every scenario that runs as one rollout (the peer is that one rollout); scenarios that
    override `Scenario.simulate` run batches or extra runs (the cross-section: section 3)."""
    if quick:
        scenario = registry.get("heavy-top")
        return [(scenario, "nutation")]
    single = [s for s in registry.scenarios().values() if type(s).simulate is Scenario.simulate]
    return [(s, c.name) for s in single for c in s.cases]


def _raw_rollout(scenario: Any, case: str, nstep: int) -> Lap:
    """One rollout of `nstep` steps of the same compiled model, initial state and controls."""
    model = scenario.build(scenario.resolve(scenario.case(case)))
    data = scenario.start(model)
    state0 = get_state(model, data)
    control = scenario.control(model, model.opt.timestep, nstep)
    kwargs = {} if control is None else {"control": control[None]}
    t0 = now()
    rollout.rollout(model, data, state0[None], nstep=nstep, **kwargs)
    return now() - t0


def bench_runner(quick: bool) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    repeats = 1 if quick else 2
    per_case: dict[str, dict[str, list[Lap]]] = {}
    nsteps: dict[str, int] = {}
    for _ in range(repeats):
        for scenario, case in _jobs(quick):
            name = f"{scenario.slug}:{case}"
            t0 = now()
            run = scenario.run(case)
            t_run = now() - t0
            nsteps[name] = run.nstep
            t_raw = _raw_rollout(scenario, case, run.nstep)
            times = per_case.setdefault(name, {"run": [], "raw": []})
            times["run"].append(t_run)
            times["raw"].append(t_raw)
    total_steps = sum(nsteps.values())
    run_totals = [sum((t["run"][i] for t in per_case.values()), ZERO) for i in range(repeats)]
    raw_totals = [sum((t["raw"][i] for t in per_case.values()), ZERO) for i in range(repeats)]
    ratio = paired_ratio(raw_totals, run_totals)
    rows = [
        row(
            "runner",
            f"Scenario.run, {len(per_case)} single-rollout case(s), steps/s",
            total_steps / median(run_totals),
            "steps/s",
            "raw mujoco.rollout, same models",
            total_steps / median(raw_totals),
            ratio,
            ">= 0.80",
            ratio >= 0.8,
            ratio_cpu=paired_ratio(raw_totals, run_totals, "cpu"),
        )
    ]
    worst = min(per_case, key=lambda k: paired_ratio(per_case[k]["raw"], per_case[k]["run"], "cpu"))
    w = per_case[worst]
    rows.append(
        row(
            "runner",
            f"  worst case: {worst} ({nsteps[worst]} steps)",
            nsteps[worst] / median(w["run"]),
            "steps/s",
            "raw mujoco.rollout",
            nsteps[worst] / median(w["raw"]),
            paired_ratio(w["raw"], w["run"]),
            ratio_cpu=paired_ratio(w["raw"], w["run"], "cpu"),
        )
    )
    cases = {
        name: {
            "nstep": nsteps[name],
            "run_s": median(t["run"]),
            "raw_s": median(t["raw"]),
            "ratio": paired_ratio(t["raw"], t["run"]),
            "ratio_cpu": paired_ratio(t["raw"], t["run"], "cpu"),
        }
        for name, t in per_case.items()
    }
    totals = {
        "raw_rollout_s": median(raw_totals),
        "raw_rollout_cpu_s": median(raw_totals, "cpu"),
        "scenario_run_s": median(run_totals),
        "scenario_run_cpu_s": median(run_totals, "cpu"),
    }
    return rows, {"cases": cases, **totals}


# ---- 3. cross-section ----------------------------------------------------------------------------------------


def _raw_beam(model: mujoco.MjModel, states0: np.ndarray, nstep: int, nthread: int, chunk: int) -> Lap:
    """The beam as bare `mujoco.rollout` calls: same states, steps, threads and chunks, one thread pool."""
    datas = [mujoco.MjData(model) for _ in range(nthread)]
    out = np.empty((min(chunk, len(states0)), nstep, states0.shape[1]))
    t0 = now()
    with rollout.Rollout(nthread=nthread if nthread > 1 else 0) as pool:
        for lo in range(0, len(states0), chunk):
            part = states0[lo : lo + chunk]
            pool.rollout(model, datas, part, nstep=nstep, state=out[: len(part)])
    return now() - t0


def bench_cross_section(quick: bool) -> list[dict[str, Any]]:
    """Collisions per second of the cross-section case, whole (`Scenario.run`: beam, rollout, histograms)
    against bare rollouts of the same states; 1 and 2 threads."""
    if "cross-section" not in registry.scenarios():
        return [row("cross-section", "collisions/s (cross-section scenario not on this branch)", float("nan"), "1/s")]
    n, repeats = (200, 1) if quick else (10_000, 2)
    scenario = type(registry.get("cross-section"))()  # a private instance: `nthread` is set on it below
    case, overrides = "heavy-projectile", {"n": n}
    model = scenario.build(scenario.resolve(scenario.case(case), overrides))
    data = scenario.start(model)
    states0, _ = scenario.beam(model, data)
    nstep = round(scenario.duration(scenario.predict(model, data)) / model.opt.timestep)
    chunk = inspect.signature(final_states).parameters["chunk"].default

    def whole(nthread: int) -> Callable[[], Lap]:
        def block() -> Lap:
            scenario.nthread = nthread
            t0 = now()
            scenario.run(case, overrides)
            return now() - t0

        return block

    blocks = {}
    for nthread in (1, 2):
        blocks[f"run {nthread}"] = whole(nthread)
        blocks[f"raw {nthread}"] = lambda nthread=nthread: _raw_beam(model, states0, nstep, nthread, chunk)
    times = interleaved(blocks, repeats)
    rate = {k: n / median(v) for k, v in times.items()}
    rows = []
    for nthread in (1, 2):
        seconds_1e5 = 1e5 / rate[f"run {nthread}"]
        rows.append(
            row(
                "cross-section",
                f"cross-section:{case}, n={n}, {nthread} thread(s), collisions/s ({nstep} RK4 steps each)",
                rate[f"run {nthread}"],
                "1/s",
                f"bare mujoco.rollout, same states, {nthread} thread(s)",
                rate[f"raw {nthread}"],
                paired_ratio(times[f"raw {nthread}"], times[f"run {nthread}"]),
                "1e5 in <= 30 s" if nthread == 2 else "",
                seconds_1e5 <= 30 if nthread == 2 else None,
                seconds_1e5=seconds_1e5,
            )
        )
    rows.append(
        row(
            "cross-section",
            "  2 threads vs 1 (Scenario.run)",
            rate["run 2"],
            "1/s",
            "1 thread",
            rate["run 1"],
            paired_ratio(times["run 1"], times["run 2"]),
        )
    )
    # The target itself, timed rather than extrapolated: the whole case with 1e5 collisions on 2 threads.
    big = 200 if quick else 100_000
    scenario.nthread = 2
    t0 = now()
    run = scenario.run(case, {"n": big})
    lap = now() - t0
    passed = sum(o.passed for o in run.outcomes)
    rows.append(
        row(
            "cross-section",
            f"cross-section:{case}, n={big}, 2 threads, Scenario.run wall ({passed}/{len(run.outcomes)} checks pass)",
            lap.wall,
            "s",
            target="1e5 in <= 30 s",
            met=None if quick else lap.wall <= 30,
            cpu=lap.cpu,
        )
    )
    return rows


# ---- 4. wall time of the command line ------------------------------------------------------------------------


def _command(args: list[str]) -> Lap:
    """Wall-clock and CPU (the child's user + system) seconds of a command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return Lap(wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)


def bench_cli(quick: bool, floor: dict[str, Any], thorough: bool) -> list[dict[str, Any]]:
    py = sys.executable
    repeats = 1 if quick else 5
    starts = interleaved(
        {
            "rigidbench --version": lambda: _command([py, "-m", "rigidbench", "--version"]),
            "import mujoco": lambda: _command([py, "-c", "import mujoco"]),
        },
        repeats,
    )
    rows = [
        row(
            "cli",
            "start-up: rigidbench --version",
            median(starts["rigidbench --version"]),
            "s",
            "python -c 'import mujoco'",
            median(starts["import mujoco"]),
            paired_ratio(starts["rigidbench --version"], starts["import mujoco"]),
            ratio_cpu=paired_ratio(starts["rigidbench --version"], starts["import mujoco"], "cpu"),
        )
    ]
    targets = ["heavy-top:nutation"] if quick else []
    lap = _command([py, "-m", "rigidbench", "run", "--quiet", *targets])
    what = "rigidbench run " + (" ".join(targets) if targets else "(default targets)")
    rows.append(
        row(
            "cli",
            f"{what}, wall",
            lap.wall,
            "s",
            "raw rollouts of its single-rollout cases, in-process, in turn",
            floor["raw_rollout_s"],
            floor["raw_rollout_s"] / lap.wall,
            "<= 60 s",
            lap.wall <= 60,
            ratio_cpu=floor["raw_rollout_cpu_s"] / lap.cpu,
            cpu_s=lap.cpu,
        )
    )
    if thorough and "thorough" in PROFILES:
        lap = _command([py, "-m", "rigidbench", "run", "--quiet", "--profile", "thorough"])
        rows.append(
            row("cli", "rigidbench run --profile thorough, wall", lap.wall, "s", target="<= 600 s", met=lap.wall <= 600)
        )
    return rows


# ---- 5. rendering --------------------------------------------------------------------------------------------


def _render_block(render: Callable[[], Any], before: Callable[[], Any], n: int) -> Callable[[], Lap]:
    def block() -> Lap:
        elapsed = ZERO
        for _ in range(n):
            before()
            t0 = now()
            render()
            elapsed += now() - t0
        return elapsed

    return block


def bench_render(quick: bool) -> list[dict[str, Any]]:
    n, repeats = (5, 2) if quick else (60, 7)
    size = {"width": 480, "height": 480}
    env_id = registry.get("heavy-top").env_id
    try:
        return _bench_render(env_id, n, repeats, size)
    except Exception as exc:  # no OpenGL backend (mujoco.FatalError, GLFW/EGL errors)
        return [row("render", f"render 480x480 ({type(exc).__name__}: {exc})", float("nan"), "frames/s")]


def _bench_render(env_id: str, n: int, repeats: int, size: dict[str, int]) -> list[dict[str, Any]]:
    ours = gym.make(env_id, render_mode="rgb_array", **size)
    peer = gym.make(PEER_ENV, render_mode="rgb_array", **size)
    ours.reset(seed=0)
    peer.reset(seed=0)
    inner = ours.unwrapped
    # The peer: a bare mujoco.Renderer on the model as its file compiles (MuJoCo's own render settings).
    scenario = inner.scenario
    bare = mujoco.Renderer(scenario.build(scenario.resolve(scenario.case(None))), 480, 480)
    zero, zero_peer = np.zeros(ours.action_space.shape), np.zeros(peer.action_space.shape)

    def bare_render():
        bare.update_scene(inner.data, camera="side")
        return bare.render()

    def step_peer():
        if peer.step(zero_peer)[2]:
            peer.reset()

    blocks = {
        "ours": _render_block(ours.render, lambda: ours.step(zero), n),
        "bare": _render_block(bare_render, lambda: ours.step(zero), n),
        "peer": _render_block(peer.render, step_peer, n),
    }
    for block in blocks.values():
        block()  # warm-up: GL context, textures
    times = interleaved(blocks, repeats)
    fps = {k: n / median(v) for k, v in times.items()}
    rows = [
        row(
            "render",
            f"{env_id} render 480x480",
            fps["ours"],
            "frames/s",
            "bare mujoco.Renderer, same model file",
            fps["bare"],
            paired_ratio(times["bare"], times["ours"]),
        ),
        row(
            "render",
            f"{env_id} render 480x480",
            fps["ours"],
            "frames/s",
            f"{PEER_ENV} render 480x480",
            fps["peer"],
            paired_ratio(times["peer"], times["ours"]),
        ),
    ]
    bare.close()
    ours.close()
    peer.close()
    return rows


# ---- table, JSON, main ---------------------------------------------------------------------------------------


def _fmt(x: Any) -> str:
    if x is None:
        return ""
    if isinstance(x, bool):
        return "yes" if x else "NO"
    if isinstance(x, float):
        if np.isnan(x):
            return "n/a"
        return f"{x:.3g}" if abs(x) < 1e4 else f"{x:.3e}"
    return str(x)


def table(rows: list[dict[str, Any]]) -> str:
    cols = [("figure", "figure"), ("value", "value"), ("unit", "unit"), ("peer", "peer"), ("peer_value", "peer value")]
    cols += [("ratio", "ratio"), ("ratio_cpu", "cpu ratio"), ("target", "target"), ("met", "met")]
    cells = [[_fmt(r[key]) for key, _ in cols] for r in rows]
    widths = [max(len(title), *(len(c[i]) for c in cells)) for i, (_, title) in enumerate(cols)]
    lines = ["  ".join(title.ljust(w) for (_, title), w in zip(cols, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.ljust(w) for c, w in zip(cell, widths, strict=True)).rstrip() for cell in cells]
    return "\n".join(lines)


def env_step_detail(rows: list[dict[str, Any]]) -> str:
    lines = [
        "env.step, us per step (medians): step = physics floor (raw mj_step, same model, in C) + per-step Python;",
        f"ceiling = {PEER_ENV}'s step / this env's physics floor, the best ratio any Python layer could reach",
    ]
    for r in rows:
        if "physics_us" in r:
            name = r["figure"].removesuffix(" env.step").removesuffix(" (peer)")
            lines.append(
                f"  {name:<34} {r['step_us']:6.2f} = {r['physics_us']:5.2f} + {r['overhead_us']:5.2f}   "
                f"ceiling {r['ceiling']:4.2f}x   [{r['model']}]"
            )
    return "\n".join(lines)


def _finite(x: Any) -> Any:
    """NaN (a figure that could not be taken) as JSON null."""
    if isinstance(x, float) and np.isnan(x):
        return None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_finite(v) for v in x]
    return x


def machine() -> dict[str, Any]:
    import gymnasium

    return {
        "load_average": os.getloadavg(),
        "cpus": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
        "numpy": np.__version__,
        "gymnasium": gymnasium.__version__,
        "rigidbench": rigidbench.__version__,
        "time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }


SECTIONS = ("env-step", "runner", "cross-section", "cli", "render")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="tiny budget (seconds): checks the script, not speed")
    parser.add_argument("--json", default=str(ROOT / "results" / "bench.json"), metavar="PATH", help="JSON output")
    parser.add_argument("--skip", action="append", default=[], choices=SECTIONS, help="leave out a section")
    parser.add_argument("--no-thorough", action="store_true", help="do not time the thorough profile")
    args = parser.parse_args(argv)

    start = machine()
    t0 = time.perf_counter()
    rows: list[dict[str, Any]] = []
    floor: dict[str, Any] = {"raw_rollout_s": float("nan"), "scenario_run_s": float("nan")}
    detail: dict[str, Any] = {}

    def section(name: str) -> bool:
        if name in args.skip:
            return False
        print(f"[{time.perf_counter() - t0:5.0f} s] {name} ...", file=sys.stderr, flush=True)
        return True

    if section("env-step"):
        rows += bench_env_step(args.quick)
    if section("runner"):
        runner_rows, detail = bench_runner(args.quick)
        rows += runner_rows
        floor = detail
    if section("cross-section"):
        rows += bench_cross_section(args.quick)
    if section("cli"):
        rows += bench_cli(args.quick, floor, thorough=not (args.quick or args.no_thorough))
    if section("render"):
        rows += bench_render(args.quick)
    end = machine()

    print(table(rows))
    if "env-step" not in args.skip:
        print()
        print(env_step_detail(rows))
    load = " / ".join(f"{x:.2f}" for x in start["load_average"])
    print(
        f"\nmujoco {start['mujoco']}, python {start['python']}, {start['cpus']} CPUs; load average (1/5/15 min) "
        f"{load} at the start, {' / '.join(f'{x:.2f}' for x in end['load_average'])} at the end; "
        f"{time.perf_counter() - t0:.0f} s{' (--quick: not a measurement)' if args.quick else ''}"
    )
    out = pathlib.Path(args.json)
    out.parent.mkdir(parents=True, exist_ok=True)
    record = {"quick": args.quick, "machine": start, "machine_end": end, "rows": rows, "runner_cases": detail}
    out.write_text(json.dumps(_finite(record), indent=1))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
