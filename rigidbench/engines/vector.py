"""Vector-env worlds: N copies of one compiled model stepped together, what a batched vector env steps
(`envs/vector.py`).

`worlds` picks the kind for an engine: `CWorlds` (C MuJoCo's `mujoco.batch`, the state and inputs views of its
rows), `MjxWorlds` (one vmapped `mjx.Data`, model and worlds packed in one buffer per dtype, `_pack_plan`) or
`WarpWorlds` (one `mjw.Data` of N worlds, a captured graph per step count). The engines' own rollouts, used by
`rigidbench.simulate`, live in `rigidbench.engines.cpu`, `.mjx` and `.warp`.
"""

from __future__ import annotations

import functools
import math
import os
from typing import Any

import mujoco
import numpy as np

from rigidbench import forces
from rigidbench.engines.base import Engine
from rigidbench.engines.mjx import MjxEngine, matmul_precision
from rigidbench.engines.warp import _WARP_LOCK, WarpEngine, _warp


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
        from mujoco import batch

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
