"""MJX (`mujoco.mjx`, JAX): float32 by default or float64 (``jax_enable_x64``), on JAX's CPU or a GPU.

`MjxEngine.rollout` steps the worlds of a request (`rigidbench.engines.batching`: gathered with other cases' of
the same model structure, `MjxEngine._structure`) in one compiled program, `jax.vmap` over the worlds of
`jax.lax.scan` over the steps (`_mjx_batch`), compiled once per model structure, batch size and run length. Its
programs are traced with float32's own matrix products (`matmul_precision`). JAX and MJX are imported on first
use, never at import of this module.
"""

from __future__ import annotations

import functools
import os
import threading
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from rigidbench import forces
from rigidbench.engines.base import STATE, Engine, EngineRefused, _layout
from rigidbench.engines.batching import _finish_all, _Request, _rollout_request, _stacked_controls


@dataclass(frozen=True)
class MjxEngine(Engine):
    """MJX (`mujoco.mjx`, JAX), float32 by default or float64 (``jax_enable_x64``), `jax.vmap` over the batch and
    `jax.lax.scan` over the steps (`_mjx_program`), compiled once per model structure, batch size and run length."""

    name: str = "mjx"
    precision: str = "float32"

    def version(self) -> str:
        from importlib.metadata import version

        return f"mujoco-mjx {version('mujoco-mjx')}, jax {version('jax')}"

    def _jax(self):
        import jax

        jax.config.update("jax_enable_x64", self.precision == "float64")
        return jax

    def check(self, model: mujoco.MjModel) -> None:
        forces.refuse_on(self.name, model)
        self._model_on_device(model)

    def record(self) -> dict[str, Any]:
        """`Engine.record` and the matrix-multiply precision its programs are traced with (`matmul_precision`)."""
        return {**super().record(), "matmul_precision": matmul_precision()}

    def jax_device(self):
        """JAX's device for `device` ("cpu", "cuda:1", ...: JAX's platform, then its index).

        Raises
        ------
        ValueError
            Naming the devices JAX sees, where it has no such device.
        """
        jax = self._jax()
        platform, _, index = self.device.partition(":")
        try:
            return jax.devices(platform)[int(index or 0)]
        except (RuntimeError, IndexError, ValueError):
            available = ", ".join(f"{d.platform}:{d.id}" for d in jax.devices())
            raise ValueError(f"engine mjx has no device {self.device!r} here (JAX sees {available})") from None

    def _model_on_device(self, model: mujoco.MjModel):
        from mujoco import mjx

        device = self.jax_device()
        try:
            return mjx.put_model(model, device=device)
        except NotImplementedError as exc:
            raise EngineRefused(f"engine mjx cannot simulate this model: {_feature(exc)}") from None

    def rollout(
        self, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None = None
    ) -> np.ndarray:
        """One world per initial state. Inside a gathering (`Gather`: a run's concurrent cases) the rollout waits
        for the others' and runs with every one of the same model structure as one batch."""
        return _rollout_request(self, model, states0, nstep, control)

    def _batch(self, part: list[_Request]) -> None:
        with _MJX_LOCK:  # one program at a time: see `_MJX_LOCK`
            _mjx_batch(part)

    def _structure(self, model: mujoco.MjModel):
        """The model on the device as a flat list of arrays, and its tree structure (static fields included: the
        integrator, the collision functions), which decides what can share a compiled program."""
        jax = self._jax()
        m = self._model_on_device(model)
        # MJX keeps the model's integer and bookkeeping arrays as static (numpy) fields of the program; a few of them
        # are data no step reads but a draw's parameters set (the initial condition in `numeric_data`, the size of a
        # site drawn on a body, keyframes, sensor cutoffs). They are zeroed in what is stepped, so draws differing
        # only there share a program; a static field the physics reads keeps them apart.
        unread = {name: np.zeros_like(getattr(m, name)) for name in _UNSTEPPED if hasattr(m, name)}
        impl = getattr(m, "_impl", None)
        if model.nhfield == 0 and hasattr(impl, "geom_rbound_hfield"):
            # the geoms' bounding radii, static for MJX's height-field collisions only (`collision_driver`)
            unread["_impl"] = impl.replace(geom_rbound_hfield=np.zeros_like(impl.geom_rbound_hfield))
        leaves, treedef = jax.tree_util.tree_flatten(m.replace(**unread))
        if _collides(model):
            # A model with contacts shares a batch only with models of the same arrays. MJX's program with the
            # model's arrays stacked per world never returned for the cross-section's colliding spheres on this CPU
            # (every XLA thread idle, the result never set), also in slices of 128 worlds (3 of 3 runs); the program
            # sharing one model does the same only intermittently, and not in such slices (`MJX_CONTACT_WORLDS`).
            return leaves, (treedef, b"".join(np.asarray(x).tobytes() for x in leaves))
        return leaves, treedef


