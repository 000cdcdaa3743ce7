"""Engines: where a compiled model and initial states become trajectories (DESIGN.md "Engine").

C MuJoCo (`mujoco.rollout`) is the default. An engine is chosen by the settings (``Settings.engine``, the CLI's
``--engine``) and is in effect for the simulation of a case (`use`): `rigidbench.simulate.simulate` and
`final_states` route through the engine in effect, so scenarios, predictions and measurements never branch on it.
Trajectories always come back as float64 arrays in MuJoCo's full-physics state layout.

An engine that lacks a feature the model uses (an integrator, a solver, a contact type) refuses it before
anything is simulated (`Engine.check`: a `ValueError` naming the engine and the feature); there is no silent
fallback. Every result records the engine, its version, its device and its float precision (`Engine.record`).
"""

from __future__ import annotations

import contextlib
import contextvars
import copy
import functools
import math
import os
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


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


class CEngine(Engine):
    """C MuJoCo through `mujoco.rollout` (threaded over a batch, in C, float64)."""

    def rollout(
        self, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None = None
    ) -> np.ndarray:
        import os

        from mujoco import rollout

        from rigidbench import forces

        nbatch = len(states0)
        forces.attach(model)
        nthread = forces.threads_for(model, min(nbatch, os.cpu_count() or 1))
        datas = [mujoco.MjData(model) for _ in range(max(nthread, 1))]
        out = np.empty((nbatch, nstep, states0.shape[1]))
        kwargs = {} if control is None else {"control": control}
        rollout.rollout(model, datas if nbatch > 1 else datas[0], states0, nstep=nstep, state=out, **kwargs)
        return out


ENGINES = ("mujoco", "warp", "mjx")
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


def engine_for(name: str | None, *, device: str | None = None, precision: str | None = None) -> Engine | None:
    """The engine of that name (None or ``"mujoco"``: C MuJoCo, which needs no engine object).

    Raises
    ------
    ValueError
        For an unknown engine, or one that is not installed (naming the extra that installs it).
    """
    if name in (None, "mujoco"):
        if device not in (None, "cpu") or precision not in (None, "float64"):
            raise ValueError("engine mujoco runs on the cpu in float64 only")
        return None
    if name not in ENGINES:
        raise ValueError(f"engine {name!r} is not one of {', '.join(ENGINES)}")
    return batched_engine(name, device=device, precision=precision)


def _layout(model: mujoco.MjModel) -> tuple[slice, slice, slice]:
    """Where time, qpos and qvel sit in a full-physics state row."""
    return slice(0, 1), slice(1, 1 + model.nq), slice(1 + model.nq, 1 + model.nq + model.nv)


