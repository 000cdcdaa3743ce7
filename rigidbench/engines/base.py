"""What an engine is: the adapter interface, its refusal, and the engine in effect.

The bottom of `rigidbench.engines`: it imports no other project module. `Engine` is what every adapter implements
(`rigidbench.engines.cpu`, `.warp`, `.mjx`): `rollout` steps initial states, `check` refuses a model using a
feature the engine lacks (`EngineRefused`), `record` says what a result row records of it. `use` makes one the
engine in effect for a block, and `current` is what `rigidbench.simulate` asks.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

# The state every engine takes and gives back: MuJoCo's full-physics state, one row per world (time, qpos, qvel, ...).
STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS

# The engines `--engine` names (`rigidbench.engines.registry.engine_for`).
ENGINES = ("mujoco", "warp", "mjx")


class EngineRefused(ValueError):
    """A model uses a feature the engine does not have (an integrator, a solver, a contact type): refused before
    anything is simulated, naming the engine and the feature. A run reports such a case as ``unsupported``."""


@dataclass(frozen=True)
class Engine:
    """An engine: its name, the device it runs on and its float precision.

    Subclasses implement `rollout` (and `check` where they lack features of C MuJoCo).
    """

    name: str = "mujoco"
    device: str = "cpu"
    precision: str = "float64"

    def version(self) -> str:
        return mujoco.__version__

    def check(self, model: mujoco.MjModel) -> None:
        """Refuse a model using a feature this engine does not have (ValueError naming engine and feature)."""

    def rollout(
        self, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None = None
    ) -> np.ndarray:
        """Step each initial state `nstep` times.

        Parameters
        ----------
        states0 : ndarray, shape (nbatch, nstate)
            Full-physics initial states.
        control : ndarray, shape (nbatch, nstep, nu), optional

        Returns
        -------
        ndarray, shape (nbatch, nstep, nstate)
            The states after each step (float64).
        """
        raise NotImplementedError

    def record(self) -> dict[str, Any]:
        """What a result row records of the engine."""
        return {
            "engine": self.name,
            "engine_version": self.version(),
            "device": self.device,
            "precision": self.precision,
        }


def _layout(model: mujoco.MjModel) -> tuple[slice, slice, slice]:
    """Where time, qpos and qvel sit in a full-physics state row (`STATE`)."""
    return slice(0, 1), slice(1, 1 + model.nq), slice(1 + model.nq, 1 + model.nq + model.nv)


_CURRENT: contextvars.ContextVar[Engine | None] = contextvars.ContextVar("rigidbench_engine", default=None)


def current() -> Engine | None:
    """The engine in effect (None: C MuJoCo's own path, `rigidbench.simulate`)."""
    return _CURRENT.get()


@contextlib.contextmanager
def use(engine: Engine | None) -> Iterator[None]:
    """Make `engine` the one `rigidbench.simulate` steps with, in this thread, for the block."""
    token = _CURRENT.set(engine)
    try:
        yield
    finally:
        _CURRENT.reset(token)