# Two cases running MJX programs at once (the runner's two threads, both in cross-section beams) hung a full `run
# --engine mjx` on this 2-core CPU: both threads and XLA's two CPU pool threads waiting on futexes, the process idle
# for 28 min (py-spy: both in `MjxEngine.rollout`'s program call). MJX steps a whole batch in one program anyway
# (vmap), so its rollouts run one at a time.
_MJX_LOCK = threading.RLock()


# Static fields of an `mjx.Model` that no step reads (`MjxEngine._structure`).
_UNSTEPPED = (
    "numeric_data",
    "site_size",
    "sensor_cutoff",
    "cam_resolution",
    "cam_sensorsize",
    "key_time",
    "key_qpos",
    "key_qvel",
    "key_act",
    "key_mpos",
    "key_mquat",
    "key_ctrl",
    "tuple_objprm",
)


def _collides(model: mujoco.MjModel) -> bool:
    """Whether any two geoms of the model can collide (contacts enabled, some contype/conaffinity pair matching)."""
    if model.opt.disableflags & (mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT):
        return False
    if model.npair:
        return True
    contype, conaffinity = model.geom_contype, model.geom_conaffinity
    return bool(((contype[:, None] & conaffinity[None, :]) | (conaffinity[:, None] & contype[None, :])).any())


def _feature(exc: NotImplementedError) -> str:
    """MJX's refusal names the feature as an enum (``mjtSolver.mjSOL_PGS``); say it in words too."""
    text = str(exc)
    words = {"mjSOL_PGS": "the PGS solver", "mjINT_IMPLICIT": "the implicit integrator"}
    for key, word in words.items():
        if key in text:
            return f"{word} is not implemented ({text})"
    return text


# The most worlds of a colliding model one MJX program steps at once (`_mjx_batch`). On this CPU (jaxlib 0.10.2) the
# program of the cross-section's colliding spheres intermittently never completed for a few hundred worlds and more,
# with every XLA thread idle and the result never set: 990 worlds x 9 steps hung 5 of 9 runs, and 0 of 9 in these
# slices (`benchmarks/mjx_contact_hang.py`); 534 worlds 1 of 5 (3 of 4 with `--xla_cpu_multi_thread_eigen=false`);
# 99-123 worlds 0 of 13. Models without contacts have not hung, nor have contacts on a GPU, where a batch is left
# whole. Narrowed (2026-11-26 (e), `--plain`): MJX alone, jit(vmap(scan(mjx.step))) of the same worlds hung 4 of 13
# runs with the MJX model a jit argument (as here, so that one compiled program serves every model of a structure)
# and 0 of 13 with it closed over as a constant.
MJX_CONTACT_WORLDS = 128


def _mjx_batch(part: list[_Request]) -> None:
    """Requests of one model structure as one MJX program: `jax.vmap` over every world of every request (each world
    picking its own model's arrays, so timesteps, masses and sizes may differ) of `jax.lax.scan` over the steps of
    the longest; each request gets its own first steps back, float64, its clock `clock`."""
    first = part[0]
    with first.engine._jax().default_device(first.engine.jax_device()):
        _mjx_batch_on_device(part)


