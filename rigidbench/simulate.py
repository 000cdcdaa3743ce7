"""Running a model for a whole number of steps, in C, and noticing when MuJoCo blew up.

The validation runner never loops over `mj_step` in Python: it calls `mujoco.rollout`, which steps in C and
returns every state. MuJoCo does not raise on a blown-up simulation; it resets the data (time jumps back to
zero), bumps a warning counter, and carries on. `Trajectory.diverged_at` reports the first sample at which
the state is no longer finite or time stops increasing.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout

STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS

# The longest run accepted (steps): 2e7 states of a small model is ~1.5 GB; longer runs are a mistake.
MAX_STEPS = 20_000_000


@dataclass(frozen=True)
class Trajectory:
    """States at every step, the initial state included.

    Attributes
    ----------
    time : ndarray, shape (n + 1,)
        Seconds.
    qpos : ndarray, shape (n + 1, nq)
    qvel : ndarray, shape (n + 1, nv)
        For free and ball joints, angular velocity in the body frame.
    diverged_at : float or None
        Simulated time (s) of the last good sample before the state stopped being finite or MuJoCo reset it;
        None if the run stayed sane.
    """

    time: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    diverged_at: float | None

    @property
    def timestep(self) -> float:
        return float(self.time[1] - self.time[0])


def steps_for(duration: float, timestep: float) -> int:
    """Whole number of steps covering `duration` (``while d.time < T`` would take one step too many).

    Raises
    ------
    ValueError
        If the run would be shorter than one step or longer than `MAX_STEPS`.
    """
    n = round(duration / timestep)
    if n < 1:
        raise ValueError(f"duration {duration:g} s is shorter than one timestep ({timestep:g} s)")
    if n > MAX_STEPS:
        raise ValueError(
            f"duration {duration:g} s at timestep {timestep:g} s needs {n} steps, more than {MAX_STEPS}; "
            "use a larger timestep or parameters with shorter time scales"
        )
    return n


def get_state(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    state = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, state, STATE)
    return state


def simulate(
    model: mujoco.MjModel, data: mujoco.MjData, duration: float, *, control: np.ndarray | None = None
) -> Trajectory:
    """Step `model` from the state in `data` for ``round(duration / timestep)`` steps.

    `data` is rollout's scratch space: it is left at the last state, not the initial one.

    Parameters
    ----------
    control : ndarray, shape (nstep, nu), optional
        Open-loop actuator controls, one row per step (e.g. a force pulse); zero controls if None.

    Raises
    ------
    ValueError
        See `steps_for`; or if `control` has the wrong shape.
    """
    nstep = steps_for(duration, model.opt.timestep)
    state0 = get_state(model, data)
    kwargs = {}
    if control is not None:
        control = np.asarray(control, dtype=float)
        if control.shape != (nstep, model.nu):
            raise ValueError(f"control has shape {control.shape}, expected ({nstep}, {model.nu})")
        kwargs["control"] = control[None]
    # Row 0 is the initial state; rollout writes the nstep states after it in place (no copy afterwards).
    states = np.empty((nstep + 1, state0.size))
    states[0] = state0
    rollout.rollout(model, data, state0[None], nstep=nstep, state=states[None, 1:], **kwargs)
    return split_states(model, states)


def split_states(model: mujoco.MjModel, states: np.ndarray) -> Trajectory:
    """Turn full-physics state rows (time, qpos, qvel, act, ...) into a `Trajectory`."""
    time = states[:, 0]
    qpos = states[:, 1 : 1 + model.nq]
    qvel = states[:, 1 + model.nq : 1 + model.nq + model.nv]
    return Trajectory(time=time, qpos=qpos, qvel=qvel, diverged_at=divergence_time(time, qpos, qvel))


def divergence_time(time: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> float | None:
    """Time of the last sane sample, or None if every sample is finite and time increases throughout."""
    bad = ~(np.isfinite(qpos).all(axis=1) & np.isfinite(qvel).all(axis=1))
    bad[1:] |= np.diff(time) <= 0.0  # MuJoCo's reset after a bad acceleration sends time back to 0
    if not bad.any():
        return None
    first = int(np.argmax(bad))
    return float(time[max(first - 1, 0)])
