"""Forces MuJoCo has no element for, added inside its passive-force stage, so every stage of RK4 sees them.

MuJoCo has no inverse-square force between bodies (no element, no first-party plugin), and a tendon or actuator
force is at most affine in the length. The route kept here is MuJoCo's passive-force callback
(``mjcb_passive``): `mj_passive` calls it inside every `mj_forward`, so RK4 evaluates the force at each of its
four stages from the stage's own positions, and `mj_step` and `mujoco.rollout` see it (`mujoco.batch` refuses to
step at all while a Python callback is installed, for any model: `rigidbench.engines.CWorlds` then steps its worlds
one at a time). A
force written into ``xfrc_applied`` between steps from Python is instead held constant over each step, which makes
any integrator first order in it (`tests/test_forces.py` measures both). A compiled plugin would avoid Python
but needs a C toolchain and MuJoCo's headers at install time, which a pip install of this package must not.

What the route costs (measured on this 2-core machine, `tests/test_forces.py` keeps the figures honest):

- the callback is Python, so each `mj_forward` pays a Python call: about 9 us per RK4 stage for one pair;
- it holds the GIL, so `mujoco.rollout` on several threads serialises on it (several times slower than one
  thread): `threads_for` gives one thread to a model that declares a force here;
- a copied model (``copy.copy``, pickling) is a new model that `attach` has not seen: it steps without the force
  until attached (the envs' ``__setstate__`` and the simulation seams attach what they step);
- ``mjcb_passive`` is global to the process. It is installed only while a model declaring a force is alive
  (`attach`, called where rigidbench compiles or steps a model) and removed with the last such model; while
  installed, every other model's `mj_forward` pays a cheap lookup and returns. Another library's passive callback
  is never overwritten: `attach` refuses, naming it.

A model declares its forces in MJCF custom elements, so the model file carries its own physics::

    <custom>
      <!-- pairs of body names (2n names) and one strength k per pair (N m^2): the second body of a pair feels
           F = k r / |r|^3, r from the first body's centre of mass to the second's; the first feels -F.
           k > 0 repels (Coulomb, q1 q2 / (4 pi eps0)), k < 0 attracts (gravity, -G m1 m2). -->
      <text name="rigidbench:inverse-square" data="target projectile"/>
      <numeric name="rigidbench:inverse-square" data="1.0"/>
    </custom>

The batched engines (MuJoCo Warp, MJX) have no passive-force callback and refuse such a model before simulating
(`refuse_on`).

``rigidbench:power-law`` (`PowerLaw`) generalises it to central terms ``|F| = |k| / r^n`` of any exponent, several
per pair (docs/theory.md K5, K6; the central-force scenario).

The third law, ``rigidbench:frame-field`` (`FrameField`), is a uniform field fixed in a body's axes: gravity
that turns with a rotating platform (the Foucault pendulum, the eastward deflection), where MuJoCo's gravity is
fixed in the world.
"""

from __future__ import annotations

import ctypes
import functools
import glob
import math
import os
import threading
import weakref
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

INVERSE_SQUARE = "rigidbench:inverse-square"


