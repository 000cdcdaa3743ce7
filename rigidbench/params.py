"""Scenario parameters: named, in SI units, validated, applied through `mujoco.MjSpec` and read back.

A parameter's default lives in the scenario's MJCF file (house rule 3): either as a native model property
(a body's mass, inertia or centre of mass, the gravity vector) or, for initial conditions and other numbers
MuJoCo has no element for, as a `<custom><numeric>` entry. A `Target` knows where the number lives: it
writes a value into an `MjSpec` and reads the compiled value back from the `MjModel`, so what a prediction
uses is what MuJoCo simulated.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import mujoco
import numpy as np

Value = float | tuple[float, ...]


class Target(Protocol):
    """Where a parameter's number lives in a model."""

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None: ...

    def read(self, model: mujoco.MjModel) -> Value: ...


@dataclass(frozen=True)
class Numeric:
    """A `<custom><numeric name=...>` entry (initial conditions and other scenario numbers)."""

    name: str

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        spec.numeric(self.name).data = list(np.atleast_1d(value))

    def read(self, model: mujoco.MjModel) -> Value:
        return _unwrap(model.numeric(self.name).data)


@dataclass(frozen=True)
class BodyMass:
    body: str

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        spec.body(self.body).mass = float(value)

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.body(self.body).mass[0])


@dataclass(frozen=True)
class BodyInertia:
    """Principal moments about the body's centre of mass; `axes` are the diagonal entries this sets."""

    body: str
    axes: tuple[int, ...]

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        inertia = np.array(spec.body(self.body).inertia, dtype=float)
        inertia[list(self.axes)] = float(value)
        spec.body(self.body).inertia = inertia

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.body(self.body).inertia[self.axes[0]])


@dataclass(frozen=True)
class BodyComOffset:
    """One coordinate of a body's centre of mass in the body frame (m)."""

    body: str
    axis: int

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        ipos = np.array(spec.body(self.body).ipos, dtype=float)
        ipos[self.axis] = float(value)
        spec.body(self.body).ipos = ipos

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.body(self.body).ipos[self.axis])


@dataclass(frozen=True)
class GeomSize:
    """One entry of a geom's size (m), e.g. index 0 = a sphere's radius."""

    geom: str
    index: int = 0

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        size = np.array(spec.geom(self.geom).size, dtype=float)
        size[self.index] = float(value)
        spec.geom(self.geom).size = size

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.geom(self.geom).size[self.index])


@dataclass(frozen=True)
class Gravity:
    """Magnitude of gravity along -z (m/s^2)."""

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        spec.option.gravity = [0.0, 0.0, -float(value)]

    def read(self, model: mujoco.MjModel) -> Value:
        return float(-model.opt.gravity[2])


@dataclass(frozen=True)
class ScaledBodyMass:
    """A body's mass (kg), with its explicit inertia scaled in proportion (the shape is kept)."""

    body: str

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        body = spec.body(self.body)
        body.inertia = np.array(body.inertia, dtype=float) * (float(value) / body.mass)
        body.mass = float(value)

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.body(self.body).mass[0])


@dataclass(frozen=True)
class RodLength:
    """Full length L (m) of a thin uniform rod along body y: a box geom of half-length L/2, and the body's
    explicit inertia M L^2 / 12 about the transverse axes x and z through its centre (the body's mass as set in
    the spec). The axial moment (about y) keeps its ratio to the transverse one (the model file's token value:
    the rod never turns about its axis; at least 1e-14 kg m^2, MuJoCo's floor being 1e-15), so the inertia obeys
    MuJoCo's triangle inequality A + B >= C at every length and mass. With `from_origin`, the rod runs from the
    body origin (a pivot) to y = L, its centre of mass and geom at y = L/2; otherwise it is centred on the
    origin."""

    body: str
    geom: str
    from_origin: bool = False

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        geom = spec.geom(self.geom)
        size = np.array(geom.size, dtype=float)
        size[1] = float(value) / 2
        geom.size = size
        body = spec.body(self.body)
        transverse = body.mass * float(value) ** 2 / 12
        axial_share = float(body.inertia[1]) / float(body.inertia[0])
        # MuJoCo refuses a moment below mjMINVAL = 1e-15; 1e-14 <= 2 x transverse down to M L^2 = 6e-14 kg m^2.
        body.inertia = [transverse, max(axial_share * transverse, 1e-14), transverse]
        if self.from_origin:
            geom.pos = [0.0, float(value) / 2, 0.0]
            body.ipos = [0.0, float(value) / 2, 0.0]

    def read(self, model: mujoco.MjModel) -> Value:
        return float(2 * model.geom(self.geom).size[1])