@dataclass(frozen=True)
class WarpEngine(Engine):
    """MuJoCo Warp (`mujoco_warp`, float32 only; GPU or CPU), one world per initial state.

    What it lacks is refused by its own `put_model` (``NotImplementedError``, turned into a refusal here), plus the
    solver settings it documents it does not honour: the PGS solver, the noslip solver, and a solver tolerance
    below 1e-6 (Warp clamps it).
    """

    name: str = "warp"
    precision: str = "float32"

    def version(self) -> str:
        from importlib.metadata import version

        return f"mujoco-warp {version('mujoco-warp')}, warp-lang {version('warp-lang')}"

    def check(self, model: mujoco.MjModel) -> None:
        from rigidbench import forces

        forces.refuse_on(self.name, model)
        if not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONSTRAINT:  # only where a solver runs
            self._check_solver(model)
        self._model_on_device(model)

    def _check_solver(self, model: mujoco.MjModel) -> None:
        if model.opt.solver == mujoco.mjtSolver.mjSOL_PGS:
            raise EngineRefused("engine warp has no PGS solver (use --option solver=Newton or CG)")
        if model.opt.noslip_iterations > 0:
            raise EngineRefused("engine warp has no noslip solver (noslip_iterations must be 0)")
        if model.opt.tolerance < 1e-6 and model.opt.tolerance != 0:
            raise EngineRefused(
                f"engine warp clamps the solver tolerance to >= 1e-6; the model asks {model.opt.tolerance:g} "
                "(use --option tolerance=1e-6 to run what Warp runs)"
            )

    def _model_on_device(self, model: mujoco.MjModel):
        wp, mjw = _warp()
        try:
            with _WARP_LOCK, wp.ScopedDevice(self.device):
                wp.init()
                return mjw.put_model(model)
        except NotImplementedError as exc:
            raise EngineRefused(f"engine warp cannot simulate this model: {exc}") from None

    def rollout(
        self, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None = None
    ) -> np.ndarray:
        """One world per initial state; K steps and their recording captured once as a Warp graph and launched
        ``nstep / K`` times (on this CPU a step launched kernel by kernel from Python costs ~11 ms, captured
        ~0.09 ms: the launches, not the physics, were the time). Inside a gathering (`Gather`) the rollout runs
        with the others' of the same model structure as one batch of worlds (`_warp_batch`)."""
        return _rollout_request(self, model, states0, nstep, control)

    def _structure(self, model: mujoco.MjModel):
        """The model on the device, and what a batch of worlds must share with it (`_warp_signature`)."""
        with _WARP_LOCK:
            m = self._model_on_device(model)
        return m, _warp_signature(model, m)

    def _batch(self, part: list[_Request]) -> None:
        with _WARP_LOCK:  # one rollout at a time: see `_WARP_LOCK`
            _warp_batch(part)

    def _rollout(
        self, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None, m
    ) -> np.ndarray:
        """`nstep` steps of one world per initial state on the device model `m` (one of `model`'s structure, its
        arrays per world where they differ, `_warp_batch`)."""
        wp, mjw = _warp()
        t, q, v = _layout(model)
        nbatch = len(states0)
        from rigidbench.warp_kernels import advance, record, set_ctrl

        with wp.ScopedDevice(self.device):
            data = mujoco.MjData(model)
            mujoco.mj_setState(model, data, states0[0], STATE)
            d = mjw.put_data(model, data, nworld=nbatch)

            def start() -> None:
                d.qpos.assign(states0[:, q].astype(np.float32))
                d.qvel.assign(states0[:, v].astype(np.float32))
                d.time.assign(states0[:, 0].astype(np.float32))

            start()
            qs = wp.zeros((nstep, nbatch, model.nq), dtype=wp.float32)
            vs = wp.zeros((nstep, nbatch, model.nv), dtype=wp.float32)
            ctrl = None
            if control is not None:
                # (world, step, control), as `set_ctrl` reads it. It was given (step, world, control), which is the
                # same memory for one world and the wrong numbers for more (a gathered batch of struck sticks).
                ctrl = wp.array(np.ascontiguousarray(control), dtype=wp.float32)
            index = wp.zeros(1, dtype=wp.int32)

            def one_step() -> None:
                if ctrl is not None:
                    wp.launch(set_ctrl, dim=(nbatch, model.nu), inputs=[ctrl, index, d.ctrl])
                mjw.step(m, d)
                wp.launch(record, dim=nbatch, inputs=[d.qpos, d.qvel, index, qs, vs])
                wp.launch(advance, dim=1, inputs=[index])  # after every world has recorded step `index`

            k = _steps_per_graph(nstep)
            one_step()  # compile and load every kernel before capturing
            index.zero_()
            start()  # the warm-up step moved the worlds: back to the start
            with wp.ScopedCapture(force_module_load=False) as capture:  # the warm-up step loaded what it needs
                for _ in range(k):
                    one_step()
            for _ in range(nstep // k):
                wp.capture_launch(capture.graph)
            for _ in range(nstep % k):
                one_step()
            wp.synchronize()
            out = np.repeat(states0[:, None, :], nstep, axis=1)
            out[:, :, q] = np.swapaxes(qs.numpy(), 0, 1)
            out[:, :, v] = np.swapaxes(vs.numpy(), 0, 1)
        return out


def _warp():
    """warp and mujoco_warp, imported with Warp's messages off (importing mujoco_warp initialises Warp, which
    prints its banner and then a line per kernel module it loads unless told to be quiet first)."""
    import warp as wp

    wp.config.quiet = True
    if hasattr(wp, "LOG_WARNING"):  # warp-lang >= 1.19 says what it logs by level: module loads are info
        wp.config.log_level = wp.LOG_WARNING
    import mujoco_warp as mjw

    return wp, mjw


# Warp compiles and loads kernels on first use and captures graphs per thread; two cases doing that at once (the
# runner's default two threads, on a fresh kernel cache) crashed the process (SIGSEGV / SIGILL in Warp's CPU graph
# replay). Warp steps all worlds of a batch in one launch anyway, so its rollouts run one at a time.
_WARP_LOCK = threading.RLock()

# Two cases running MJX programs at once (the runner's two threads, both in cross-section beams) hung a full `run
# --engine mjx` on this 2-core CPU: both threads and XLA's two CPU pool threads waiting on futexes, the process idle
# for 28 min (py-spy: both in `MjxEngine.rollout`'s program call). MJX steps a whole batch in one program anyway
# (vmap), so its rollouts run one at a time.
_MJX_LOCK = threading.RLock()


def _steps_per_graph(nstep: int) -> int:
    """Steps captured in one Warp graph: enough that launching it costs little per step, few enough that the
    remainder (stepped one by one) stays cheap."""
    return max(1, min(nstep, 32))


# The float32 round-off floor's factor: a step rounds each of the state's numbers to within eps/2 of its size, a few
# dozen operations per RK4 stage each add as much, and the roundings add up as a random walk over the run (measured
# on every check both float32 engines run: docs/engines.md); C = 10 keeps the floor above what was measured without
# making it a blanket.
ROUNDOFF_FACTOR = 10.0


def roundoff_floor(precision: str, nstep: int, scale: float, *, secular: bool = False) -> tuple[float, str]:
    """The error float `precision` alone leaves in a quantity of size `scale` after `nstep` steps, and its rule.

    Random (the default): ``C eps sqrt(N + 1) scale``, the initial state's rounding and a random walk of each step's
    (`ROUNDOFF_FACTOR`). Secular, for a coordinate that a steady motion advances by a near-constant increment every
    step (a position in uniform motion, like the clock): each addition is rounded to within half an ulp of the sum,
    the same way every step, so the error grows like the step count, at most ``(eps / 2) N scale``. 0 on float64,
    whose floor is below every tolerance.
    """
    if precision == "float64":
        return 0.0, ""
    eps = float(np.finfo(np.dtype(precision)).eps)
    if secular:
        floor = 0.5 * eps * nstep * scale
        return floor, f"(eps / 2) N x scale, eps = {eps:.3g}, N = {nstep} steps (secular), scale {scale:.3g}"
    floor = ROUNDOFF_FACTOR * eps * math.sqrt(nstep + 1) * scale
    return floor, f"{ROUNDOFF_FACTOR:g} eps sqrt(N + 1) x scale, eps = {eps:.3g}, N = {nstep} steps, scale {scale:.3g}"


def advance_error(model: mujoco.MjModel, data: mujoco.MjData, precision: str) -> tuple[float, str]:
    """The largest relative error that storing positions in `precision` puts into one step's advance of a moving
    body at `data`'s state, and a phrase naming that body and the numbers (0 and "" on float64 or with nothing
    moving).

    A translational coordinate x advanced by v dt a step is stored on a grid of spacing <= eps |x|: each step's sum
    is rounded by up to eps |x| / 2, or by the whole advance where that is less (a coordinate can stall, never go
    back). Per body (free and slide joints; the state's own coordinates, so the check covers what is simulated),
    the rounding errors of its coordinates against its advance |v| dt. Where the advance is below the grid spacing
    the body stalls: a float32 beam whose projectile, 38 m from the origin, moved 7e-9 m a step never reached its
    target (an MJX census draw of cross-section). Rotations are not covered (orientations are O(1) numbers; the
    tops carry their own floors).
    """
    if precision == "float64":
        return 0.0, ""
    eps = float(np.finfo(np.dtype(precision)).eps)
    dt = float(model.opt.timestep)
    worst, where = 0.0, ""
    for j in range(model.njnt):
        kind = int(model.jnt_type[j])
        if kind not in (int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            continue
        n = 3 if kind == int(mujoco.mjtJoint.mjJNT_FREE) else 1
        x = np.abs(data.qpos[model.jnt_qposadr[j] : model.jnt_qposadr[j] + n])
        v = np.abs(data.qvel[model.jnt_dofadr[j] : model.jnt_dofadr[j] + n])
        advance = float(np.linalg.norm(v)) * dt
        if advance == 0:
            continue
        error = float(np.linalg.norm(np.minimum(0.5 * eps * x, v * dt))) / advance
        if error > worst:
            body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.jnt_bodyid[j])) or f"#{j}"
            worst = error
            pos = ", ".join(f"{c:.3g}" for c in data.qpos[model.jnt_qposadr[j] : model.jnt_qposadr[j] + n])
            stalls = " (it can stall)" if error >= 1 else ""
            where = (
                f"body '{body}' at ({pos}) m advances |v| dt = {advance:.3g} m a step, and {precision} rounds each "
                f"coordinate x to within eps |x| / 2 (eps = {eps:.3g}): an error of {min(error, 1.0):.3g} of the "
                f"advance{stalls}"
            )
    return worst, where