@dataclass(frozen=True)
class InverseSquare:
    """The inverse-square pairs of a model: body ids ``first``, ``second`` and strengths ``k`` (N m^2).

    ``free_dofs``: where every body of the pairs is a free body with its centre of mass at its origin and in one
    pair only, the three translational dofs of each (``first``'s, then ``second``'s, flattened), where a force is
    its own generalised force (one vectorised add, for Monte Carlo models with many pairs); None otherwise
    (`mujoco.mj_applyFT` per body).
    """

    first: np.ndarray
    second: np.ndarray
    k: np.ndarray
    free_dofs: tuple[np.ndarray, np.ndarray] | None = None

    def forces(self, xipos: np.ndarray) -> np.ndarray:
        """The force on each pair's second body (N, world frame), shape (npair, 3); the first feels minus it."""
        r = xipos[self.second] - xipos[self.first]
        dist = np.sqrt(np.einsum("ij,ij->i", r, r))
        # A coincident pair (the model's qpos0 before a scenario places its bodies, e.g. when dm_control resets a
        # physics) has no direction: no force, rather than NaN in qfrc_passive.
        scale = np.divide(self.k, dist**3, out=np.zeros_like(dist), where=dist > 0)
        return scale[:, None] * r

    def potential_energy(self, xipos: np.ndarray) -> float:
        """sum of k / |r| over the pairs (J)."""
        r = xipos[self.second] - xipos[self.first]
        return float(np.sum(self.k / np.sqrt(np.einsum("ij,ij->i", r, r))))

    def apply(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Add the pair forces, at each body's centre of mass, to ``data.qfrc_passive``."""
        f = self.forces(data.xipos)
        if self.free_dofs is not None:
            a, b = self.free_dofs  # each dof once (`_free_dofs`), so a fancy-indexed add is exact
            data.qfrc_passive[a] -= f.ravel()
            data.qfrc_passive[b] += f.ravel()
            return
        zero = np.zeros(3)
        for a, b, fb in zip(self.first, self.second, f, strict=True):
            mujoco.mj_applyFT(model, data, fb, zero, data.xipos[b], int(b), data.qfrc_passive)
            mujoco.mj_applyFT(model, data, -fb, zero, data.xipos[a], int(a), data.qfrc_passive)


def _custom(model: mujoco.MjModel, obj: mujoco.mjtObj, name: str) -> int:
    return mujoco.mj_name2id(model, obj, name)


def inverse_square(model: mujoco.MjModel) -> InverseSquare | None:
    """The model's inverse-square pairs, or None if it declares none.

    Raises
    ------
    ValueError
        If the declaration is malformed: an odd number of names, an unknown or world body, a pair of one body,
        a strength count that differs from the pair count, or a zero or non-finite strength.
    """
    it = _custom(model, mujoco.mjtObj.mjOBJ_TEXT, INVERSE_SQUARE)
    if it < 0:
        return None
    first, second = _pairs(model, it, INVERSE_SQUARE)
    inum = _custom(model, mujoco.mjtObj.mjOBJ_NUMERIC, INVERSE_SQUARE)
    if inum < 0:
        raise ValueError(f"custom numeric {INVERSE_SQUARE!r} (the strengths, N m^2) is missing")
    adr, size = model.numeric_adr[inum], model.numeric_size[inum]
    k = np.array(model.numeric_data[adr : adr + size], dtype=float)
    if len(k) != len(first):
        raise ValueError(f"custom numeric {INVERSE_SQUARE!r} has {len(k)} strengths for {len(first)} pairs")
    if not np.all(np.isfinite(k)) or np.any(k == 0):
        raise ValueError(f"custom numeric {INVERSE_SQUARE!r}: every strength must be finite and nonzero, got {k}")
    return InverseSquare(first, second, k, _free_dofs(model, first, second))


def _pairs(model: mujoco.MjModel, text: int, law: str) -> tuple[np.ndarray, np.ndarray]:
    """The body ids (first, second) of the pairs listed by custom text `text` of law `law`, validated."""
    adr, size = model.text_adr[text], model.text_size[text]
    names = bytes(model.text_data[adr : adr + size - 1]).decode().split()
    if not names or len(names) % 2:
        raise ValueError(f"custom text {law!r} must list pairs of body names, got {names}")
    ids = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in names])
    for n, i in zip(names, ids, strict=True):
        if i <= 0:
            raise ValueError(f"custom text {law!r}: {n!r} is not a body of the model (or is the world)")
    first, second = ids[0::2], ids[1::2]
    if np.any(first == second):
        raise ValueError(f"custom text {law!r}: a pair names one body twice")
    return first, second


