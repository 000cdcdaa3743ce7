"""Running a model for a whole number of steps, in C, and noticing when MuJoCo blew up.

The validation runner never loops over `mj_step` in Python: it calls `mujoco.rollout`, which steps in C and
returns every state. MuJoCo does not raise on a blown-up simulation; it resets the data (time jumps back to
zero), bumps a warning counter, and carries on. `Trajectory.diverged_at` reports the first sample at which
the state is no longer finite or time stops increasing.
"""

from __future__ import annotations

import os
import statistics
import time as _time
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout

from rigidbench.trajectory import MAX_STEPS, STATE, Trajectory, steps_for  # noqa: F401 (their old home)

# The most memory one recorded trajectory may take (bytes): every state of the run is kept (`simulate`), so a run
# of n steps of a model with s state numbers needs 8 (n + 1) s bytes. Two cases run at once on two cores.
MAX_TRAJECTORY_BYTES = 2 * 1024**3


def check_run_size(model: mujoco.MjModel, nstep: int) -> None:
    """Refuse a run whose recorded trajectory would not fit in `MAX_TRAJECTORY_BYTES`.

    Raises
    ------
    ValueError
        Naming the steps, the state size and the memory it would need.
    """
    nbytes = 8 * (nstep + 1) * mujoco.mj_stateSize(model, STATE)
    if nbytes > MAX_TRAJECTORY_BYTES:
        raise ValueError(
            f"a run of {nstep} steps would record {nbytes / 1024**3:.1f} GiB of states, more than "
            f"{MAX_TRAJECTORY_BYTES / 1024**3:.0f} GiB; use a larger timestep or parameters with shorter time scales"
        )


def get_state(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    state = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, state, STATE)
    return state


def simulate(
    model: mujoco.MjModel, data: mujoco.MjData, duration: float, *, control: np.ndarray | None = None
) -> Trajectory:
    """Step `model` from the state in `data` for ``round(duration / timestep)`` steps.

    `data` is left at the initial state (rollout works on its own copy of the state).

    Parameters
    ----------
    control : ndarray, shape (nstep, nu), optional
        Open-loop actuator controls, one row per step (e.g. a force pulse); zero controls if None.

    Raises
    ------
    ValueError
        See `steps_for`; or if `control` has the wrong shape.
    """
    from rigidbench import forces
    from rigidbench.engines.base import current

    nstep = steps_for(duration, model.opt.timestep)
    forces.attach(model)
    state0 = get_state(model, data)
    kwargs = {}
    if control is not None:
        control = np.asarray(control, dtype=float)
        if control.shape != (nstep, model.nu):
            raise ValueError(f"control has shape {control.shape}, expected ({nstep}, {model.nu})")
        kwargs["control"] = control[None]
    engine = current()
    if engine is not None:  # MuJoCo Warp or MJX (`rigidbench.engines`): float64 states back, same layout
        states = np.concatenate([state0[None], engine.rollout(model, state0[None], nstep, kwargs.get("control"))[0]])
        return split_states(model, states)
    # Row 0 is the initial state; rollout writes the nstep states after it in place (no copy afterwards). It
    # steps the MjData it is given: a scratch copy keeps `data` at the initial state, as promised.
    states = np.empty((nstep + 1, state0.size))
    states[0] = state0
    rollout.rollout(model, mujoco.MjData(model), state0[None], nstep=nstep, state=states[None, 1:], **kwargs)
    return split_states(model, states)


def split_states(model: mujoco.MjModel, states: np.ndarray) -> Trajectory:
    """Turn full-physics state rows (time, qpos, qvel, act, ...) into a `Trajectory`."""
    time = states[:, 0]
    qpos = states[:, 1 : 1 + model.nq]
    qvel = states[:, 1 + model.nq : 1 + model.nq + model.nv]
    return Trajectory(time=time, qpos=qpos, qvel=qvel, diverged_at=divergence_time(time, qpos, qvel), states=states)