STEADY_CHANGE_RULE = (
    "a steady change: a number x that a constant increment c changes every step lives on a grid of spacing <= eps |x|, "
    "and while x stays in one binade each sum is rounded the same way, so the increment it takes is off by up to "
    "eps |x| / (2 |c|) of itself, the same sign every step"
)


def steady_change_error(value: float, change: float) -> float:
    """The relative error, in units of eps, of a steady per-step `change` to a number of size `value`
    (`STEADY_CHANGE_RULE`): ``|value| / (2 |change|)``; infinite for no change. The secular floor of the clock and of
    a uniform motion's position (`roundoff_floor`) is the same mechanism; `advance_error` refuses where it stalls a
    body. A velocity under a small steady acceleration a takes a dt this way (a ball sliding at 0.043 m/s against a
    friction deceleration of 2.0e-3 m/s^2 at dt = 4e-5 s: 21.4 grid steps a step, rounded alike each step)."""
    return abs(value) / (2 * abs(change)) if change else math.inf


def stored(model: mujoco.MjModel, data: mujoco.MjData, precision: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The model and the state as an engine of `precision` stores them (`stored_model`, `stored_state`); the inputs
    themselves on float64.

    A float32 engine simulates this body, not the one asked for: rounding moves each number by up to eps/2 = 6e-8
    of itself, and a quantity that depends on a small difference of stored numbers moves much more (a rotor with
    I3 - I2 = 1.1e-5 I3 has that difference 1e-2 off). Predicting from it (`Scenario.prepare`) scores the engine's
    arithmetic, not its storage of the model; the rounded parameters are what the rows report.
    """
    if precision == "float64":
        return model, data
    rounded = stored_model(model, precision)
    return rounded, stored_state(rounded, data, precision)


def stored_model(model: mujoco.MjModel, precision: str) -> mujoco.MjModel:
    """A float64 copy of `model` with every float of it (its arrays and its options) rounded to `precision`, its
    constants recomputed (`mj_setConst`); `model` itself on float64."""
    if precision == "float64":
        return model
    dtype = np.dtype(precision)
    rounded = copy.copy(model)
    for holder in (rounded, rounded.opt):
        for name in dir(holder):
            if name.startswith("_"):
                continue
            try:
                value = getattr(holder, name)
            except Exception:  # noqa: BLE001 (a property that needs more than the model)
                continue
            if isinstance(value, np.ndarray) and value.dtype == np.float64 and value.flags.writeable:
                value[...] = value.astype(dtype)
            elif type(value) is float:
                setattr(holder, name, float(dtype.type(value)))
    mujoco.mj_setConst(rounded, mujoco.MjData(rounded))
    return rounded


def stored_state(rounded: mujoco.MjModel, data: mujoco.MjData, precision: str) -> mujoco.MjData:
    """A new MjData of `rounded` (a `stored_model`) at `data`'s state (an MjData of the same model, rounded or not)
    with every number rounded to `precision` but the time (the clock is the step count in float64, `clock`),
    derived quantities computed."""
    full = np.empty(mujoco.mj_stateSize(rounded, STATE))
    mujoco.mj_getState(rounded, data, full, STATE)
    time = full[0]
    full = full.astype(np.dtype(precision)).astype(np.float64)
    full[0] = time
    state = mujoco.MjData(rounded)
    mujoco.mj_setState(rounded, state, full, STATE)
    mujoco.mj_forward(rounded, state)
    return state


def clock(t0: np.ndarray, timestep: float, nstep: int) -> np.ndarray:
    """The time after each step, t0 + (i + 1) dt, in float64, shape (nbatch, nstep).

    A float32 engine's own clock accumulates ``t += dt`` in float32: at t = 43 s, dt = 2 ms is rounded to a multiple
    of the clock's ulp (3.8e-6 s) every step, a bias of 5e-4 of the step, which alone put the pendulum's measured
    period 1.05e-4 off on Warp and MJX float32. Nothing in rigidbench's models reads the time (controls are given
    per step), so the step count is the clock.
    """
    return np.asarray(t0, dtype=np.float64)[:, None] + timestep * np.arange(1, nstep + 1)


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
        from rigidbench import forces

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


def _collides(model: mujoco.MjModel) -> bool:
    """Whether any two geoms of the model can collide (contacts enabled, some contype/conaffinity pair matching)."""
    if model.opt.disableflags & (mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT):
        return False
    if model.npair:
        return True
    contype, conaffinity = model.geom_contype, model.geom_conaffinity
    return bool(((contype[:, None] & conaffinity[None, :]) | (conaffinity[:, None] & contype[None, :])).any())


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


def _rollout_request(
    engine: Engine, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None
) -> np.ndarray:
    """A Warp or MJX rollout: run now, or, inside a gathering (`Gather`), with the others waiting."""
    states0 = np.asarray(states0, dtype=np.float64)
    if control is not None and np.shape(control) != (len(states0), nstep, model.nu):
        # here, in the case that asked: in a gathered batch it would fail every case of the batch
        raise ValueError(f"control has shape {np.shape(control)}, expected ({len(states0)}, {nstep}, {model.nu})")
    request = _Request(engine, model, states0, int(nstep), control)
    gather = _GATHERING
    if gather is not None and gather.member():
        return gather.submit(request)
    _run_requests([request])
    if request.error is not None:
        raise request.error
    return request.result


@dataclass(eq=False)
class _Request:
    """One rollout asked of an engine: a model, its initial states, steps and controls; its result when run."""

    engine: Any  # MjxEngine or WarpEngine
    model: mujoco.MjModel
    states0: np.ndarray
    nstep: int
    control: np.ndarray | None
    result: np.ndarray | None = None
    error: BaseException | None = None
    leaves: Any = None  # the model on the device (MJX: its flat arrays; Warp: the `mjw.Model`)
    key: Any = None

    def prepare(self) -> None:
        """The model on the device and the key of what it may share a batch with: the engine, the model's
        structure (`MjxEngine._structure`, `WarpEngine._structure`), the state's fields outside time, qpos and qvel
        (one start state for every world), and the number of controls."""
        self.leaves, structure = self.engine._structure(self.model)
        t, q, v = _layout(self.model)
        rest = np.delete(self.states0[0], np.r_[t, q, v]).tobytes()
        self.key = (self.engine, structure, rest, self.model.nu)

    def finish(self, states: np.ndarray) -> None:
        """This request's worlds' states after each step (its first `nstep`), float64; its clock `clock`."""
        t = _layout(self.model)[0]
        out = np.array(states[:, : self.nstep], dtype=np.float64)  # a copy: the batch's array is let go
        out[:, :, t] = clock(self.states0[:, 0], self.model.opt.timestep, self.nstep)[..., None]
        self.result, self.leaves = out, None


# A gathered batch's recorded states (float32 qpos and qvel per world and step, on the device and again on the host)
# are kept under this many bytes: a larger group is split, its requests sorted by run length so that each part pads
# the fewest steps.
GATHER_BYTES = 1 << 30


def _run_requests(requests: list[_Request], done: Callable[[list[_Request]], None] | None = None) -> None:
    """Run requests: each group of one engine and model structure (`_Request.key`) as one batch (the engine's
    `_batch`: `_mjx_batch`, `_warp_batch`), split where its recorded states would pass `GATHER_BYTES`; every world
    stepped to the longest run of its part and each request's own steps kept. `done` is told of each part as it
    finishes (and of the requests that failed to prepare), so their cases go on while the other parts run."""
    done = done or (lambda part: None)
    groups: dict[Any, list[_Request]] = {}
    for request in requests:
        try:
            request.prepare()
        except BaseException as exc:  # noqa: BLE001 - handed back to the case that asked (a refusal, say)
            request.error = exc
            done([request])
            continue
        groups.setdefault(request.key, []).append(request)
    for group in groups.values():
        group.sort(key=lambda r: r.nstep)
        part: list[_Request] = []
        for request in group:
            width = 4 * (request.model.nq + request.model.nv)
            worlds = sum(len(r.states0) for r in part) + len(request.states0)
            if part and worlds * request.nstep * width > GATHER_BYTES:
                _run_part(part)
                done(part)
                part = []
            part.append(request)
        _run_part(part)
        done(part)


def _run_part(part: list[_Request]) -> None:
    try:
        part[0].engine._batch(part)
    except BaseException as exc:  # noqa: BLE001 - every case of the batch gets it
        for request in part:
            request.error = exc


def _stacked_controls(part: list[_Request], nstep: int, nu: int) -> np.ndarray | None:
    """Every world's controls for `nstep` steps (zeros past a request's own steps), or None if none has any."""
    if all(r.control is None for r in part):
        return None
    controls = np.zeros((sum(len(r.states0) for r in part), nstep, nu))
    row = 0
    for r in part:
        if r.control is not None:
            controls[row : row + len(r.states0), : r.nstep] = r.control
        row += len(r.states0)
    return controls


def _finish_all(part: list[_Request], states: np.ndarray) -> None:
    """Hand each request its worlds' rows of a batch's `states` (worlds, steps, state)."""
    row = 0
    for r in part:
        r.finish(states[row : row + len(r.states0)])
        row += len(r.states0)


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


# The most worlds of a colliding model one MJX program steps at once (`_mjx_batch`). On this CPU (jaxlib 0.10.2) the
# program of the cross-section's colliding spheres intermittently never completed for a few hundred worlds and more,
# with every XLA thread idle and the result never set: 990 worlds x 9 steps hung 5 of 9 runs, and 0 of 9 in these
# slices (`benchmarks/mjx_contact_hang.py`); 534 worlds 1 of 5 (3 of 4 with `--xla_cpu_multi_thread_eigen=false`);
# 99-123 worlds 0 of 13. Models without contacts have not hung, nor have contacts on a GPU, where a batch is left
# whole. Narrowed (2026-11-26 (e), `--plain`): MJX alone, jit(vmap(scan(mjx.step))) of the same worlds hung 4 of 13
# runs with the MJX model a jit argument (as here, so that one compiled program serves every model of a structure)
# and 0 of 13 with it closed over as a constant.
MJX_CONTACT_WORLDS = 128


def _warp_signature(model: mujoco.MjModel, m) -> tuple:
    """What worlds of one Warp batch must share: every field of the device model `m` but the arrays Warp keeps per
    world (a leading ``*`` dimension: masses, inertias, sizes, positions, the timestep, gravity), whose shapes only
    count. `dof_length` (not per world) is read only by sleeping islands: ignored unless the model enables sleep."""
    import dataclasses as dc

    wp, _ = _warp()
    sleeps = bool(model.opt.enableflags & mujoco.mjtEnableBit.mjENBL_SLEEP)

    def sign(value, spec, name):
        if isinstance(value, wp.array):
            shape = getattr(spec, "shape", ())
            if (shape and shape[0] == "*") or (name == "dof_length" and not sleeps):
                return ("per-world", value.shape, str(value.dtype))
            return ("shared", value.shape, value.numpy().tobytes())
        if dc.is_dataclass(value):
            return tuple(sign(getattr(value, f.name), f.type, f.name) for f in dc.fields(value))
        if isinstance(value, tuple | list):
            return tuple(sign(x, None, name) for x in value)
        if isinstance(value, np.ndarray):
            return ("numpy", value.shape, value.tobytes())
        return repr(value)

    return sign(m, None, "")


def _warp_batch(part: list[_Request]) -> None:
    """Requests of one model structure as one Warp batch: the first's device model with every per-world array that
    differs between the requests' models made one row per world, each world stepped to the longest run."""
    import dataclasses as dc

    wp, _ = _warp()
    first = part[0]
    worlds = [len(r.states0) for r in part]

    def per_world(objs) -> None:
        for f in dc.fields(objs[0]):
            values = [getattr(x, f.name) for x in objs]
            if dc.is_dataclass(values[0]):
                per_world(values)
            elif isinstance(values[0], wp.array) and getattr(values[0], "_is_batched", False):
                rows = [v.numpy() for v in values]
                if any(not np.array_equal(r, rows[0]) for r in rows[1:]):
                    stacked = np.concatenate([np.repeat(r[:1], n, axis=0) for r, n in zip(rows, worlds, strict=True)])
                    array = wp.array(stacked, dtype=values[0].dtype, device=values[0].device)
                    array._is_batched = True
                    setattr(objs[0], f.name, array)

    with wp.ScopedDevice(first.engine.device):
        m = first.leaves
        if len(part) > 1:
            per_world([r.leaves for r in part])
        nstep = max(r.nstep for r in part)
        states0 = np.concatenate([r.states0 for r in part])
        states = first.engine._rollout(first.model, states0, nstep, _stacked_controls(part, nstep, first.model.nu), m)
    _finish_all(part, states)