def _free_dofs(model: mujoco.MjModel, first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    def dof(body: int) -> int | None:
        j = model.body_jntadr[body]
        free = model.body_jntnum[body] == 1 and model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE
        return int(model.jnt_dofadr[j]) if free and not np.any(model.body_ipos[body]) else None

    if len(set(first) | set(second)) != 2 * len(first):
        return None  # a body in several pairs: mj_applyFT accumulates
    dofs = [[dof(b) for b in bodies] for bodies in (first, second)]
    if any(d is None for ds in dofs for d in ds):
        return None
    return tuple((np.array(ds)[:, None] + np.arange(3)).ravel() for ds in dofs)


POWER_LAW = "rigidbench:power-law"
POWER_LAW_EXPONENT = "rigidbench:power-law-exponent"


@dataclass(frozen=True)
class PowerLaw:
    """Central power-law terms between pairs of bodies: the second body of term i feels ``F = k_i r / |r|^(n_i + 1)``
    (magnitude ``|k_i| / |r|^n_i``; ``k_i < 0`` attracts), r from the first body's centre of mass to the second's;
    the first feels -F. A pair may carry several terms (an inverse square and an ``r^-4`` correction, docs/theory.md
    K6); a term of strength 0 exerts nothing.

    Declared as ``<text name="rigidbench:power-law" data="a b [a b ...]"/>`` (one pair of body names per term),
    ``<numeric name="rigidbench:power-law" data="k ..."/>`` (N m^n) and ``<numeric
    name="rigidbench:power-law-exponent" data="n ..."/>``. n = 2 is the inverse square's law (``rigidbench:
    inverse-square`` is kept for it, unchanged); the potential of a term is ``k r^(1 - n) / (n - 1)``, or ``-k ln r``
    at n = 1. Applied with `mujoco.mj_applyFT` at each body's centre of mass, so a body fixed to the world may be
    the centre.
    """

    first: np.ndarray
    second: np.ndarray
    k: np.ndarray
    n: np.ndarray

    def forces(self, xipos: np.ndarray) -> np.ndarray:
        """The force on each term's second body (N, world frame), shape (nterm, 3); the first feels minus it."""
        r = xipos[self.second] - xipos[self.first]
        dist = np.sqrt(np.einsum("ij,ij->i", r, r))
        safe = np.where(dist > 0, dist, 1.0)  # coincident bodies have no direction: no force (`InverseSquare`)
        scale = np.where(dist > 0, self.k / safe ** (self.n + 1), 0.0)
        return scale[:, None] * r

    def potential_energy(self, xipos: np.ndarray) -> float:
        """sum over the terms of k r^(1 - n) / (n - 1) (-k ln r at n = 1) (J)."""
        r = xipos[self.second] - xipos[self.first]
        dist = np.sqrt(np.einsum("ij,ij->i", r, r))
        one = self.n == 1
        u = np.where(one, -self.k * np.log(dist), self.k * dist ** (1 - self.n) / np.where(one, 1.0, self.n - 1))
        return float(np.sum(u))

    def __post_init__(self) -> None:
        # The terms grouped by pair, as Python numbers: `apply` runs at every RK4 stage, where numpy's per-call cost
        # on arrays of two terms dominated (~120 us a call, measured); one force per pair, one mj_applyFT per body.
        pairs: dict[tuple[int, int], list[tuple[float, float]]] = {}
        for a, b, k, n in zip(self.first, self.second, self.k, self.n, strict=True):
            if k != 0:
                pairs.setdefault((int(a), int(b)), []).append((float(k), -float(n) - 1))
        object.__setattr__(self, "_pairs", tuple((a, b, tuple(terms)) for (a, b), terms in pairs.items()))

    def apply(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Add the term forces, at each body's centre of mass, to ``data.qfrc_passive`` (a body welded to the world,
        such as a fixed centre, takes none: it has no dofs)."""
        zero = np.zeros(3)
        xipos = data.xipos
        for a, b, terms in self._pairs:
            r = xipos[b] - xipos[a]
            dist = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
            if dist == 0:
                continue  # coincident bodies: no direction, no force (`forces`)
            fb = sum(k * dist**p for k, p in terms) * r
            if model.body_weldid[b]:
                mujoco.mj_applyFT(model, data, fb, zero, xipos[b], b, data.qfrc_passive)
            if model.body_weldid[a]:
                mujoco.mj_applyFT(model, data, -fb, zero, xipos[a], a, data.qfrc_passive)


def power_law(model: mujoco.MjModel) -> PowerLaw | None:
    """The model's power-law terms, or None if it declares none.

    Raises
    ------
    ValueError
        If the declaration is malformed: an odd number of names, an unknown or world body, a pair of one body, a
        missing numeric, strength or exponent counts that differ from the term count, or a non-finite number.
    """
    it = _custom(model, mujoco.mjtObj.mjOBJ_TEXT, POWER_LAW)
    inum = _custom(model, mujoco.mjtObj.mjOBJ_NUMERIC, POWER_LAW)
    iexp = _custom(model, mujoco.mjtObj.mjOBJ_NUMERIC, POWER_LAW_EXPONENT)
    if it < 0 and inum < 0 and iexp < 0:
        return None
    if it < 0:
        raise ValueError(f"custom text {POWER_LAW!r} (pairs of body names, one per term) is missing")
    first, second = _pairs(model, it, POWER_LAW)
    values = []
    for name, i, unit in ((POWER_LAW, inum, "the strengths, N m^n"), (POWER_LAW_EXPONENT, iexp, "the exponents")):
        if i < 0:
            raise ValueError(f"custom numeric {name!r} ({unit}) is missing")
        adr, size = model.numeric_adr[i], model.numeric_size[i]
        v = np.array(model.numeric_data[adr : adr + size], dtype=float)
        if len(v) != len(first) or not np.all(np.isfinite(v)):
            raise ValueError(f"custom numeric {name!r} must hold {len(first)} finite numbers ({unit}), got {v}")
        values.append(v)
    return PowerLaw(first, second, *values)


FRAME_FIELD = "rigidbench:frame-field"


@dataclass(frozen=True)
class FrameField:
    """A uniform field of acceleration fixed in the frame of one body (gravity fixed in a turning platform's axes):
    body ``frame``'s axes carry the field ``field_frame`` (m/s^2), and each body of ``bodies`` feels ``m R g`` at
    its centre of mass, R its orientation now (``xmat``), m its mass. No reaction is applied to ``frame``.

    MuJoCo's own gravity is fixed in the world: a model whose "down" turns with a body declares this instead (and
    sets ``gravity="0 0 0"``). Evaluated at every RK4 stage from the stage's orientation, like the other laws.
    """

    frame: int
    bodies: np.ndarray
    mass: np.ndarray
    field_frame: np.ndarray

    def field_world(self, xmat: np.ndarray) -> np.ndarray:
        """The field in world axes (m/s^2), shape (3,), from ``data.xmat``."""
        return xmat[self.frame].reshape(3, 3) @ self.field_frame

    def apply(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Add ``m R g`` at each body's centre of mass to ``data.qfrc_passive``."""
        a = self.field_world(data.xmat)
        zero = np.zeros(3)
        for b, m in zip(self.bodies, self.mass, strict=True):
            mujoco.mj_applyFT(model, data, m * a, zero, data.xipos[b], int(b), data.qfrc_passive)


def frame_field(model: mujoco.MjModel) -> FrameField | None:
    """The model's field fixed in a body's frame, or None if it declares none.

    Declared as ``<text name="rigidbench:frame-field" data="frame body [body ...]"/>`` (the first name is the body
    whose axes carry the field, possibly ``world``; the others feel it) and ``<numeric
    name="rigidbench:frame-field" data="gx gy gz"/>`` (m/s^2, in the frame body's axes).

    Raises
    ------
    ValueError
        If the declaration is malformed: fewer than two names, an unknown body, the world or the frame among the
        bodies feeling it, a body named twice, a field that is not three finite numbers, or a missing numeric.
    """
    it = _custom(model, mujoco.mjtObj.mjOBJ_TEXT, FRAME_FIELD)
    inum = _custom(model, mujoco.mjtObj.mjOBJ_NUMERIC, FRAME_FIELD)
    if it < 0 and inum < 0:
        return None
    if it < 0:
        raise ValueError(f"custom text {FRAME_FIELD!r} (the frame body, then the bodies feeling the field) is missing")
    adr, size = model.text_adr[it], model.text_size[it]
    names = bytes(model.text_data[adr : adr + size - 1]).decode().split()
    if len(names) < 2:
        raise ValueError(f"custom text {FRAME_FIELD!r} must name the frame body and at least one body, got {names}")
    ids = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in names])
    for n, i in zip(names, ids, strict=True):
        if i < 0:
            raise ValueError(f"custom text {FRAME_FIELD!r}: {n!r} is not a body of the model")
    frame, bodies = int(ids[0]), ids[1:]
    if np.any(bodies <= 0) or np.any(bodies == frame) or len(set(bodies)) != len(bodies):
        raise ValueError(
            f"custom text {FRAME_FIELD!r}: the bodies feeling the field must be distinct moving bodies other than the "
            f"frame, got {names[1:]}"
        )
    if inum < 0:
        raise ValueError(f"custom numeric {FRAME_FIELD!r} (the field, m/s^2, in the frame body's axes) is missing")
    adr, size = model.numeric_adr[inum], model.numeric_size[inum]
    field_frame = np.array(model.numeric_data[adr : adr + size], dtype=float)
    if field_frame.shape != (3,) or not np.all(np.isfinite(field_frame)):
        raise ValueError(f"custom numeric {FRAME_FIELD!r} must be three finite numbers (m/s^2), got {field_frame}")
    return FrameField(frame, bodies, np.array(model.body_mass[bodies], dtype=float), field_frame)


