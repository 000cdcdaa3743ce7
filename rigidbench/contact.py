"""Elastic contacts in MuJoCo: from a stiffness (or a target penetration) and a timestep to solref/solimp.

MuJoCo's default contact (solref = (0.02, 1): a critically damped spring with a 20 ms time constant) is
nearly plastic: two spheres meeting head-on separate with restitution ~0.1. The *direct* solref format,
``solref = (-k, -b)``, sets the reference acceleration of the contact's normal coordinate to
``-b v - k r`` (constraint space, so already divided by the effective mass); with ``b = 0`` and a constant
impedance (``solimp = (d, d, ...)``) the penetration delta obeys ``delta'' = -k delta`` while in contact.
That is a linear spring of potential ``V = 1/2 mu k delta^2`` (mu the effective mass of the contact): an
elastic collision lasting ``pi / sqrt(k)`` seconds with largest penetration ``v_n / sqrt(k)``.

Measured here (mujoco 4.0, two 1 kg spheres, RK4): the contact lasts pi/sqrt(k) to within the step
resolution for k = 1e4 and 1e6 and d = 0.9 ... 0.9999, and the spheres exchange velocities exactly.

The direct format bypasses MuJoCo's safety clamp (the standard format keeps the time constant >= 2 dt), so
a contact resolved in too few steps blows up. `elastic_contact` refuses those settings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# Fewest timesteps per contact half-period pi/sqrt(k) that MuJoCo survives (the brief's measurement: below
# ~4 steps the contact explodes). Accuracy needs far more; `RESOLVED_STEPS` is what the reference profiles use.
MIN_STEPS = 4
RESOLVED_STEPS = 40
# Impedance of an elastic contact: constant over the penetration (dmin = dmax), close to 1.
IMPEDANCE = 0.9999


@dataclass(frozen=True)
class ElasticContact:
    """An undamped linear contact spring.

    Attributes
    ----------
    stiffness : float
        k (1/s^2): normal acceleration per unit penetration (force per penetration per effective mass).
    """

    stiffness: float

    @property
    def solref(self) -> tuple[float, float]:
        return (-self.stiffness, 0.0)

    @property
    def solimp(self) -> tuple[float, float, float, float, float]:
        return (IMPEDANCE, IMPEDANCE, 0.001, 0.5, 2.0)

    @property
    def duration(self) -> float:
        """Time in contact (s), pi / sqrt(k), for any approach speed."""
        return math.pi / math.sqrt(self.stiffness)

    def max_penetration(self, approach_speed: float) -> float:
        """Largest penetration (m) for a normal approach speed (m/s): v_n / sqrt(k)."""
        return approach_speed / math.sqrt(self.stiffness)


def elastic_contact(
    *,
    timestep: float,
    stiffness: float | None = None,
    penetration: float | None = None,
    approach_speed: float | None = None,
    min_steps: float = MIN_STEPS,
) -> ElasticContact:
    """An elastic contact resolved in at least `min_steps` timesteps.

    Give either `stiffness` (1/s^2), or a target largest `penetration` (m) with the normal `approach_speed`
    (m/s), from which k = (approach_speed / penetration)^2.

    Raises
    ------
    ValueError
        If the inputs are missing, not positive and finite, or the contact would last fewer than `min_steps`
        timesteps (pi / sqrt(k) < min_steps * timestep), which the direct solref format does not guard.
    """
    for name, value in (
        ("timestep", timestep),
        ("stiffness", stiffness),
        ("penetration", penetration),
        ("approach_speed", approach_speed),
    ):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} = {value!r} must be positive and finite")
    if stiffness is None:
        if penetration is None or approach_speed is None:
            raise ValueError("give stiffness, or penetration together with approach_speed")
        stiffness = (approach_speed / penetration) ** 2
    contact = ElasticContact(float(stiffness))
    steps = contact.duration / timestep
    if steps < min_steps:
        k_max = (math.pi / (min_steps * timestep)) ** 2
        raise ValueError(
            f"contact stiffness = {stiffness:g} 1/s^2 is too high for timestep = {timestep:g} s: the contact would "
            f"last {steps:.2g} steps (< {min_steps:g}) and blow up; use stiffness <= {k_max:.3g} 1/s^2 or a "
            f"timestep <= {contact.duration / min_steps:.3g} s"
        )
    return contact