def _feature(exc: NotImplementedError) -> str:
    """MJX's refusal names the feature as an enum (``mjtSolver.mjSOL_PGS``); say it in words too."""
    text = str(exc)
    words = {"mjSOL_PGS": "the PGS solver", "mjINT_IMPLICIT": "the implicit integrator"}
    for key, word in words.items():
        if key in text:
            return f"{word} is not implemented ({text})"
    return text


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


# ---- gathering: the rollouts of a run's concurrent cases as one batch -----------------------------------------


class Gather:
    """Gathers the MJX rollouts of cases running at once on threads (`rigidbench.runner.Gathered`): a member's
    rollout waits until every member is waiting on one, then the waiting rollouts run as one compiled batch per
    model structure (`_run_requests`). A census's draws of a case differ in their parameters, timestep and run
    length but share a structure: one program and one batch instead of one compile (8-24 s on this CPU) per draw.

    The members are the calls running or about to run: `calls` of them, at most `width` at once. A call that
    finishes (or fails) without a rollout hands its place to the next call, or, with none left, lets the others go
    on without it. After `close` (the run ended or was interrupted) every rollout runs at once.
    """

    def __init__(self, calls: int, width: int) -> None:
        self._cv = threading.Condition()
        self._members = min(calls, width)
        self._unstarted = calls - self._members
        self._waiting = 0
        self._closed = False
        self._pending: list[_Request] = []
        self._local = threading.local()

    @contextlib.contextmanager
    def member_of(self) -> Iterator[None]:
        self._local.member = True
        try:
            yield
        finally:
            self._local.member = False
            with self._cv:
                if self._unstarted > 0:  # the next call takes this place
                    self._unstarted -= 1
                else:
                    self._members -= 1
            self._flush_if_all_wait()

    def member(self) -> bool:
        return getattr(self._local, "member", False)

    def close(self) -> None:
        """No more calls will start: what waits runs now, and every later rollout at once."""
        with self._cv:
            self._closed = True
        self._flush_if_all_wait()

    def submit(self, request: _Request) -> np.ndarray:
        with self._cv:
            self._pending.append(request)
            self._waiting += 1
        self._flush_if_all_wait()
        with self._cv:
            while request.result is None and request.error is None:
                self._cv.wait()
        if request.error is not None:
            raise request.error
        return request.result

    def _flush_if_all_wait(self) -> None:
        """Run what is pending once every member waits (this thread runs it; the others wake with their results)."""
        with self._cv:
            if not self._pending or (self._waiting < self._members and not self._closed):
                return
            batch, self._pending = self._pending, []
        answered: set[int] = set()

        def done(part: list[_Request]) -> None:  # those cases go on (and journal) while the other parts run
            with self._cv:
                self._waiting -= len(part)  # answered: a member asking again is waiting anew
                answered.update(id(r) for r in part)
                self._cv.notify_all()

        try:
            _run_requests(batch, done)
        finally:
            left = [r for r in batch if id(r) not in answered]
            for request in left:
                if request.result is None and request.error is None:
                    request.error = RuntimeError("the gathered batch did not run")
            done(left)


