"""Float precision: what storing and stepping in float32 costs, so a check's tolerance can say so.

A float32 engine (Warp; MJX by default) simulates the model and state rounded to float32 (`stored`), and each step
rounds again. `roundoff_floor` is the error float32 alone leaves in a quantity after N steps, added to each check's
float64 tolerance and stated in its reason; `advance_error` and `steady_change_error` bound the roundings that do
not average out (a body too slow for its coordinate's grid, a steady change); `clock` is the float64 clock every
batched engine reports instead of its own float32 time. Everything here is 0 or the input itself on float64.
Measured against both float32 engines in docs/engines.md ("Float32: a floor added to each check").
"""

from __future__ import annotations

import copy
import math

import mujoco
import numpy as np

from rigidbench.engines.base import STATE

# The float32 round-off floor's factor: a step rounds each of the state's numbers to within eps/2 of its size, a few
# dozen operations per RK4 stage each add as much, and the roundings add up as a random walk over the run (measured
# on every check both float32 engines run: docs/engines.md); C = 10 keeps the floor above what was measured without
# making it a blanket.
ROUNDOFF_FACTOR = 10.0


def roundoff_floor(precision: str, nstep: int, scale: float, *, secular: bool = False) -> tuple[float, str]:
    """The error float `precision` alone leaves in a quantity of size `scale` after `nstep` steps, and its rule.

    Random (the default): ``C eps sqrt(N + 1) scale``, the initial state's rounding and a random walk of each step's
    (`ROUNDOFF_FACTOR`). Secular, for a coordinate that a steady motion advances by a near-constant increment every
    step (a position in uniform motion, like the clock): each addition is rounded to within half an ulp of the sum,
    the same way every step, so the error grows like the step count, at most ``(eps / 2) N scale``. 0 on float64,
    whose floor is below every tolerance.
    """
    if precision == "float64":
        return 0.0, ""
    eps = float(np.finfo(np.dtype(precision)).eps)
    if secular:
        floor = 0.5 * eps * nstep * scale
        return floor, f"(eps / 2) N x scale, eps = {eps:.3g}, N = {nstep} steps (secular), scale {scale:.3g}"
    floor = ROUNDOFF_FACTOR * eps * math.sqrt(nstep + 1) * scale
    return floor, f"{ROUNDOFF_FACTOR:g} eps sqrt(N + 1) x scale, eps = {eps:.3g}, N = {nstep} steps, scale {scale:.3g}"


def advance_error(model: mujoco.MjModel, data: mujoco.MjData, precision: str) -> tuple[float, str]:
    """The largest relative error that storing positions in `precision` puts into one step's advance of a moving
    body at `data`'s state, and a phrase naming that body and the numbers (0 and "" on float64 or with nothing
    moving).

    A translational coordinate x advanced by v dt a step is stored on a grid of spacing <= eps |x|: each step's sum
    is rounded by up to eps |x| / 2, or by the whole advance where that is less (a coordinate can stall, never go
    back). Per body (free and slide joints; the state's own coordinates, so the check covers what is simulated),
    the rounding errors of its coordinates against its advance |v| dt. Where the advance is below the grid spacing
    the body stalls: a float32 beam whose projectile, 38 m from the origin, moved 7e-9 m a step never reached its
    target (an MJX census draw of cross-section). Rotations are not covered (orientations are O(1) numbers; the
    tops carry their own floors).
    """
    if precision == "float64":
        return 0.0, ""
    eps = float(np.finfo(np.dtype(precision)).eps)
    dt = float(model.opt.timestep)
    worst, where = 0.0, ""
    for j in range(model.njnt):
        kind = int(model.jnt_type[j])
        if kind not in (int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            continue
        n = 3 if kind == int(mujoco.mjtJoint.mjJNT_FREE) else 1
        x = np.abs(data.qpos[model.jnt_qposadr[j] : model.jnt_qposadr[j] + n])
        v = np.abs(data.qvel[model.jnt_dofadr[j] : model.jnt_dofadr[j] + n])
        advance = float(np.linalg.norm(v)) * dt
        if advance == 0:
            continue
        error = float(np.linalg.norm(np.minimum(0.5 * eps * x, v * dt))) / advance
        if error > worst:
            body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.jnt_bodyid[j])) or f"#{j}"
            worst = error
            pos = ", ".join(f"{c:.3g}" for c in data.qpos[model.jnt_qposadr[j] : model.jnt_qposadr[j] + n])
            stalls = " (it can stall)" if error >= 1 else ""
            where = (
                f"body '{body}' at ({pos}) m advances |v| dt = {advance:.3g} m a step, and {precision} rounds each "
                f"coordinate x to within eps |x| / 2 (eps = {eps:.3g}): an error of {min(error, 1.0):.3g} of the "
                f"advance{stalls}"
            )
    return worst, where


