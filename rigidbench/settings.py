"""Simulation settings and profiles.

Settings are part of what is measured (DESIGN.md). The scenario's MJCF file holds its *reference* settings
(integrator, timestep, contact softness), each commented with the reason; a profile overrides some of them.
Whatever the profile, the settings recorded with a result are read back from the compiled model.

Profiles
--------
reference
    The model file as written: settings under which MuJoCo should reproduce the theory closely.
mujoco-default
    What a user gets by writing the model naively: MuJoCo's default integrator (Euler), 2 ms step, default
    solref/solimp on every geom and equality constraint, pyramidal friction cone. Failures here are the
    benchmark's findings.
thorough
    The reference settings with at least `THOROUGH_SAMPLES` Monte Carlo samples in statistical scenarios.

Monte Carlo sample counts: a scenario that draws samples keeps its count in ``<numeric name="samples">``
(its public parameter, e.g. ``n``, targets that entry); `Settings.samples` raises it to at least that many.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import mujoco
import numpy as np

from rigidbench.contract import MAX_ACCELERATION, round_step  # noqa: F401 (their old home; defined with the contract)


def _enum(prefix: str, enum: type, names: dict[str, str]) -> dict[str, int]:
    """Public name -> MuJoCo enum value, for the members this MuJoCo has."""
    return {
        public: getattr(enum, f"{prefix}{member}") for public, member in names.items() if hasattr(enum, prefix + member)
    }


# MJCF's names for MuJoCo's enums (`<option integrator="..." solver="..." cone="..." jacobian="...">`). MuJoCo 4.0
# adds the `discrete` integrator (first order; the constraint solve and the implicit velocity update in one step).
INTEGRATORS = _enum(
    "mjINT_",
    mujoco.mjtIntegrator,
    {"Euler": "EULER", "RK4": "RK4", "implicit": "IMPLICIT", "implicitfast": "IMPLICITFAST", "discrete": "DISCRETE"},
)
CONES = _enum("mjCONE_", mujoco.mjtCone, {"pyramidal": "PYRAMIDAL", "elliptic": "ELLIPTIC"})
SOLVERS = _enum("mjSOL_", mujoco.mjtSolver, {"PGS": "PGS", "CG": "CG", "Newton": "NEWTON"})
JACOBIANS = _enum("mjJAC_", mujoco.mjtJacobian, {"dense": "DENSE", "sparse": "SPARSE", "auto": "AUTO"})

# MuJoCo's own defaults (MJCF reference, <geom solref solimp>, <option>).
MUJOCO_DEFAULT_SOLREF = (0.02, 1.0)
MUJOCO_DEFAULT_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)
MUJOCO_DEFAULT_TIMESTEP = 0.002

# Samples in the thorough profile: a goodness-of-fit test with ~20 bins then resolves bin probabilities to ~1 %.
THOROUGH_SAMPLES = 100_000


# Largest timestep accepted (s), to catch a typo: MuJoCo accepts anything. Reference timesteps follow the parameters
# (`Scenario.reference_settings`), and the slowest the ranges allow, a 100 m pendulum at g = 1e-6 m/s^2 (period
# 17 h), steps 60 s; 1000 s leaves a sweep's ladder room above that.
MAX_TIMESTEP = 1000.0


# Name of the model's custom text holding the settings that followed the parameters (`Scenario.reference_settings`),
# as JSON: {"timestep": {"value": ..., "rule": ...}, ...}; read back into every result's settings as "derived".
DERIVED_TEXT = "rigidbench:derived"


@dataclass(frozen=True)
class Option:
    """One field of MuJoCo's ``<option>`` a user may set: its kind and the values MuJoCo means it to take.

    MuJoCo's compiler accepts almost anything here (a negative timestep, -1 iterations); these ranges are the ones
    its documentation gives the fields, so that a typo is an error rather than a silently broken run.
    """

    kind: str  # "enum", "int", "float" or "vector"
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    values: dict[str, int] | None = None
    size: int = 1

    def parse(self, name: str, value: object) -> object:
        """`value` (text from the command line, or a TOML/MJCF value) as the option's Python value.

        Raises
        ------
        ValueError
            Naming the option, the value and the valid values or range.
        """
        if self.kind == "enum":
            names = {k.lower(): k for k in self.values}
            key = str(value).strip().lower()
            if key not in names:
                raise ValueError(f"option {name} = {value!r} is not one of {', '.join(self.values)}")
            return names[key]
        if self.kind == "vector":
            parts = value if isinstance(value, (list, tuple)) else str(value).replace(",", " ").split()
            try:
                numbers = tuple(float(x) for x in parts)
            except (TypeError, ValueError):
                numbers = ()
            if len(numbers) != self.size or not all(math.isfinite(x) for x in numbers):
                raise ValueError(f"option {name} = {value!r}: expected {self.size} finite numbers")
            return numbers
        try:
            number = float(value) if not isinstance(value, bool) else math.nan
        except (TypeError, ValueError):
            number = math.nan
        if self.kind == "int" and not (math.isfinite(number) and number == round(number)):
            raise ValueError(f"option {name} = {value!r} is not an integer")
        above = number > self.low if self.low_open else number >= self.low
        if not (math.isfinite(number) and above and number <= self.high):
            bound = f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}]"
            raise ValueError(f"option {name} = {value!r} is outside its valid range {bound}")
        return int(number) if self.kind == "int" else number


_COUNT = Option("int", 0)
_TOLERANCE = Option("float", 0)
# Every field of <option> that sets how MuJoCo integrates and solves (MJCF reference, `option`). The physical
# quantities of <option> (gravity, wind, magnetic, density, viscosity) are the scenario's, not settings: a user
# changes them with --set where a scenario has them as parameters (g), never behind its theory's back.
OPTIONS: dict[str, Option] = {
    "integrator": Option("enum", values=INTEGRATORS),
    "timestep": Option("float", 0.0, MAX_TIMESTEP, low_open=True),
    "solver": Option("enum", values=SOLVERS),
    "iterations": Option("int", 1),
    "tolerance": _TOLERANCE,
    "ls_iterations": _COUNT,
    "ls_tolerance": _TOLERANCE,
    "noslip_iterations": _COUNT,
    "noslip_tolerance": _TOLERANCE,
    "ccd_iterations": _COUNT,
    "ccd_tolerance": _TOLERANCE,
    "sleep_tolerance": _TOLERANCE,
    "sdf_iterations": Option("int", 1),
    "sdf_initpoints": Option("int", 1),
    "impratio": Option("float", 0.0, low_open=True),
    "cone": Option("enum", values=CONES),
    "jacobian": Option("enum", values=JACOBIANS),
    # Values used in place of every contact's when the `override` flag is enabled.
    "o_margin": Option("float", 0),
    "o_solref": Option("vector", size=2),
    "o_solimp": Option("vector", size=5),
    "o_friction": Option("vector", size=5),
}
PHYSICAL_OPTIONS = ("gravity", "wind", "magnetic", "density", "viscosity")

# <flag NAME="enable|disable">: MuJoCo's disable bits (on by default) and enable bits (off by default).
FLAGS: dict[str, tuple[int, bool]] = {
    **{
        b.lower(): (int(getattr(mujoco.mjtDisableBit, f"mjDSBL_{b}")), False)
        for b in (
            "CONSTRAINT",
            "EQUALITY",
            "FRICTIONLOSS",
            "LIMIT",
            "CONTACT",
            "SPRING",
            "DAMPER",
            "GRAVITY",
            "CLAMPCTRL",
            "WARMSTART",
            "FILTERPARENT",
            "ACTUATION",
            "REFSAFE",
            "SENSOR",
            "MIDPHASE",
            "EULERDAMP",
            "AUTORESET",
            "NATIVECCD",
            "ISLAND",
            "MULTICCD",
        )
        if hasattr(mujoco.mjtDisableBit, f"mjDSBL_{b}")
    },
    **{
        b.lower(): (int(getattr(mujoco.mjtEnableBit, f"mjENBL_{b}")), True)
        for b in ("OVERRIDE", "ENERGY", "FWDINV", "INVDISCRETE", "SLEEP", "DIAGEXACT", "IPC", "SPECULATIVE")
        if hasattr(mujoco.mjtEnableBit, f"mjENBL_{b}")
    },
}
_ON = {"enable": True, "enabled": True, "on": True, "true": True, "1": True}
_OFF = {"disable": False, "disabled": False, "off": False, "false": False, "0": False}


def parse_flag(name: str, value: object) -> bool:
    """``enable``/``disable`` (or on/off, true/false) -> True/False.

    Raises
    ------
    ValueError
        Naming the flag and the valid words.
    """
    word = str(value).strip().lower() if not isinstance(value, bool) else str(value).lower()
    if word in _ON:
        return True
    if word in _OFF:
        return False
    raise ValueError(f"flag {name} = {value!r}: use enable or disable")


def check_solref(value: object, option: str = "solref") -> tuple[float, float]:
    """A constraint's (timeconst, dampratio), both positive, or its direct (-stiffness, -damping), both <= 0.

    Raises
    ------
    ValueError
    """
    ref = Option("vector", size=2).parse(option, value)
    if not (ref[0] > 0 and ref[1] > 0) and not (ref[0] < 0 and ref[1] <= 0):
        raise ValueError(
            f"{option} = {value!r}: give (timeconst, dampratio) > 0 or the direct (-stiffness, -damping) <= 0"
        )
    return ref


def check_solimp(value: object, option: str = "solimp") -> tuple[float, ...]:
    """A constraint's impedance (dmin, dmax, width[, midpoint, power]): dmin, dmax in (0, 1), width > 0,
    midpoint in (0, 1), power >= 1 (MJCF reference, `solimp`).

    Raises
    ------
    ValueError
    """
    parts = value if isinstance(value, (list, tuple)) else str(value).replace(",", " ").split()
    try:
        imp = tuple(float(x) for x in parts)
    except (TypeError, ValueError):
        imp = ()
    if len(imp) == 3:
        imp = (*imp, 0.5, 2.0)
    ok = (
        len(imp) == 5
        and all(math.isfinite(x) for x in imp)
        and 0 < imp[0] < 1
        and 0 < imp[1] < 1
        and imp[2] > 0
        and 0 < imp[3] < 1
        and imp[4] >= 1
    )
    if not ok:
        raise ValueError(
            f"{option} = {value!r}: give dmin, dmax, width[, midpoint, power] with dmin, dmax in (0, 1), width > 0, "
            "midpoint in (0, 1), power >= 1"
        )
    return imp


@dataclass(frozen=True)
class Settings:
    """Overrides of the model's simulation options; ``None`` (or empty) keeps what the model file says.

    A value: from a profile name or file, a user's MJCF (`from_model`), ``--option`` flags (`from_options`), merged
    in that order (`merged`), applied to a spec (`apply`) and read back in full with every result
    (`read_settings`).

    Attributes
    ----------
    integrator : {"Euler", "RK4", "implicit", "implicitfast", "discrete"} or None
    timestep : float or None
        Seconds, in (0, 0.1].
    cone : {"pyramidal", "elliptic"} or None
    solref, solimp : tuple of float or None
        Applied to every geom, explicit contact pair and equality constraint (MuJoCo's constraint softness;
        MuJoCo's defaults are the same for all three).
    samples : int or None
        Least number of Monte Carlo samples (raises the model's ``<numeric name="samples">``, if it has one).
    options : tuple of (name, value)
        Any other field of `OPTIONS` (solver, iterations, tolerance, impratio, jacobian, noslip_*, o_*, ...).
    flags : tuple of (name, bool)
        `FLAGS` set: True enables, False disables (``warmstart``, ``energy``, ``override``, ...).
    engine : {"mujoco", "warp", "mjx"} or None
        What steps the model (`rigidbench.engines`); None is C MuJoCo.
    device : str or None
        The engine's device (``"cpu"``, ``"cuda:0"``); None is the CPU.
    precision : {"float32", "float64"} or None
        The engine's float precision (MJX only has a choice; None is the engine's default).
    """

    integrator: str | None = None
    timestep: float | None = None
    cone: str | None = None
    solref: tuple[float, ...] | None = None
    solimp: tuple[float, ...] | None = None
    samples: int | None = None
    options: tuple[tuple[str, Any], ...] = ()
    flags: tuple[tuple[str, bool], ...] = ()
    engine: str | None = None
    device: str | None = None
    precision: str | None = None

    def __post_init__(self) -> None:
        if self.integrator is not None and self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator {self.integrator!r} is not one of {', '.join(INTEGRATORS)}")
        if self.timestep is not None and not 0.0 < self.timestep <= MAX_TIMESTEP:
            raise ValueError(f"timestep = {self.timestep!r} s is outside the valid range (0, {MAX_TIMESTEP}] s")
        if self.cone is not None and self.cone not in CONES:
            raise ValueError(f"cone {self.cone!r} is not one of {', '.join(CONES)}")
        if self.samples is not None and not (isinstance(self.samples, int) and self.samples >= 1):
            raise ValueError(f"samples = {self.samples!r} must be an integer >= 1")
        for name, value in self.options:
            if name not in OPTIONS or name in ("integrator", "timestep", "cone"):
                raise ValueError(f"options: {name!r} is not a settable option here")
            OPTIONS[name].parse(name, value)
        for name, _ in self.flags:
            if name not in FLAGS:
                raise ValueError(f"flag {name!r} is not one of {', '.join(FLAGS)}")
        if self.precision not in (None, "float32", "float64"):
            raise ValueError(f"precision {self.precision!r} is not float32 or float64")

    def engine_object(self):
        """The engine these settings simulate with (`rigidbench.engines.engine_for`; None: C MuJoCo).

        Raises
        ------
        ValueError
            For an unknown or uninstalled engine, or a device or precision it does not have.
        """
        from rigidbench.engines.registry import engine_for

        return engine_for(self.engine, device=self.device, precision=self.precision)

    @classmethod
    def from_options(cls, items: Mapping[str, object], flags: Mapping[str, object] | None = None) -> Settings:
        """Settings from option names and values (``--option NAME=VALUE``, a profile file's ``[option]``), where a
        flag's name (``warmstart=disable``) sets the flag, and ``solref``/``solimp`` the constraints' softness.

        Raises
        ------
        ValueError
            Naming the option or flag, with its valid values (one line).
        """
        fields: dict[str, Any] = {}
        options: dict[str, Any] = {}
        chosen: dict[str, bool] = {name: parse_flag(name, v) for name, v in (flags or {}).items() if _known_flag(name)}
        for name, value in items.items():
            key = name.strip()
            if key in PHYSICAL_OPTIONS:
                raise ValueError(
                    f"option {key} is a physical quantity of the scenario, not a setting: use --set where the scenario "
                    "has it as a parameter (g)"
                )
            if key in ("solref", "solimp"):
                fields[key] = check_solref(value) if key == "solref" else check_solimp(value)
            elif key in FLAGS:
                chosen[key] = parse_flag(key, value)
            elif key in OPTIONS:
                parsed = OPTIONS[key].parse(key, value)
                if key in ("integrator", "timestep", "cone"):
                    fields[key] = parsed
                else:
                    options[key] = parsed
            else:
                valid = ", ".join([*OPTIONS, "solref", "solimp"])
                raise ValueError(f"unknown option {key!r}; options: {valid}; flags: {', '.join(FLAGS)}")
        return cls(**fields, options=tuple(options.items()), flags=tuple(chosen.items()))

    def merged(self, other: Settings) -> Settings:
        """These settings with every field `other` sets replaced by `other`'s value (options and flags by name)."""
        changes = {k: v for k, v in vars(other).items() if v is not None and k not in ("options", "flags")}
        options = {**dict(self.options), **dict(other.options)}
        flags = {**dict(self.flags), **dict(other.flags)}
        return replace(self, **changes, options=tuple(options.items()), flags=tuple(flags.items()))

    def apply(self, spec: mujoco.MjSpec) -> None:
        """Write the overrides into `spec` (before compiling)."""
        if self.integrator is not None:
            spec.option.integrator = INTEGRATORS[self.integrator]
        if self.timestep is not None:
            spec.option.timestep = self.timestep
        if self.cone is not None:
            spec.option.cone = CONES[self.cone]
        for name, value in self.options:
            kind = OPTIONS[name]
            setattr(spec.option, name, kind.values[value] if kind.kind == "enum" else value)
        for name, on in self.flags:
            bit, enable = FLAGS[name]
            if enable:
                spec.option.enableflags = (spec.option.enableflags | bit) if on else (spec.option.enableflags & ~bit)
            else:
                spec.option.disableflags = (spec.option.disableflags & ~bit) if on else (spec.option.disableflags | bit)
        for element in (*spec.geoms, *spec.pairs, *spec.equalities):
            if self.solref is not None:
                element.solref = list(self.solref)
            if self.solimp is not None:
                element.solimp = list(self.solimp)
        samples = spec.numeric("samples")
        if self.samples is not None and samples is not None:
            samples.data = [max(float(samples.data[0]), float(self.samples))]

    def record(self) -> dict[str, Any]:
        """What was asked for (not what the model ended up with: see `read_settings`), for an error row."""
        out = {k: v for k, v in vars(self).items() if v is not None and k not in ("options", "flags")}
        out.update(dict(self.options))
        out.update({name: ("enable" if on else "disable") for name, on in self.flags})
        return out


def from_model(path: str) -> Settings:
    """The settings of a user's own MJCF (their robot): every field of `OPTIONS` of its ``<option>``, its
    ``<flag>`` bits, and the contact softness (``solref``, ``solimp``) of its default class: ``MODEL.xml`` takes the
    main class, ``MODEL.xml#CLASS`` the named one (with what it inherits).

    What cannot be carried over is refused: forces of the medium (``density``, ``viscosity``, ``wind``), which the
    scenarios' theories do not have; a gravity other than MuJoCo's default, which is a scenario parameter
    (``--set g=...``); and, for ``MODEL.xml`` alone, a model whose default classes give contacts different softness
    (name the class to take).

    Raises
    ------
    ValueError
        Naming the file and what cannot be carried over (one line).
    """
    file, _, cls = path.partition("#")
    try:
        spec = mujoco.MjSpec.from_file(file)
    except (ValueError, OSError) as exc:
        raise ValueError(f"--settings-from {file}: MuJoCo cannot read it ({' '.join(str(exc).split())})") from None
    reference = mujoco.MjSpec().option
    opt = spec.option
    for name in ("density", "viscosity", "wind"):
        if np.any(np.asarray(getattr(opt, name)) != np.asarray(getattr(reference, name))):
            raise ValueError(
                f"--settings-from {file}: option {name} = {getattr(opt, name)} adds forces of a medium that the "
                "scenarios' theories do not have; it cannot be carried over"
            )
    if np.any(np.asarray(opt.gravity) != np.asarray(reference.gravity)):
        raise ValueError(
            f"--settings-from {file}: gravity {tuple(opt.gravity)} is the scenario's, not a setting; it cannot be "
            "carried over (use --set g=... where a scenario has g)"
        )
    options: dict[str, Any] = {}
    fields: dict[str, Any] = {}
    for name, kind in OPTIONS.items():
        value = getattr(opt, name)
        if kind.kind == "enum":
            value = {int(v): k for k, v in kind.values.items()}[int(value)]
        elif kind.kind == "vector":
            value = tuple(float(x) for x in value)
        value = kind.parse(name, value)
        if name in ("integrator", "timestep", "cone"):
            fields[name] = value
        else:
            options[name] = value
    flags = {
        name: bool(opt.enableflags & bit) if enable else not opt.disableflags & bit
        for name, (bit, enable) in FLAGS.items()
    }
    if cls:
        default = spec.find_default(cls)
        if default is None:
            raise ValueError(f"--settings-from {path}: the model has no default class {cls!r}")
    else:
        default = spec.default
        softness = {
            name: (tuple(d.geom.solref), tuple(d.geom.solimp))
            for name in _default_classes(file)
            if (d := spec.find_default(name)) is not None
        }
        if len(set(softness.values()) | {(tuple(default.geom.solref), tuple(default.geom.solimp))}) > 1:
            raise ValueError(
                f"--settings-from {file}: its default classes give contacts different softness "
                f"({', '.join(sorted(softness))}); name the one to carry over: {file}#CLASS"
            )
    fields["solref"] = check_solref(tuple(float(x) for x in default.geom.solref))
    fields["solimp"] = check_solimp(tuple(float(x) for x in default.geom.solimp))
    return Settings(**fields, options=tuple(options.items()), flags=tuple(flags.items()))


def _default_classes(path: str, seen: set[str] | None = None) -> list[str]:
    """The names of the default classes an MJCF file (and the files it includes) defines."""
    import xml.etree.ElementTree as ET

    seen = seen if seen is not None else set()
    real = os.path.realpath(path)
    if real in seen:
        return []
    seen.add(real)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return []
    names = [e.get("class") for e in root.iter("default") if e.get("class")]
    for include in root.iter("include"):
        if include.get("file"):
            names += _default_classes(os.path.join(os.path.dirname(path), include.get("file")), seen)
    return names


def _known_flag(name: str) -> bool:
    if name not in FLAGS:
        raise ValueError(f"flag {name!r} is not one of {', '.join(FLAGS)}")
    return True


PROFILES: dict[str, Settings] = {
    "reference": Settings(),
    "mujoco-default": Settings(
        integrator="Euler",
        timestep=MUJOCO_DEFAULT_TIMESTEP,
        cone="pyramidal",
        solref=MUJOCO_DEFAULT_SOLREF,
        solimp=MUJOCO_DEFAULT_SOLIMP,
    ),
    "thorough": Settings(samples=THOROUGH_SAMPLES),
}
# Profiles shipped as files (`rigidbench/profiles/*.toml`): configurations people run, to put under the benchmark.
PROFILE_DIR = "profiles"


def profile_files() -> dict[str, str]:
    """The shipped profile files, by name (their stem)."""
    import importlib.resources

    root = importlib.resources.files("rigidbench").joinpath(PROFILE_DIR)
    return {entry.name[: -len(".toml")]: str(entry) for entry in root.iterdir() if entry.name.endswith(".toml")}


def profile_names() -> list[str]:
    return [*PROFILES, *sorted(profile_files())]


def profile(name: str) -> Settings:
    """The settings of a named profile: a built-in one (`PROFILES`), a shipped profile file, or a path to a
    profile file (``*.toml``, `load_profile`).

    Raises
    ------
    ValueError
        If `name` is neither, or the file is not a valid profile (naming it).
    """
    if name in PROFILES:
        return PROFILES[name]
    files = profile_files()
    if name in files:
        return load_profile(files[name])
    if name.endswith(".toml") or os.path.sep in name or os.path.exists(name):
        return load_profile(name)
    raise ValueError(f"profile {name!r} is not one of {', '.join(profile_names())}, nor a profile file (*.toml)")


def load_profile(path: str) -> Settings:
    """A profile file: TOML with an ``[option]`` table (`OPTIONS` fields, e.g. ``solver = "Newton"``), a ``[flag]``
    table (``warmstart = "disable"``) and a ``[contact]`` table (``solref``, ``solimp``: every geom, pair and
    equality constraint), plus free-text ``name`` and ``description``.

    Raises
    ------
    ValueError
        Naming the file and what is wrong (one line).
    """
    import tomllib

    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except OSError as exc:
        raise ValueError(f"profile {path}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"profile {path}: not TOML ({exc})") from None
    unknown = sorted(set(doc) - {"name", "description", "option", "flag", "contact"})
    if unknown:
        raise ValueError(f"profile {path}: unknown table(s) {', '.join(unknown)}; use [option], [flag], [contact]")
    tables = {key: doc.get(key, {}) for key in ("option", "flag", "contact")}
    for key, table in tables.items():
        if not isinstance(table, dict):
            raise ValueError(f"profile {path}: [{key}] must be a table")
    contact = tables["contact"]
    bad = sorted(set(contact) - {"solref", "solimp"})
    if bad:
        raise ValueError(f"profile {path}: [contact] takes solref and solimp, not {', '.join(bad)}")
    try:
        return Settings.from_options({**tables["option"], **contact}, tables["flag"])
    except ValueError as exc:
        raise ValueError(f"profile {path}: {exc}") from None


# Pipeline stages a model can switch off (MuJoCo's disable flags), by the name recorded with results.
STAGES = {"contact": mujoco.mjtDisableBit.mjDSBL_CONTACT, "constraint": mujoco.mjtDisableBit.mjDSBL_CONSTRAINT}


def idle_stages(model: mujoco.MjModel) -> tuple[str, ...]:
    """The pipeline stages that can do nothing in `model`, so that skipping them changes no result.

    ``contact``: no two geoms of different bodies have matching contype/conaffinity bits, and there is no
    explicit ``<pair>`` and no flex (conservative: MuJoCo's parent-child and static-body filters are ignored).
    ``constraint``: besides no contact, no equality, no joint or tendon limit and no friction loss.

    Measured (mujoco 4.0, RK4): collision detection over geoms that cannot collide still costs ~0.3 us per
    force evaluation, and the empty constraint stage ~0.1 us: 20-30 % of a pendulum's or a top's step.
    Skipping both leaves every state bit for bit the same (tests/test_settings.py checks every scenario).
    """
    contype, conaffinity, body = model.geom_contype, model.geom_conaffinity, model.geom_bodyid
    pairs = (np.bitwise_and.outer(contype, conaffinity) | np.bitwise_and.outer(conaffinity, contype)) != 0
    collides = bool(model.npair or model.nflex or (pairs & (body[:, None] != body[None, :])).any())
    constrained = collides or bool(
        model.neq
        or model.jnt_limited.any()
        or model.tendon_limited.any()
        or (model.dof_frictionloss > 0).any()
        or (model.tendon_frictionloss > 0).any()
    )
    return (() if collides else ("contact",)) + (() if constrained else ("constraint",))


def skip_idle_stages(model: mujoco.MjModel) -> None:
    """Switch off the stages `idle_stages` finds (in place). Call it again after editing the model's contacts,
    limits, equalities or friction loss: a stage once skipped stays skipped."""
    for stage in idle_stages(model):
        model.opt.disableflags |= STAGES[stage]


def read_settings(model: mujoco.MjModel) -> dict:
    """The settings a compiled model actually uses, in full, for the results record (values immutable): every
    field of `OPTIONS`, the flags that differ from MuJoCo's defaults (``disabled``, ``enabled``), the softness of
    the contacts, the settings that followed the parameters (``derived``) and the MuJoCo version."""
    opt = model.opt
    out: dict[str, Any] = {}
    for name, kind in OPTIONS.items():
        value = getattr(opt, name)
        if kind.kind == "enum":
            names = {int(v): k for k, v in kind.values.items()}
            out[name] = names.get(int(value), str(int(value)))
        elif kind.kind == "vector":
            out[name] = tuple(float(x) for x in value)
        else:
            out[name] = int(value) if kind.kind == "int" else float(value)
    out["mujoco"] = mujoco.__version__
    out["disabled"] = tuple(name for name, (bit, enable) in FLAGS.items() if not enable and opt.disableflags & bit)
    out["enabled"] = tuple(name for name, (bit, enable) in FLAGS.items() if enable and opt.enableflags & bit)
    derived = _custom_text(model, DERIVED_TEXT)
    if derived is not None:
        out["derived"] = json.loads(derived)
    contact = [i for i in range(model.ngeom) if model.geom_contype[i] or model.geom_conaffinity[i]]
    if contact:
        out["solref"] = tuple(sorted({tuple(float(x) for x in model.geom_solref[i]) for i in contact}))
        out["solimp"] = tuple(sorted({tuple(float(x) for x in model.geom_solimp[i]) for i in contact}))
    return out


def _custom_text(model: mujoco.MjModel, name: str) -> str | None:
    """The data of the model's custom text `name`, or None if it has none."""
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXT, name)
    if i < 0:
        return None
    start, size = int(model.text_adr[i]), int(model.text_size[i])
    return bytes(model.text_data[start : start + size]).rstrip(b"\0").decode()