# The force laws: each parses a model (None: the model declares none) into something with `apply(model, data)`.
LAWS: dict[str, Callable[[mujoco.MjModel], object | None]] = {
    INVERSE_SQUARE: inverse_square,
    POWER_LAW: power_law,
    FRAME_FIELD: frame_field,
}


def declared(model: mujoco.MjModel) -> list[str]:
    """The names of the force laws the model declares (custom elements named after a law)."""
    return [
        name
        for name in LAWS
        if _custom(model, mujoco.mjtObj.mjOBJ_TEXT, name) >= 0 or _custom(model, mujoco.mjtObj.mjOBJ_NUMERIC, name) >= 0
    ]


_LOCK = threading.Lock()
_PARSED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # model -> its parsed laws (empty: none)
_ATTACHED: weakref.WeakSet = weakref.WeakSet()  # the live models that keep the callback installed
_KNOWN: set[int] = set()  # their addresses (the raw mjModel pointers MuJoCo passes to the callback)
_CFUNC = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)
_TRAMPOLINE: list = [None]  # MuJoCo's own Python trampoline for `_passive`, called for the models in _KNOWN


def _laws(model: mujoco.MjModel) -> list:
    laws = _PARSED.get(model)
    if laws is None:
        laws = [parsed for parse in LAWS.values() if (parsed := parse(model)) is not None]
        _PARSED[model] = laws
    return laws


