"""Blows as short rectangular force pulses, delivered through `Scenario.control` (open-loop actuator controls).

A blow of impulse Pi lasting tau is a constant actuator force Pi / (n dt) over the first n = round(tau / dt)
steps (at least one). The control is constant within a step, so the delivered impulse is Pi exactly for any
integrator; what a finite pulse changes is *where* the body is while it is pushed: a body turning at omega moves
by omega tau during the pulse, an O(omega tau) effect each scenario bounds in its tolerances. The duration
actually used, n dt, is what the predictions see (`duration`).
"""

from __future__ import annotations

import mujoco
import numpy as np

# Name of the `<custom><numeric>` entry holding a model's nominal pulse duration (s).
PULSE_DURATION = "pulse_duration"


def steps(model: mujoco.MjModel) -> int:
    """Number of steps the pulse lasts at this model's timestep (at least one)."""
    tau = float(model.numeric(PULSE_DURATION).data[0])
    return max(1, round(tau / model.opt.timestep))


def duration(model: mujoco.MjModel) -> float:
    """The pulse duration (s) actually simulated: a whole number of steps."""
    return steps(model) * float(model.opt.timestep)


def control(model: mujoco.MjModel, nstep: int, actuator: str, impulse: float) -> np.ndarray:
    """Controls, shape (nstep, nu): a rectangular pulse of `impulse` (N s, or N m s) on `actuator`, from t = 0.

    Raises
    ------
    ValueError
        If the run is shorter than the pulse.
    """
    n = steps(model)
    if nstep < n:
        raise ValueError(f"run of {nstep} steps is shorter than the {n}-step pulse")
    ctrl = np.zeros((nstep, model.nu))
    ctrl[:n, model.actuator(actuator).id] = impulse / duration(model)
    return ctrl