@dataclass(frozen=True)
class SphereRadius:
    """Radius R (m) of a solid sphere: the sphere geom's size, and the body's explicit inertia 2/5 M R^2."""

    body: str
    geom: str

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        spec.geom(self.geom).size = [float(value), 0.0, 0.0]
        body = spec.body(self.body)
        body.inertia = [0.4 * body.mass * float(value) ** 2] * 3

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.geom(self.geom).size[0])


@dataclass(frozen=True)
class GeomFriction:
    """Sliding friction coefficient of the named geoms (MuJoCo uses the larger of a pair's two values)."""

    geoms: tuple[str, ...]

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        for name in self.geoms:
            friction = np.array(spec.geom(name).friction, dtype=float)
            friction[0] = float(value)
            spec.geom(name).friction = friction

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.geom(self.geoms[0]).friction[0])


@dataclass(frozen=True)
class SitePosition:
    """One coordinate (m) of a site's position in its body's frame."""

    site: str
    axis: int

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        pos = np.array(spec.site(self.site).pos, dtype=float)
        pos[self.axis] = float(value)
        spec.site(self.site).pos = pos

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.site(self.site).pos[self.axis])


@dataclass(frozen=True)
class ActuatorGear:
    """One component of an actuator's gear (e.g. the moment arm of a force-and-couple pair, m)."""

    actuator: str
    index: int

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        gear = np.array(spec.actuator(self.actuator).gear, dtype=float)
        gear[self.index] = float(value)
        spec.actuator(self.actuator).gear = gear

    def read(self, model: mujoco.MjModel) -> Value:
        return float(model.actuator(self.actuator).gear[self.index])


def _unwrap(data: np.ndarray) -> Value:
    values = tuple(float(x) for x in np.ravel(data))
    return values[0] if len(values) == 1 else values


@dataclass(frozen=True)
class Range:
    """An interval of valid values; `low_open`/`high_open` exclude the end point. With `magnitude`, the interval
    holds |x| (a value of either sign whose size lies in it, e.g. an amplitude between a floor and a ceiling)."""

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False
    magnitude: bool = False

    def __contains__(self, x: float) -> bool:
        x = abs(x) if self.magnitude else x
        above = x > self.low if self.low_open else x >= self.low
        below = x < self.high if self.high_open else x <= self.high
        return above and below

    def __str__(self) -> str:
        text = f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}{')' if self.high_open else ']'}"
        return f"|x| in {text}" if self.magnitude else text


def positive(high: float) -> Range:
    """The interval (0, high]."""
    return Range(0.0, high, low_open=True)


@dataclass(frozen=True)
class Bound:
    """A range that depends on other parameters, e.g. an impact parameter in ``[0, r1 + r2)``.

    Attributes
    ----------
    text : str
        The range in words, as `rigidbench list` prints it, e.g. ``"[0, r1 + r2)"``.
    range : callable
        Resolved parameters -> the `Range` in SI units.
    needs : tuple of str
        The parameters it depends on (a census draws those first).
    """

    text: str
    range: Callable[[Mapping[str, Value]], Range]
    needs: tuple[str, ...] = ()

    def __str__(self) -> str:
        return self.text


