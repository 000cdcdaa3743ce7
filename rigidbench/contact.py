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

Why the spring is exactly ``-k delta`` (MuJoCo's constraint model, engine_core_constraint.c): the reference
acceleration is ``aref = -B v - K d(r) r`` with ``K = -solref[0] / dmax^2`` (direct) or
``1 / (dmax^2 tau^2 zeta^2)`` (standard, tau clamped to >= 2 dt), and the soft constraint yields the
acceleration ``(1 - d) a0 + d aref`` whenever its regulariser uses the exact effective mass (true for a
frictionless sphere-sphere normal, whose inverse effective mass 1/m1 + 1/m2 is what MuJoCo's diagonal
approximation computes). With no other force (a0 = 0) and d(r) = dmax: ``delta'' = -k delta``. `contact_spring`
returns these effective coefficients for either format, so predictions can read them from a compiled model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

# Fewest timesteps per contact half-period pi/sqrt(k) that MuJoCo survives (the brief's measurement: below
# ~4 steps the contact explodes). Accuracy needs far more; `RESOLVED_STEPS` is what the reference profiles use.
# Measured (mujoco 4.0, two 1 kg spheres at 1 m/s, b = a/2, kinetic energy out/in) at 0.5 / 1 / 2 / 4 steps per
# contact: Euler and implicitfast 556 / 30 / 1.43 / 1.025 (the energy explodes), RK4 0.82 (1.5 steps) / 0.94 /
# 0.996 (4 steps). Past 4 steps the error is a few percent at worst, and it falls as (sqrt(k) dt)^2.
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

    def steps(self, timestep: float) -> float:
        """Timesteps per contact, pi / (sqrt(k) timestep)."""
        return self.duration / timestep


@dataclass(frozen=True)
class ContactSpring:
    """The linear spring-damper a fully engaged MuJoCo contact behaves like: ``delta'' = -k delta - c delta'``
    (delta the penetration, constraint space, no other force on the contact's normal coordinate).

    Attributes
    ----------
    stiffness : float
        k (1/s^2).
    damping : float
        c (1/s).
    direct : bool
        True for the direct solref format (no safety clamp), False for the standard (timeconst, dampratio).
    """

    stiffness: float
    damping: float
    direct: bool

    @property
    def elastic(self) -> bool:
        return self.damping == 0.0

    @property
    def restitution(self) -> float:
        """Normal restitution of the spring-damper alone (a linear oscillator's half-cycle decay; 0 at or past
        critical damping). MuJoCo's real restitution also depends on the impedance's variation over its width."""
        disc = 4 * self.stiffness - self.damping**2
        if disc <= 0:
            return 0.0
        return math.exp(-math.pi * self.damping / math.sqrt(disc))


def contact_spring(solref, timestep: float) -> ContactSpring:
    """The effective spring-damper of a contact with these solref/solimp, at the full impedance d = dmax.

    Direct format ``solref = (-k, -c)``: ``k_eff = k (d/dmax)^2 = k``, ``c_eff = c d / dmax = c``. Standard
    format ``(tau, zeta)``: ``k_eff = d^2 / (dmax^2 tau^2 zeta^2)``, ``c_eff = 2 d / (dmax tau)``, with tau
    clamped to >= 2 timestep as MuJoCo does. (MuJoCo's acceleration is d times its reference acceleration,
    module docstring.)

    Parameters
    ----------
    solref : sequence of 2 floats
    timestep : float
        Seconds.
    """
    if solref[0] < 0:
        return ContactSpring(stiffness=-float(solref[0]), damping=-float(solref[1]), direct=True)
    tau = max(float(solref[0]), 2 * timestep)
    zeta = float(solref[1])
    return ContactSpring(stiffness=1.0 / (tau * zeta) ** 2, damping=2.0 / tau, direct=False)


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


def require_overlap_at_most(speed: float, stiffness: float, contact_distance: float, fraction: float, why: str) -> None:
    """Refuse a contact so soft that a head-on approach at `speed` (m/s) overlaps by more than `fraction` of the
    `contact_distance` (m): the largest penetration is speed / sqrt(k).

    Raises
    ------
    ValueError
        Naming the stiffness parameter, the overlap, and the smallest stiffness that is accepted.
    """
    depth = speed / math.sqrt(stiffness)
    if not depth <= fraction * contact_distance:
        raise ValueError(
            f"parameter 'stiffness' = {stiffness:g} 1/s^2 lets the spheres overlap by speed/sqrt(k) = {depth:.3g} m, "
            f"more than {fraction:.0%} of r1 + r2 = {contact_distance:g} m ({why}): use stiffness >= "
            f"{(speed / (fraction * contact_distance)) ** 2:.3g} 1/s^2"
        )


# ---- parameter targets (`rigidbench.params.Param.target`) for a contact's stiffness and resolution ----------------


@dataclass(frozen=True)
class ContactStiffness:
    """Stiffness k (1/s^2) of an elastic contact on the named geoms: solref = (-k, 0) (`contact_spring`).

    Read back as the stiffness MuJoCo uses: -solref[0] in the direct format; for a standard-format solref (a
    profile such as ``mujoco-default`` replaced it) the equivalent spring 1/(tau zeta)^2 of
    `rigidbench.contact.contact_spring`, which then comes with damping.
    """

    geoms: tuple[str, ...]

    def apply(self, spec: mujoco.MjSpec, value: float) -> None:
        for name in self.geoms:
            spec.geom(name).solref = [-float(value), 0.0]

    def read(self, model: mujoco.MjModel) -> float:
        return contact_spring(model.geom(self.geoms[0]).solref, model.opt.timestep).stiffness


@dataclass(frozen=True)
class ContactSteps:
    """Timesteps per contact N (1) of an elastic contact on `geom`: sets the timestep to pi / (N sqrt(k)), so the
    timestep follows the stiffness k (apply the stiffness first; `Settings.timestep` still overrides it).

    A whole N puts the force's kink at contact exit on a step boundary, as a lead of whole steps does for the
    entry: RK4 then meets no kink inside a step and stays fourth order (`contact_spring`). Read back from the
    compiled model as pi / (sqrt(k) timestep), whatever set the timestep.
    """

    geom: str

    def apply(self, spec: mujoco.MjSpec, value: float) -> None:
        stiffness = -float(spec.geom(self.geom).solref[0])
        if stiffness <= 0:
            raise ValueError(f"geom '{self.geom}': contact steps need a direct-format solref (-k, -b), not a time")
        spec.option.timestep = math.pi / (float(value) * math.sqrt(stiffness))

    def read(self, model: mujoco.MjModel) -> float:
        stiffness = contact_spring(model.geom(self.geom).solref, model.opt.timestep).stiffness
        return math.pi / (math.sqrt(stiffness) * float(model.opt.timestep))