_GATHERING: Gather | None = None


@contextlib.contextmanager
def gathering(gather: Gather) -> Iterator[Gather]:
    """Route the MJX rollouts of `gather`'s members through it for the block."""
    global _GATHERING
    previous, _GATHERING = _GATHERING, gather
    try:
        yield gather
    finally:
        _GATHERING = previous


def batched_engine(name: str, *, device: str | None, precision: str | None) -> Engine:
    """A Warp or MJX engine, checked to be installed and to support the precision asked for.

    Raises
    ------
    ValueError
    """
    import importlib.util

    module, extra = {"warp": ("mujoco_warp", "warp"), "mjx": ("mujoco.mjx", "mjx")}[name]
    try:
        found = importlib.util.find_spec(module) is not None
    except ModuleNotFoundError:
        found = False
    if not found:
        raise ValueError(f"engine {name} is not installed: pip install 'rigidbench[{extra}]'")
    if name == "warp":
        if precision not in (None, "float32"):
            raise ValueError("engine warp computes in float32 only")
        return WarpEngine(device=device or "cpu")
    if precision not in (None, "float32", "float64"):
        raise ValueError(f"precision {precision!r} is not float32 or float64")
    return MjxEngine(device=device or "cpu", precision=precision or "float32")


# ---- worlds: N copies of one model stepped together, for the batched vector envs -----------------------------


class Worlds:
    """N copies ("worlds") of one compiled model, stepped together by an engine: what a batched vector env steps.

    The state the envs read and the inputs they write are host arrays of float64, shape (nworld, ...): `qpos`
    (nworld, nq), `qvel` (nworld, nv) and `time` (nworld,) after each `step`; `ctrl` (nworld, nu), `qfrc_applied`
    (nworld, nv) and `xfrc_applied` (nworld, nbody, 6), applied by the next `step`. Each engine keeps the rest of
    its state (warm starts, its own precision) where it computes.

    Attributes
    ----------
    model : MjModel
    nworld : int
    engine : Engine or None
        None for C MuJoCo.
    """

    model: mujoco.MjModel
    nworld: int
    engine: Engine | None = None
    qpos: np.ndarray
    qvel: np.ndarray
    time: np.ndarray
    ctrl: np.ndarray
    qfrc_applied: np.ndarray
    xfrc_applied: np.ndarray

    def load(self, ids: np.ndarray, data: mujoco.MjData) -> None:
        """Put worlds `ids` (ints, sorted) in the whole integration state of `data` (the same for each)."""
        raise NotImplementedError

    def step(self, nstep: int) -> None:
        """Advance every world `nstep` steps with the current inputs."""
        raise NotImplementedError

    def raw_step(self, nstep: int) -> None:
        """The engine's bare batched step, with no transfer of inputs or state (what a batched env's rate is
        compared with: `benchmarks/vector_envs.py`); C MuJoCo's is `step` itself."""
        self.step(nstep)

    def advance(self, data: mujoco.MjData, nstep: int) -> None:
        """A batch of one (`VectorScenarioEnv`'s on MJX and Warp): world 0 steps `nstep` times with the inputs in
        `data`, and its state comes back into `data` (qpos, qvel, and the clock as its time). The host arrays of
        inputs and state need not follow: a batch of one is read and written through `data`."""
        self.ctrl[0], self.qfrc_applied[0], self.xfrc_applied[0] = data.ctrl, data.qfrc_applied, data.xfrc_applied
        self.step(nstep)
        data.qpos[:], data.qvel[:], data.time = self.qpos[0], self.qvel[0], self.time[0]

    def close(self) -> None:
        """Release what the engine holds (threads, device memory)."""


