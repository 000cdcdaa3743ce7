"""MuJoCo Warp (`mujoco_warp`, float32 only; GPU or CPU): one world per initial state.

`WarpEngine.rollout` steps the worlds of a request (`rigidbench.engines.batching`: gathered with other cases' of
the same model structure, `_warp_signature`) as K steps captured once as a Warp graph and launched ``nstep / K``
times; the per-world arrays that differ between the gathered models (masses, sizes, the timestep) are stacked per
world (`_warp_batch`). Warp and mujoco_warp are imported on first use (`_warp`), never at import of this module.
"""

from __future__ import annotations

import dataclasses as dc
import threading
from dataclasses import dataclass

import mujoco
import numpy as np

from rigidbench import forces
from rigidbench.engines.base import STATE, Engine, EngineRefused, _layout
from rigidbench.engines.batching import _finish_all, _Request, _rollout_request, _stacked_controls


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


def _steps_per_graph(nstep: int) -> int:
    """Steps captured in one Warp graph: enough that launching it costs little per step, few enough that the
    remainder (stepped one by one) stays cheap."""
    return max(1, min(nstep, 32))


def _warp_signature(model: mujoco.MjModel, m) -> tuple:
    """What worlds of one Warp batch must share: every field of the device model `m` but the arrays Warp keeps per
    world (a leading ``*`` dimension: masses, inertias, sizes, positions, the timestep, gravity), whose shapes only
    count. `dof_length` (not per world) is read only by sleeping islands: ignored unless the model enables sleep."""
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
