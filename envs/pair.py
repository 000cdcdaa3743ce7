"""The gymnasium side shared by the scenarios of two free bodies (`hard-spheres`, `two-body-orbit`, `rutherford`):
observation, action, measurement and deviation, for one env and for a batch of them.

Observation: x1, x2, v1, v2 (world frame, m and m/s), the bodies' free-joint positions and linear velocities.
Action: a force (N, world frame) on one body, through ``xfrc_applied``. Observables: the relative position
r = x1 - x2 (m), and the deviation |r - r_theory| over a length scale of the scenario.
"""

from __future__ import annotations

import math
from typing import ClassVar

import gymnasium as gym
import numpy as np

from rigidbench.envs.base import ScenarioEnv


class FreePairEnv(ScenarioEnv):
    """A scenario env of two free bodies. A subclass's `load` sets, before `start_views`:

    - ``_slices``: where x1, x2, v1, v2 sit, ``(("qpos", slice), ("qpos", slice), ("qvel", slice), ("qvel",
      slice))``, each slice three long;
    - ``_body_id``: the body the action pushes;
    - ``_scale``: the length (m) the deviation is measured in;

    and the class sets ``max_force`` (N), unless it overrides `define_action_space`.
    """

    max_force: ClassVar[float] = 1.0
    # Observables compared with theory: the relative position r = x1 - x2 (m), world frame.
    observables: ClassVar[tuple[str, ...]] = ("r_x", "r_y", "r_z")

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(12,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_force, self.max_force, shape=(3,), dtype=np.float64)

    @staticmethod
    def _pair_slices(q1: int, q2: int, d1: int, d2: int) -> tuple[tuple[str, slice], ...]:
        """`_slices` from the two free joints' qpos and dof addresses."""
        return tuple(
            (array, slice(start, start + 3))
            for array, start in (("qpos", q1), ("qpos", q2), ("qvel", d1), ("qvel", d2))
        )

    def bind_views(self) -> None:
        """x1, x2, v1, v2 and the pushed body's force (`ScenarioEnv.bind_views`)."""
        data = self.data
        self._obs_views = tuple(getattr(data, array)[where] for array, where in self._slices)
        self._force = data.xfrc_applied[self._body_id, :3]

    def observe(self) -> np.ndarray:
        return np.concatenate(self._obs_views)  # [x1, x2, v1, v2]

    def apply_action(self, action: np.ndarray) -> None:
        self._force[:] = action

    def observe_batch(self, worlds) -> np.ndarray:
        return np.concatenate([getattr(worlds, array)[:, where] for array, where in self._slices], axis=1)

    def apply_actions(self, actions: np.ndarray, worlds) -> None:
        worlds.xfrc_applied[:, self._body_id, :3] = actions

    def measured(self, obs: np.ndarray) -> list[float]:
        o = obs.tolist()
        return [o[0] - o[3], o[1] - o[4], o[2] - o[5]]

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        return obs[:, 0:3] - obs[:, 3:6]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        """|r - r_theory| / scale (Python floats: one env's step)."""
        (m1, m2, m3), (p1, p2, p3) = measured, predicted
        d1, d2, d3 = m1 - p1, m2 - p2, m3 - p3
        return math.sqrt(d1 * d1 + d2 * d2 + d3 * d3) / self._scale

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        """`deviation` of every copy, in the same operations (bit for bit)."""
        d1, d2, d3 = (measured - predicted).T
        return np.sqrt(d1 * d1 + d2 * d2 + d3 * d3) / self._scale