_INTEGRATION = mujoco.mjtState.mjSTATE_INTEGRATION


class CWorlds(Worlds):
    """C MuJoCo's `mujoco.batch.Batch`: each world is one mjSTATE_INTEGRATION row (state, inputs and the solver's
    warm start), stepped on `nthread` threads in C, bit for bit as a loop of `mj_step` over one MjData per world
    (MuJoCo's own guarantee; `tests/test_vector.py` checks it against single envs). The state and input arrays are
    views of the rows: nothing is copied between the envs and the engine."""

    def __init__(self, model: mujoco.MjModel, nworld: int, *, nthread: int | None = None) -> None:
        import os

        from mujoco import batch

        from rigidbench import forces

        self.model, self.nworld = model, int(nworld)
        forces.attach(model)
        nthread = forces.threads_for(model, min(self.nworld, os.cpu_count() or 1) if nthread is None else int(nthread))
        self._batch = batch.Batch(model, self.nworld, nthread=nthread)
        for name in ("qpos", "qvel", "time", "ctrl", "qfrc_applied", "xfrc_applied"):
            setattr(self, name, self._batch.bind(name))
        self._row = np.empty(mujoco.mj_stateSize(model, _INTEGRATION))
        self._scratch: mujoco.MjData | None = None

    def load(self, ids: np.ndarray, data: mujoco.MjData) -> None:
        mujoco.mj_getState(self.model, data, self._row, _INTEGRATION)
        self._batch.state[ids] = self._row

    def step(self, nstep: int) -> None:
        if mujoco.get_mjcb_passive() is None:
            self._batch.step(nstep=nstep)
            return
        # A Python passive-force callback is installed (`rigidbench.forces`, while any model declaring a force is
        # alive, this one or another), and `mujoco.batch` refuses to step under one. The batch's own steps, one world
        # at a time: its state row into one MjData, `mj_step`, and back (what a non-persistent batch does on each of
        # its threads; bit for bit the same, `tests/test_vector.py`).
        if self._scratch is None:
            self._scratch = mujoco.MjData(self.model)
        scratch, state = self._scratch, self._batch.state
        for i in range(self.nworld):
            mujoco.mj_setState(self.model, scratch, state[i], _INTEGRATION)
            mujoco.mj_step(self.model, scratch, nstep)
            mujoco.mj_getState(self.model, scratch, state[i], _INTEGRATION)


class HostWorlds(Worlds):
    """Worlds an engine keeps on its device (MJX, Warp): float64 host copies of what the envs read and write, the
    state of the loaded worlds written into them by `_load_host`, and the step count as the clock (`clock`)."""

    def _host_arrays(self) -> None:
        n, m = self.nworld, self.model
        self.qpos, self.qvel = np.zeros((n, m.nq)), np.zeros((n, m.nv))
        self.time, self.ctrl = np.zeros(n), np.zeros((n, m.nu))
        self.qfrc_applied, self.xfrc_applied = np.zeros((n, m.nv)), np.zeros((n, m.nbody, 6))
        # The step count in float64 (exact to 2^53 steps, the same time as an int64 count): the first integer ufunc
        # after an XLA call cost 20-28 us on this CPU, a float one ~5 us (one-world MJX step, measured).
        self._t0, self._k = np.zeros(n), np.zeros(n)

    def _load_host(self, ids: np.ndarray, data: mujoco.MjData) -> None:
        self.qpos[ids], self.qvel[ids] = data.qpos, data.qvel
        self._t0[ids], self._k[ids] = data.time, 0
        self.time[ids] = data.time
        self.ctrl[ids], self.qfrc_applied[ids], self.xfrc_applied[ids] = data.ctrl, data.qfrc_applied, data.xfrc_applied

    def _tick(self, nstep: int) -> None:
        self._k += nstep
        self.time[:] = self._t0 + self.model.opt.timestep * self._k  # not the engine's float32 time: see `clock`


