"""What a run records (`Trajectory`), and the whole number of steps a run takes (`steps_for`).

The two things a scenario's `measure` and `duration` hooks work with; running a model is the harness's
(`rigidbench.simulate`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

# The state a run records and restarts from: everything that evolves (time, qpos, qvel, act, warm start, ...).
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
    states : ndarray, shape (n + 1, nstate), optional
        The full-physics states (`STATE`) the other fields are views of: what restarts the run exactly from any
        sample (`rigidbench.simulate.time_stepping`).
    """

    time: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    diverged_at: float | None
    states: np.ndarray | None = field(default=None, repr=False)

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