def _passive(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """The Python side of the callback: add the model's declared forces."""
    for law in _laws(model):
        law.apply(model, data)


def _filter(model_ptr: int, data_ptr: int) -> None:
    """What MuJoCo calls (``mjcb_passive``): the declared models go on to `_passive`, every other returns at once.

    MuJoCo's Python bindings hand a Python callable the Python objects of the raw model and data, and fail
    (``Python exception raised``) on a model that has none yet, which is every model while MuJoCo compiles it
    (the compiler runs `mj_forward` in `mj_setConst`). So the installed callback is this ctypes function, which
    MuJoCo calls with raw pointers; only a model `attach` has seen reaches the bindings' own trampoline.
    """
    if model_ptr in _KNOWN:
        _TRAMPOLINE[0](model_ptr, data_ptr)


_FILTER = _CFUNC(_filter)


@functools.cache
def _slot() -> ctypes.c_void_p:
    """MuJoCo's global ``mjcb_passive`` in the loaded libmujoco."""
    here = os.path.dirname(mujoco.__file__)
    paths = sorted(glob.glob(os.path.join(here, "libmujoco*")) + glob.glob(os.path.join(here, "mujoco.dll")))
    if not paths:
        raise RuntimeError(f"cannot find libmujoco beside {mujoco.__file__} (rigidbench.forces needs mjcb_passive)")
    return ctypes.c_void_p.in_dll(ctypes.CDLL(paths[0]), "mjcb_passive")


def _install() -> None:
    mujoco.set_mjcb_passive(_passive)  # the bindings keep `_passive` and point mjcb_passive at their trampoline
    slot = _slot()
    _TRAMPOLINE[0] = _CFUNC(slot.value)
    slot.value = ctypes.cast(_FILTER, ctypes.c_void_p).value


def _release(address: int) -> None:
    with _LOCK:
        _KNOWN.discard(address)
        if not _KNOWN and mujoco.get_mjcb_passive() is _passive:
            mujoco.set_mjcb_passive(None)


def attach(model: mujoco.MjModel) -> bool:
    """Make sure MuJoCo adds the forces `model` declares whenever it is stepped, for as long as it is alive.

    Parses the declaration (so a malformed one fails here, before simulating) and installs the passive callback
    while any such model lives. Cheap and idempotent: call it wherever a model is compiled or stepped.

    Returns
    -------
    bool
        Whether the model declares a force here.

    Raises
    ------
    ValueError
        A malformed declaration (see `inverse_square`, `power_law`, `frame_field`).
    RuntimeError
        If another passive-force callback is installed in this process (it is never overwritten).
    """
    if not declared(model):
        return False
    _laws(model)
    with _LOCK:
        if model in _ATTACHED:
            return True
        current = mujoco.get_mjcb_passive()
        if current is not None and current is not _passive:
            raise RuntimeError(
                f"another passive-force callback ({current!r}) is installed; rigidbench's forces ({declared(model)}) "
                "need mjcb_passive and never overwrite it"
            )
        if current is None:
            _install()
        _ATTACHED.add(model)
        _KNOWN.add(model._address)
        weakref.finalize(model, _release, model._address)
    return True


def threads_for(model: mujoco.MjModel, nthread: int) -> int:
    """The threads to step `model` on: one where it declares a force (the Python callback holds the GIL, so more
    threads only wait on each other), else `nthread`."""
    return 1 if declared(model) else nthread


def refuse_on(engine: str, model: mujoco.MjModel) -> None:
    """Refuse a model with declared forces on an engine that has no passive-force callback.

    Raises
    ------
    rigidbench.engines.EngineRefused
        Naming the engine and the forces.
    """
    # Imported here: loading `rigidbench.engines` loads its adapters, which import this module.
    from rigidbench.engines.base import EngineRefused

    laws = declared(model)
    if laws:
        raise EngineRefused(
            f"engine {engine} has no passive-force callback, which the model's {', '.join(laws)} force needs "
            "(rigidbench.forces; C MuJoCo runs it)"
        )