def divergence_time(time: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> float | None:
    """Time of the last sane sample, or None if every sample is finite and time increases throughout."""
    bad = ~(np.isfinite(qpos).all(axis=1) & np.isfinite(qvel).all(axis=1))
    bad[1:] |= np.diff(time) <= 0.0  # MuJoCo's reset after a bad acceleration sends time back to 0
    if not bad.any():
        return None
    first = int(np.argmax(bad))
    return float(time[max(first - 1, 0)])


def initial_states(model: mujoco.MjModel, data: mujoco.MjData, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
    """Full-physics states for a batch: the state in `data` with qpos and qvel replaced row by row.

    Parameters
    ----------
    qpos : ndarray, shape (nbatch, nq)
    qvel : ndarray, shape (nbatch, nv)

    Returns
    -------
    ndarray, shape (nbatch, mj_stateSize(model, mjSTATE_FULLPHYSICS))
    """
    qpos = np.atleast_2d(qpos)
    qvel = np.atleast_2d(qvel)
    states = np.repeat(get_state(model, data)[None], len(qpos), axis=0)
    states[:, 1 : 1 + model.nq] = qpos
    states[:, 1 + model.nq : 1 + model.nq + model.nv] = qvel
    return states


def final_states(
    model: mujoco.MjModel | list[mujoco.MjModel],
    states0: np.ndarray,
    nstep: int,
    *,
    nthread: int | None = None,
    chunk: int = 1024,
) -> tuple[np.ndarray, np.ndarray]:
    """Step many independent initial states `nstep` times each, in C (threaded), keeping only the last state.

    Batch work for Monte Carlo (DESIGN.md "Where speed comes from"): `mujoco.rollout` with one MjData per
    thread. Rollout records every step, so the batch runs in chunks of `chunk` states to bound the memory
    (chunk x nstep x nstate doubles). The result does not depend on `nthread` or `chunk`: each state is
    stepped on its own from a fresh copy of its initial state.

    Parameters
    ----------
    model : MjModel, or a list of one MjModel per state (same sizes, e.g. different contact stiffness)
    states0 : ndarray, shape (nbatch, nstate)
        Full-physics initial states (`initial_states`).
    nstep : int
        Steps per state, >= 1.
    nthread : int, optional
        Threads (default: the number of CPUs).
    chunk : int
        States per rollout call.

    Returns
    -------
    states : ndarray, shape (nbatch, nstate)
        The state after `nstep` steps.
    diverged : ndarray of bool, shape (nbatch,)
        True where the state went non-finite or MuJoCo reset it (time did not reach nstep * timestep).

    Raises
    ------
    ValueError
        If nstep < 1 or nstep > MAX_STEPS, or the shapes do not match.
    """
    if not 1 <= nstep <= MAX_STEPS:
        raise ValueError(f"nstep = {nstep} is outside [1, {MAX_STEPS}]")
    states0 = np.atleast_2d(np.asarray(states0, dtype=float))
    models = model if isinstance(model, list) else None
    base = models[0] if models else model
    if states0.shape[1] != mujoco.mj_stateSize(base, STATE):
        raise ValueError(f"states0 has {states0.shape[1]} columns, expected {mujoco.mj_stateSize(base, STATE)}")
    if models is not None and len(models) != len(states0):
        raise ValueError(f"{len(models)} models for {len(states0)} states")
    from rigidbench import forces
    from rigidbench.engines.base import current

    nthread = (os.cpu_count() or 1) if nthread is None else int(nthread)
    for m in models if models is not None else [base]:
        if forces.attach(m):
            nthread = forces.threads_for(m, nthread)
    datas = [mujoco.MjData(base) for _ in range(max(nthread, 1))]
    out = np.empty_like(states0)
    engine = current()
    if engine is not None and models is not None:
        for i, (m, s0) in enumerate(zip(models, states0, strict=True)):  # one model each (e.g. a stiffness each)
            out[i] = engine.rollout(m, s0[None], nstep)[0, -1]
    elif engine is not None:
        for lo in range(0, len(states0), chunk):
            hi = min(lo + chunk, len(states0))
            out[lo:hi] = engine.rollout(base, states0[lo:hi], nstep)[:, -1]  # one batch of worlds per chunk
    for lo in range(0, len(states0) if engine is None else 0, chunk):
        hi = min(lo + chunk, len(states0))
        m = models[lo:hi] if models is not None else base
        states, _ = rollout.rollout(m, datas, states0[lo:hi], nstep=nstep)
        out[lo:hi] = states[:, -1]
    qpos = out[:, 1 : 1 + base.nq]
    qvel = out[:, 1 + base.nq : 1 + base.nq + base.nv]
    t_end = states0[:, 0] + nstep * base.opt.timestep
    diverged = ~(np.isfinite(qpos).all(axis=1) & np.isfinite(qvel).all(axis=1))
    diverged |= ~np.isclose(out[:, 0], t_end, rtol=1e-9, atol=0.5 * base.opt.timestep)
    return out, diverged


# ---- the cost of stepping ------------------------------------------------------------------------------------

# What a cost measurement times (`time_stepping`): at least TIMING_BUDGET seconds, at least TIMING_REPEATS repeats.
TIMING_BUDGET = 0.1
TIMING_REPEATS = 3


@dataclass(frozen=True)
class Timing:
    """The measured cost of stepping a case.

    Attributes
    ----------
    cpu_per_step, wall_per_step : float
        Median over the repeats of CPU seconds (this process, every thread) and wall seconds per step.
    cpu_spread : tuple of float
        The smallest and largest CPU seconds per step over the repeats.
    repeats : int
    steps : int
        Steps timed in all.
    method : str
        ``"chunks"``: stretches of the run restarted from its recorded states, spread over the run (so that a
        run whose cost changes along it, e.g. in contact, is sampled where it costs); ``"whole"``: the whole
        run repeated (a run shorter than a chunk, or a scenario with its own `simulate`).
    """

    cpu_per_step: float
    wall_per_step: float
    cpu_spread: tuple[float, float]
    repeats: int
    steps: int
    method: str

    def record(self, timestep: float) -> dict:
        """The cost as rows carry it: CPU seconds per simulated second, its spread, the real-time factor."""
        return {
            "cpu_per_sim_second": self.cpu_per_step / timestep,
            "cpu_per_sim_second_spread": [self.cpu_spread[0] / timestep, self.cpu_spread[1] / timestep],
            "realtime_factor": timestep / self.cpu_per_step if self.cpu_per_step > 0 else None,
            "wall_per_sim_second": self.wall_per_step / timestep,
            "timed_repeats": self.repeats,
            "timed_steps": self.steps,
            "timing": self.method,
        }


def time_stepping(
    model: mujoco.MjModel,
    traj: Trajectory,
    control: np.ndarray | None = None,
    *,
    first: tuple[float, float] | None = None,
    budget: float = TIMING_BUDGET,
    repeats: int = TIMING_REPEATS,
) -> Timing:
    """Time the stepping of a run already simulated, from its recorded states, without re-running all of it.

    `first` is the (CPU, wall) seconds the run itself took: it is the first repeat (the whole run's stepping).
    Each further repeat restarts `mujoco.rollout` from a recorded state and steps a chunk of the run (the same
    controls), timing only the rollout. Chunks are long enough that `repeats` of them take `budget` seconds (from
    the first repeat's cost per step), and start at evenly spaced points of the run; a run shorter than a chunk is
    repeated whole. Repeats continue until `budget` seconds have been timed and at least `repeats` were made.

    Raises
    ------
    ValueError
        If the trajectory has no recorded states.
    """
    if traj.states is None:
        raise ValueError("the trajectory has no recorded states to restart from")
    states = traj.states
    nstep = len(states) - 1
    data = mujoco.MjData(model)
    probe = min(nstep, 64)

    def step_from(start: int, n: int) -> tuple[float, float]:
        kwargs = {}
        if control is not None:
            kwargs["control"] = np.asarray(control[start : start + n])[None]
        out = np.empty((1, n, states.shape[1]))
        c0, w0 = _time.process_time(), _time.perf_counter()
        rollout.rollout(model, data, states[start][None], nstep=n, state=out, **kwargs)
        return _time.process_time() - c0, _time.perf_counter() - w0

    cpus: list[float] = []
    walls: list[float] = []
    timed = 0.0
    if first is not None:
        cpus.append(first[0] / nstep)
        walls.append(first[1] / nstep)
        timed = first[1]
        per_step = max(first[1] / nstep, 1e-9)
    else:
        per_step = max(step_from(0, probe)[1] / probe, 1e-9)
    left = max(budget - timed, 0.0) / max(repeats - len(cpus), 1)
    chunk = int(min(nstep, max(probe, left / per_step)))
    starts = [0] if chunk >= nstep else [round(i * (nstep - chunk) / max(repeats - 1, 1)) for i in range(repeats)]
    i = 0
    while len(cpus) < repeats or timed < budget:
        start = starts[i % len(starts)]
        cpu, wall = step_from(start, chunk)
        cpus.append(cpu / chunk)
        walls.append(wall / chunk)
        timed += wall
        i += 1
        if i >= 1000:  # a run of a few steps: enough repeats
            break
    return Timing(
        cpu_per_step=statistics.median(cpus),
        wall_per_step=statistics.median(walls),
        cpu_spread=(min(cpus), max(cpus)),
        repeats=len(cpus),
        steps=chunk * (len(cpus) - (first is not None)) + (nstep if first is not None else 0),
        method="whole" if chunk >= nstep else "chunks",
    )


def time_calls(run, *, steps: int, budget: float = TIMING_BUDGET, repeats: int = TIMING_REPEATS) -> Timing:
    """Time a whole simulation call `run()` (a scenario's own `simulate`) repeatedly: `steps` is what one call
    steps. Repeats until `budget` seconds and `repeats` calls."""
    cpus: list[float] = []
    walls: list[float] = []
    timed = 0.0
    while len(cpus) < repeats or timed < budget:
        c0, w0 = _time.process_time(), _time.perf_counter()
        run()
        cpu, wall = _time.process_time() - c0, _time.perf_counter() - w0
        cpus.append(cpu / steps)
        walls.append(wall / steps)
        timed += wall
    return Timing(
        statistics.median(cpus), statistics.median(walls), (min(cpus), max(cpus)), len(cpus), steps * len(cpus), "whole"
    )


def machine() -> dict:
    """What a cost figure depends on: the CPU, the CPUs this process may use, the load, the versions."""
    import platform

    model = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    return {
        "cpu": model,
        "cpus": cpus,
        "load": list(load) if load else None,
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
    }