class MjxWorlds(HostWorlds):
    """MJX: the worlds as one vmapped `mjx.Data` on the engine's device, packed in one buffer per dtype with the
    model likewise (`_pack_plan`); `nstep` steps one jitted `fori_loop` (compiled once per model structure, world
    count and step count); the inputs go up and qpos, qvel come down each step."""

    def __init__(self, engine: MjxEngine, model: mujoco.MjModel, nworld: int) -> None:
        jax = engine._jax()
        from jax import numpy as jp
        from mujoco import mjx

        self.engine, self.model, self.nworld = engine, model, int(nworld)
        self._jp = jp
        self._dtype = jp.float64 if engine.precision == "float64" else jp.float32
        self._np_dtype = np.dtype(engine.precision)
        self._m = engine._model_on_device(model)
        d0 = mjx.put_data(model, mujoco.MjData(model))
        shapes = jax.eval_shape(lambda d: mjx.step(self._m, d), d0)  # as `MjxEngine.rollout`: the step's dtypes
        d0 = jax.tree_util.tree_map(lambda x, like: jp.asarray(x, like.dtype), d0, shapes)
        self._device = next(iter(self._m.qpos0.devices()))  # where the model went (`MjxEngine._model_on_device`)
        self._jax = jax
        # The model and the worlds go to the program packed: one buffer per dtype (`_pack_plan`), unpacked inside it
        # by static slices. A jitted call costs ~1.5 us per argument and result array on this CPU: as MJX's
        # dataclasses (flattened in Python) it was 250-450 us a call, as flat lists of their 208 arrays (HeavyTop)
        # ~300 us, most of a one-world step; packed, a handful of arrays. The program rebuilds the trees from their
        # structures.
        m_leaves, m_def = jax.tree_util.tree_flatten(self._m)
        d_leaves, d_def = jax.tree_util.tree_flatten(d0)
        self._m_plan, self._d_plan = _pack_plan(m_leaves), _pack_plan(d_leaves)
        self._m_bufs = jax.device_put(_pack([np.asarray(x) for x in m_leaves], self._m_plan, np), self._device)
        row = _pack([np.asarray(x) for x in d_leaves], self._d_plan, np)
        self._d_bufs = jax.device_put([np.broadcast_to(x, (self.nworld, *x.shape)) for x in row], self._device)
        self._d_dtypes = [np.dtype(x.dtype) for x in d_leaves]
        # A GPU's step writes the worlds' new state over the old (buffer donation); XLA on the CPU cannot, and warns.
        donate = self._device.platform != "cpu"
        self._program = _mjx_worlds_program(donate, m_def, d_def, self._m_plan, self._d_plan)
        self._load_program = _mjx_load_program(donate)
        self._start: tuple[bytes, list] = (b"", [])  # the last state loaded, packed, on the device
        self._row = np.empty(mujoco.mj_stateSize(model, _INTEGRATION))
        self._host_arrays()
        # `advance`'s: the model's numbers as the device model has them, and the views of the last `data` stepped
        self._timestep, self._nq = model.opt.timestep, model.nq
        self._views: tuple | None = None

    def load(self, ids: np.ndarray, data: mujoco.MjData) -> None:
        """Every field of worlds `ids` (warm start, contacts, ...) from `data`, in the dtypes the step gives them.

        One jitted select over the worlds' arrays; the state's own arrays go to the device once and are kept while
        the same state is loaded again (the envs' autoresets load their episode's initial state every time). The
        field-by-field update this replaced cost 35 ms a load on this CPU, 82 us a step of a one-world episode."""
        import jax
        from mujoco import mjx

        self._load_host(ids, data)
        mujoco.mj_getState(self.model, data, self._row, _INTEGRATION)
        key = self._row.tobytes()
        if key != self._start[0]:
            leaves = jax.tree_util.tree_leaves(mjx.put_data(self.model, data))
            leaves = [np.asarray(x).astype(dtype) for x, dtype in zip(leaves, self._d_dtypes, strict=True)]
            self._start = (key, jax.device_put(_pack(leaves, self._d_plan, np), self._device))
        mask = np.zeros(self.nworld, dtype=bool)
        mask[ids] = True
        self._d_bufs = self._load_program(self._d_bufs, self._start[1], mask)

    def step(self, nstep: int) -> None:
        # The inputs go to the jitted program as one numpy array [ctrl | qfrc_applied | xfrc_applied] of its dtype
        # (its dispatch copies it to the device; three arrays cost ~30 us a step more at N = 1) and the state comes
        # back as one array [qpos | qvel]: one transfer each way a step.
        n = self.nworld
        inputs = np.concatenate(
            (self.ctrl, self.qfrc_applied, self.xfrc_applied.reshape(n, -1)), axis=1, dtype=self._np_dtype
        )
        self._d_bufs, state = self._program(self._m_bufs, self._d_bufs, inputs, nstep=nstep)
        state = np.asarray(state)
        nq = self.model.nq
        self.qpos[:], self.qvel[:] = state[:, :nq], state[:, nq:]
        self._tick(nstep)

    def advance(self, data: mujoco.MjData, nstep: int) -> None:
        """`Worlds.advance` with the fewest host operations: `data`'s inputs straight into the program's input
        array and the state straight into `data`, the clock kept, the host arrays left as the last `step` or `load`
        left them. Each numpy operation just after an XLA call costs several times what it costs warm on this CPU
        (5-45 us, measured); going through the host arrays put a one-world env at 0.74 of the raw step, this at
        0.83 (HeavyTop, paired per-step medians). `data`'s arrays are read through views kept while the same
        `data` comes (an `MjData` attribute is a new array each time), and the clock is set while XLA steps
        (dispatch is asynchronous), before the state is waited for: 12-20 us a step less in place (docs/engines.md)."""
        if self.nworld != 1:
            raise ValueError(f"advance() steps a batch of one; this one has {self.nworld} worlds")
        views = self._views
        if views is None or views[0] is not data:
            views = self._views = (
                data,
                data.ctrl,
                data.qfrc_applied,
                data.xfrc_applied.reshape(-1),
                data.qpos,
                data.qvel,
            )
        _, ctrl, qfrc_applied, xfrc_applied, qpos, qvel = views
        inputs = np.concatenate((ctrl, qfrc_applied, xfrc_applied), dtype=self._np_dtype)
        self._d_bufs, state = self._program(self._m_bufs, self._d_bufs, inputs[None], nstep=nstep)
        k = self._k.item() + nstep  # `_tick`'s clock, for world 0
        self._k[0] = k
        data.time = self._t0.item() + self._timestep * k
        state = np.asarray(state)[0]
        nq = self._nq
        qpos[:], qvel[:] = state[:nq], state[nq:]

    def raw_step(self, nstep: int) -> None:
        """The engine's bare batched step: zero inputs already on the device, nothing copied back."""
        if getattr(self, "_zeros", None) is None:
            m = self.model
            self._zeros = self._jax.device_put(
                np.zeros((self.nworld, m.nu + m.nv + 6 * m.nbody), self._np_dtype), self._device
            )
        self._d_bufs, state = self._program(self._m_bufs, self._d_bufs, self._zeros, nstep=nstep)
        state.block_until_ready()


def _pack_plan(leaves: list) -> tuple:
    """How `_pack` lays `leaves` out: per dtype (in order of first appearance), the leaves' indices and shapes, in
    order. Hashable: a jitted program's static description of its packed arguments."""
    groups: dict[str, list] = {}
    for i, x in enumerate(leaves):
        groups.setdefault(np.dtype(x.dtype).str, []).append((i, tuple(x.shape)))
    return tuple((dtype, tuple(entries)) for dtype, entries in groups.items())


def _pack(leaves: list, plan: tuple, xp) -> list:
    """`leaves` as one 1-D buffer per dtype of `plan` (`_pack_plan`), with `xp` (numpy, or jax.numpy in a
    program); each leaf raveled, exactly (no conversion: a group holds one dtype)."""
    return [xp.concatenate([xp.ravel(leaves[i]) for i, _ in entries]) for _, entries in plan]


def _unpack(bufs: list, plan: tuple) -> list:
    """The leaves `_pack` packed into `bufs`, by static slices (1-D buffers: one world, or the model)."""
    leaves: list = [None] * sum(len(entries) for _, entries in plan)
    for buf, (_, entries) in zip(bufs, plan, strict=True):
        offset = 0
        for i, shape in entries:
            size = math.prod(shape)
            leaves[i] = buf[offset : offset + size].reshape(shape)
            offset += size
    return leaves