@dataclass(frozen=True)
class Param:
    """One public, named scenario parameter.

    Attributes
    ----------
    name : str
        Public name (``--set name=value``, ``options={"params": {name: value}}``).
    unit : str
        SI unit of the value, e.g. ``"kg m^2"``; ``"1"`` for dimensionless.
    doc : str
        One sentence: what the number is, with its convention (frame, reference point, sign).
    valid : Range
        Valid range for each component.
    target : Target
        Where the value lives in the model.
    size : int
        Number of components (3 for a vector such as a body-frame angular velocity).
    integer : bool
        Whether each component must be a whole number (a count, e.g. the number of pendulums in a chain).
    within : Bound, optional
        A further range that depends on other parameters (checked by `Scenario.resolve` once every parameter
        is known), e.g. a strike point on the stick: ``(0, L/2]``.
    budget : bool
        A sample count or a resolution (Monte Carlo samples, steps per contact) rather than a physical quantity:
        larger values cost more and only tighten statistics or resolution. A census draws it between its lower
        end and its default (`rigidbench.census`), so a census costs what a run costs.
    """

    name: str
    unit: str
    doc: str
    valid: Range
    target: Target
    size: int = 1
    integer: bool = False
    within: Bound | None = None
    budget: bool = False

    def parse(self, text: str) -> Value:
        """Parse a command-line value (``"0.3"`` or ``"0.1,5,0.1"``) and validate it.

        Raises
        ------
        ValueError
            If the text is not a number (or comma-separated numbers) or the value is invalid.
        """
        try:
            parts = [float(p) for p in text.split(",")]
        except ValueError:
            raise ValueError(f"parameter '{self.name}': cannot read {text!r} as {self._shape_words()}") from None
        return self.check(parts[0] if len(parts) == 1 else parts)

    def check(self, value: object) -> Value:
        """Return `value` as a float (or tuple of floats) after checking type, shape, finiteness and range.

        Raises
        ------
        ValueError
            Naming the parameter, the value and the valid range.
        """
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"parameter '{self.name}': expected {self._shape_words()}, got {value!r}") from None
        if arr.size != self.size or (self.size == 1 and arr.ndim > 1):
            raise ValueError(f"parameter '{self.name}': expected {self._shape_words()}, got {value!r}")
        for x in arr.ravel():
            if not math.isfinite(x):
                raise ValueError(f"parameter '{self.name}' = {value!r} is not finite")
            if x not in self.valid or (self.integer and x != round(x)):
                kind = "integers in " if self.integer else ""
                unit = "" if self.unit == "1" else f" {self.unit}"  # no unit printed for a pure number
                raise ValueError(
                    f"parameter '{self.name}' = {_fmt(value)}{unit} is outside the valid range {kind}{self.valid}{unit}"
                )
        return _unwrap(arr)

    def check_within(self, value: Value, values: Mapping[str, Value]) -> None:
        """Check `value` against the dependent range `within`, evaluated on the resolved `values`.

        Raises
        ------
        ValueError
            Naming the parameter, the value and the range, in words and in numbers.
        """
        if self.within is None:
            return
        bound = self.within.range(values)
        for x in np.ravel(value):
            if float(x) not in bound:
                unit = "" if self.unit == "1" else f" {self.unit}"
                raise ValueError(
                    f"parameter '{self.name}' = {_fmt(value)}{unit} is outside its range {self.within.text} "
                    f"= {bound}{unit}"
                )

    def range_text(self) -> str:
        """The valid range as `rigidbench list` prints it: the static range, and the dependent one if any."""
        unit = "" if self.unit == "1" else f" {self.unit}"
        text = f"{self.valid}{unit}"
        return text if self.within is None else f"{text}, and in {self.within.text}"

    def _shape_words(self) -> str:
        return "a number" if self.size == 1 else f"{self.size} comma-separated numbers"


def _fmt(value: object) -> str:
    if isinstance(value, (list, tuple, np.ndarray)):
        return ",".join(f"{float(x):g}" for x in np.ravel(value))
    return f"{float(value):g}" if isinstance(value, (int, float)) else repr(value)


def __getattr__(name: str):
    """`ContactStiffness` and `ContactSteps`, whose home is now `rigidbench.contact` (with the contact model they
    read back through): their old import path here, loaded on first use so that params does not depend on it."""
    if name in ("ContactStiffness", "ContactSteps"):
        return getattr(importlib.import_module("rigidbench.contact"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def check_known(params: Sequence[Param], names: Mapping[str, object] | Sequence[str], owner: str) -> None:
    """Refuse parameter names the scenario does not have, listing the ones it does."""
    known = {p.name for p in params}
    for name in names:
        if name not in known:
            raise ValueError(f"unknown parameter '{name}' for scenario '{owner}'; valid: {', '.join(sorted(known))}")