STEADY_CHANGE_RULE = (
    "a steady change: a number x that a constant increment c changes every step lives on a grid of spacing <= eps |x|, "
    "and while x stays in one binade each sum is rounded the same way, so the increment it takes is off by up to "
    "eps |x| / (2 |c|) of itself, the same sign every step"
)


def steady_change_error(value: float, change: float) -> float:
    """The relative error, in units of eps, of a steady per-step `change` to a number of size `value`
    (`STEADY_CHANGE_RULE`): ``|value| / (2 |change|)``; infinite for no change. The secular floor of the clock and of
    a uniform motion's position (`roundoff_floor`) is the same mechanism; `advance_error` refuses where it stalls a
    body. A velocity under a small steady acceleration a takes a dt this way (a ball sliding at 0.043 m/s against a
    friction deceleration of 2.0e-3 m/s^2 at dt = 4e-5 s: 21.4 grid steps a step, rounded alike each step)."""
    return abs(value) / (2 * abs(change)) if change else math.inf


def stored(model: mujoco.MjModel, data: mujoco.MjData, precision: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The model and the state as an engine of `precision` stores them (`stored_model`, `stored_state`); the inputs
    themselves on float64.

    A float32 engine simulates this body, not the one asked for: rounding moves each number by up to eps/2 = 6e-8
    of itself, and a quantity that depends on a small difference of stored numbers moves much more (a rotor with
    I3 - I2 = 1.1e-5 I3 has that difference 1e-2 off). Predicting from it (`Scenario.prepare`) scores the engine's
    arithmetic, not its storage of the model; the rounded parameters are what the rows report.
    """
    if precision == "float64":
        return model, data
    rounded = stored_model(model, precision)
    return rounded, stored_state(rounded, data, precision)


def stored_model(model: mujoco.MjModel, precision: str) -> mujoco.MjModel:
    """A float64 copy of `model` with every float of it (its arrays and its options) rounded to `precision`, its
    constants recomputed (`mj_setConst`); `model` itself on float64."""
    if precision == "float64":
        return model
    dtype = np.dtype(precision)
    rounded = copy.copy(model)
    for holder in (rounded, rounded.opt):
        for name in dir(holder):
            if name.startswith("_"):
                continue
            try:
                value = getattr(holder, name)
            except Exception:  # noqa: BLE001 (a property that needs more than the model)
                continue
            if isinstance(value, np.ndarray) and value.dtype == np.float64 and value.flags.writeable:
                value[...] = value.astype(dtype)
            elif type(value) is float:
                setattr(holder, name, float(dtype.type(value)))
    mujoco.mj_setConst(rounded, mujoco.MjData(rounded))
    return rounded


def stored_state(rounded: mujoco.MjModel, data: mujoco.MjData, precision: str) -> mujoco.MjData:
    """A new MjData of `rounded` (a `stored_model`) at `data`'s state (an MjData of the same model, rounded or not)
    with every number rounded to `precision` but the time (the clock is the step count in float64, `clock`),
    derived quantities computed."""
    full = np.empty(mujoco.mj_stateSize(rounded, STATE))
    mujoco.mj_getState(rounded, data, full, STATE)
    time = full[0]
    full = full.astype(np.dtype(precision)).astype(np.float64)
    full[0] = time
    state = mujoco.MjData(rounded)
    mujoco.mj_setState(rounded, state, full, STATE)
    mujoco.mj_forward(rounded, state)
    return state


def clock(t0: np.ndarray, timestep: float, nstep: int) -> np.ndarray:
    """The time after each step, t0 + (i + 1) dt, in float64, shape (nbatch, nstep).

    A float32 engine's own clock accumulates ``t += dt`` in float32: at t = 43 s, dt = 2 ms is rounded to a multiple
    of the clock's ulp (3.8e-6 s) every step, a bias of 5e-4 of the step, which alone put the pendulum's measured
    period 1.05e-4 off on Warp and MJX float32. Nothing in rigidbench's models reads the time (controls are given
    per step), so the step count is the clock.
    """
    return np.asarray(t0, dtype=np.float64)[:, None] + timestep * np.arange(1, nstep + 1)