@functools.cache
def _mjx_worlds_program(donate: bool, m_def, d_def, m_plan: tuple, d_plan: tuple):
    """`nstep` MJX steps of every world with the given inputs, jitted once per model and data structure (`m_def`,
    `d_def`: their tree structures, hashable; `m_plan`, `d_plan`: how their arrays are packed, `_pack_plan`) and
    step count (a static argument). The model (one buffer per dtype) and the worlds (one (nworld, size) buffer per
    dtype) are arguments, so every model of one structure shares the program; with `donate` the old worlds'
    buffers hold the new ones."""
    import jax
    from mujoco import mjx

    def run(m_bufs, d_bufs, inputs, nstep):
        m = jax.tree_util.tree_unflatten(m_def, _unpack(m_bufs, m_plan))

        def one(d_row, inputs):  # one world's buffers; inputs: its [ctrl | qfrc_applied | xfrc_applied] (`step`)
            d = jax.tree_util.tree_unflatten(d_def, _unpack(d_row, d_plan))
            nu, nv = d.ctrl.shape[0], d.qfrc_applied.shape[0]
            xfrc = inputs[nu + nv :].reshape(d.xfrc_applied.shape)
            d = d.replace(ctrl=inputs[:nu], qfrc_applied=inputs[nu : nu + nv], xfrc_applied=xfrc)
            with jax.default_matmul_precision(matmul_precision()):  # float32's own, not TF32 (`matmul_precision`)
                d = jax.lax.fori_loop(0, nstep, lambda _, d: mjx.step(m, d), d)
            return _pack(jax.tree_util.tree_leaves(d), d_plan, jax.numpy), jax.numpy.concatenate([d.qpos, d.qvel])

        return jax.vmap(one)(d_bufs, inputs)

    return jax.jit(run, static_argnames="nstep", donate_argnums=(1,) if donate else ())


@functools.cache
def _mjx_load_program(donate: bool):
    """The worlds' buffers (packed, `MjxWorlds`) with the rows of the worlds in `mask` replaced by one state's
    buffers (one world's, in the same order), jitted once per structure and world count (`jax.jit`'s own cache)."""
    import jax
    from jax import numpy as jp

    def load(d_bufs, start_bufs, mask):
        def pick(x, x0):
            return jp.where(mask.reshape((-1,) + (1,) * (x.ndim - 1)), x0[None], x)

        return [pick(x, x0) for x, x0 in zip(d_bufs, start_bufs, strict=True)]

    return jax.jit(load, donate_argnums=(0,) if donate else ())


class WarpWorlds(HostWorlds):
    """MuJoCo Warp: one `mjw.Data` of `nworld` worlds; `nstep` steps captured once as a Warp graph (as in
    `WarpEngine.rollout`), the inputs assigned before and qpos, qvel copied back after each launch."""

    def __init__(self, engine: WarpEngine, model: mujoco.MjModel, nworld: int) -> None:
        wp, mjw = _warp()
        self.engine, self.model, self.nworld = engine, model, int(nworld)
        self._wp = wp
        with _WARP_LOCK, wp.ScopedDevice(engine.device):
            self._m = engine._model_on_device(model)
            self._d = mjw.put_data(model, mujoco.MjData(model), nworld=self.nworld)
        self._host_arrays()
        self._graphs: dict[int, Any] = {}
        # On the CPU a Warp array's `numpy()` is a view of its memory: a step writes the inputs into these and reads
        # the state out of them (a float32 cast each), where `assign` and `numpy()` cost ~15-35 us a call in Python
        # (a third of a one-world step's overhead, docs/engines.md). A GPU's arrays are copied both ways.
        names = ("ctrl", "qfrc_applied", "xfrc_applied", "qpos", "qvel")
        self._views = {name: getattr(self._d, name).numpy() for name in names} if self._d.qpos.device.is_cpu else None

    def load(self, ids: np.ndarray, data: mujoco.MjData) -> None:
        self._load_host(ids, data)
        with _WARP_LOCK, self._wp.ScopedDevice(self.engine.device):
            self._d.qpos.assign(self.qpos.astype(np.float32))
            self._d.qvel.assign(self.qvel.astype(np.float32))
            warmstart = self._d.qacc_warmstart.numpy()
            warmstart[ids] = data.qacc_warmstart
            self._d.qacc_warmstart.assign(warmstart)

    def _graph(self, nstep: int):
        wp, mjw = _warp()
        if nstep not in self._graphs:
            warmstart = self._d.qacc_warmstart.numpy()
            mjw.step(self._m, self._d)  # compile and load every kernel before capturing: one step, undone below
            self._d.qpos.assign(self.qpos.astype(np.float32))
            self._d.qvel.assign(self.qvel.astype(np.float32))
            self._d.qacc_warmstart.assign(warmstart)
            with wp.ScopedCapture(force_module_load=False) as capture:
                for _ in range(nstep):
                    mjw.step(self._m, self._d)
            self._graphs[nstep] = capture.graph
        return self._graphs[nstep]

    def step(self, nstep: int) -> None:
        wp = self._wp
        views = self._views
        with _WARP_LOCK, wp.ScopedDevice(self.engine.device):
            if views is not None:  # the CPU: straight into and out of the arrays' memory
                views["ctrl"][...], views["qfrc_applied"][...] = self.ctrl, self.qfrc_applied
                views["xfrc_applied"][...] = self.xfrc_applied
                wp.capture_launch(self._graph(nstep))  # a CPU launch returns when it is done
                self.qpos[:], self.qvel[:] = views["qpos"], views["qvel"]
            else:
                self._d.ctrl.assign(self.ctrl.astype(np.float32))
                self._d.qfrc_applied.assign(self.qfrc_applied.astype(np.float32))
                self._d.xfrc_applied.assign(self.xfrc_applied.astype(np.float32))
                wp.capture_launch(self._graph(nstep))
                self.qpos[:], self.qvel[:] = self._d.qpos.numpy(), self._d.qvel.numpy()
        self._tick(nstep)

    def raw_step(self, nstep: int) -> None:
        """The engine's bare batched step (a graph launch, no transfers)."""
        with _WARP_LOCK, self._wp.ScopedDevice(self.engine.device):
            self._wp.capture_launch(self._graph(nstep))
            self._wp.synchronize()


def worlds(engine: Engine | None, model: mujoco.MjModel, nworld: int, *, nthread: int | None = None) -> Worlds:
    """`nworld` copies of `model` on `engine` (None: C MuJoCo, on `nthread` threads, default every CPU).

    Raises
    ------
    EngineRefused
        If the engine cannot simulate the model (`Engine.check`).
    ValueError
        For ``nworld < 1``.
    """
    if int(nworld) < 1:
        raise ValueError(f"num_envs = {nworld!r} must be an integer >= 1")
    if engine is None:
        return CWorlds(model, nworld, nthread=nthread)
    engine.check(model)
    if isinstance(engine, MjxEngine):
        return MjxWorlds(engine, model, nworld)
    if isinstance(engine, WarpEngine):
        return WarpWorlds(engine, model, nworld)
    raise ValueError(f"engine {engine.name!r} has no batched worlds")