def _mjx_batch_on_device(part: list[_Request]) -> None:
    """`_mjx_batch` with JAX's default device the engine's: the start, the inputs and the model on one device (a
    start left on JAX's default device, a GPU, beside a model on the CPU asked for was an error)."""
    first = part[0]
    engine, model = first.engine, first.model
    jax = engine._jax()
    from jax import numpy as jp
    from mujoco import mjx

    dtype = jp.float64 if engine.precision == "float64" else jp.float32
    nstep = max(r.nstep for r in part)
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, first.states0[0], STATE)
    # put_data keeps MuJoCo's int32 contact indices; under jax_enable_x64 a step returns them as int64, which
    # `scan` refuses as a carry: give every array of the start the dtype a step gives it.
    treedef = first.key[1][0] if isinstance(first.key[1], tuple) else first.key[1]  # (treedef, arrays) if it collides
    m0 = jax.tree_util.tree_unflatten(treedef, first.leaves)
    d0 = mjx.put_data(model, data, device=engine.jax_device())  # put_data commits to device 0 otherwise
    shapes = jax.eval_shape(lambda d: mjx.step(m0, d), d0)
    d0 = jax.tree_util.tree_map(lambda x, like: jp.asarray(x, like.dtype), d0, shapes)
    stacked = [jp.stack(column) for column in zip(*(r.leaves for r in part), strict=True)]
    which = np.concatenate([np.full(len(r.states0), i) for i, r in enumerate(part)])
    states0 = np.concatenate([r.states0 for r in part])
    controls = _stacked_controls(part, nstep, model.nu)
    controls = np.zeros((len(states0), nstep, model.nu)) if controls is None else controls
    t, q, v = _layout(model)
    shared = len(part) == 1 or all(_same_arrays(r.leaves, first.leaves) for r in part[1:])
    program = _mjx_shared_program() if shared else _mjx_program(treedef)
    states = np.repeat(states0[:, None, :], nstep, axis=1)
    # Colliding models run in slices of `MJX_CONTACT_WORLDS` worlds (the last padded with copies of its first world,
    # so every slice reuses one compiled program): see `MJX_CONTACT_WORLDS`.
    on_cpu = engine.device.partition(":")[0] == "cpu"
    width = MJX_CONTACT_WORLDS if on_cpu and _collides(model) else len(states0)
    for lo in range(0, len(states0), width):
        rows = np.arange(lo, min(lo + width, len(states0)))
        pad = np.concatenate([rows, np.full(width - len(rows), lo)]) if len(states0) > width else rows
        start = [jp.asarray(states0[pad][:, column], dtype) for column in (0, q, v)]  # time, qpos, qvel
        inputs = (*start, jp.asarray(controls[pad], dtype))
        if shared:  # one model for every world: the program with the model shared, not stacked
            qpos, qvel = program(m0, d0, *inputs)
        else:
            qpos, qvel = program(stacked, jp.asarray(which[pad]), d0, *inputs)
        block = states[lo : lo + len(rows)]  # a view
        block[:, :, q], block[:, :, v] = np.asarray(qpos)[: len(rows)], np.asarray(qvel)[: len(rows)]
    _finish_all(part, states)  # each request's clock from its own timestep, not MJX's float32 `time`: see `clock`


def _same_arrays(a: list, b: list) -> bool:
    return all(np.array_equal(np.asarray(x), np.asarray(y)) for x, y in zip(a, b, strict=True))


def matmul_precision() -> str:
    """The matrix-multiply precision rigidbench's MJX programs are traced with (`jax.default_matmul_precision`, set
    inside each program, so a user's own JAX code keeps its own): float32's own, "highest", unless the environment's
    ``JAX_DEFAULT_MATMUL_PRECISION`` names another.

    On an NVIDIA H100, JAX's default lets float32 matrix products run in TF32 (a 10-bit mantissa): a light projectile
    (m2 / m1 = 9.3e3) then kept its momentum to 3.06e-4, against 6.8e-7 with "highest" and the float32 floor's
    4.5e-5 (docs/engines.md). The floors are float32's, so the programs run float32. A CPU has no TF32.
    """
    return os.environ.get("JAX_DEFAULT_MATMUL_PRECISION") or "highest"


def _mjx_scan(m, d0, time, qpos, qvel, controls):
    """One world's rollout inside a jitted program: `jax.lax.scan` of `mjx.step` over the controls from `d0` at
    (time, qpos, qvel); the qpos and qvel after each step."""
    import jax
    from mujoco import mjx

    def body(d, c):
        d = mjx.step(m, d.replace(ctrl=c))
        return d, (d.qpos, d.qvel)

    with jax.default_matmul_precision(matmul_precision()):
        return jax.lax.scan(body, d0.replace(time=time, qpos=qpos, qvel=qvel), controls)[1]


@functools.cache
def _mjx_shared_program():
    """The batched MJX rollout of one model: `jax.vmap` of `_mjx_scan` over the worlds, the model an argument shared
    by every world (not closed over, so every call of the same shapes reuses the compiled program)."""
    import jax

    def run(m, d0, time, qpos, qvel, controls):
        return jax.vmap(lambda *world: _mjx_scan(m, d0, *world))(time, qpos, qvel, controls)

    return jax.jit(run)


@functools.cache
def _mjx_program(m_def):
    """The batched MJX rollout of models of one structure (`m_def`), jitted once (and again for each new shape):
    `jax.vmap` of `_mjx_scan` over the worlds, each taking its model's arrays from the stacked ones (`which`). The
    models and the start are arguments, not closed over, so JAX reuses the compiled program for every call of the
    same shapes."""
    import jax

    def run(stacked, which, d0, time, qpos, qvel, controls):
        def one(i, *world):
            return _mjx_scan(jax.tree_util.tree_unflatten(m_def, [leaf[i] for leaf in stacked]), d0, *world)

        return jax.vmap(one)(which, time, qpos, qvel, controls)

    return jax.jit(run)
