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
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


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

        nbatch = len(states0)
        nthread = min(nbatch, os.cpu_count() or 1)
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
        if not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONSTRAINT:  # only where a solver runs
            self._check_solver(model)
        self._model_on_device(model)

    def _check_solver(self, model: mujoco.MjModel) -> None:
        if model.opt.solver == mujoco.mjtSolver.mjSOL_PGS:
            raise ValueError("engine warp has no PGS solver (use --option solver=Newton or CG)")
        if model.opt.noslip_iterations > 0:
            raise ValueError("engine warp has no noslip solver (noslip_iterations must be 0)")
        if model.opt.tolerance < 1e-6 and model.opt.tolerance != 0:
            raise ValueError(
                f"engine warp clamps the solver tolerance to >= 1e-6; the model asks {model.opt.tolerance:g} "
                "(use --option tolerance=1e-6 to run what Warp runs)"
            )

    def _model_on_device(self, model: mujoco.MjModel):
        import mujoco_warp as mjw
        import warp as wp

        wp.config.quiet = True
        wp.init()
        try:
            with wp.ScopedDevice(self.device):
                return mjw.put_model(model)
        except NotImplementedError as exc:
            raise ValueError(f"engine warp cannot simulate this model: {exc}") from None

    def rollout(
        self, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None = None
    ) -> np.ndarray:
        import mujoco_warp as mjw
        import warp as wp

        t, q, v = _layout(model)
        nbatch = len(states0)
        out = np.repeat(states0[:, None, :], nstep, axis=1)
        with wp.ScopedDevice(self.device):
            m = self._model_on_device(model)
            data = mujoco.MjData(model)
            mujoco.mj_setState(model, data, states0[0], STATE)
            d = mjw.put_data(model, data, nworld=nbatch)
            d.qpos.assign(states0[:, q].astype(np.float32))
            d.qvel.assign(states0[:, v].astype(np.float32))
            d.time.assign(states0[:, 0].astype(np.float32))
            for i in range(nstep):
                if control is not None:
                    d.ctrl.assign(np.ascontiguousarray(control[:, i]).astype(np.float32))
                mjw.step(m, d)
                out[:, i, t] = d.time.numpy().astype(np.float64)[:, None]
                out[:, i, q] = d.qpos.numpy()
                out[:, i, v] = d.qvel.numpy()
        return out


@dataclass(frozen=True)
class MjxEngine(Engine):
    """MJX (`mujoco.mjx`, JAX), float32 by default or float64 (``jax_enable_x64``), `jax.vmap` over the batch and
    `jax.lax.scan` over the steps, compiled once per model structure, batch size and run length."""

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
        self._model_on_device(model)

    def _model_on_device(self, model: mujoco.MjModel):
        jax = self._jax()
        from mujoco import mjx

        try:
            return mjx.put_model(model, device=jax.devices(self.device)[0])
        except NotImplementedError as exc:
            raise ValueError(f"engine mjx cannot simulate this model: {exc}") from None

    def rollout(
        self, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None = None
    ) -> np.ndarray:
        jax = self._jax()
        from jax import numpy as jp
        from mujoco import mjx

        t, q, v = _layout(model)
        dtype = jp.float64 if self.precision == "float64" else jp.float32
        m = self._model_on_device(model)
        data = mujoco.MjData(model)
        mujoco.mj_setState(model, data, states0[0], STATE)
        d0 = mjx.put_data(model, data)
        ctrl = jp.zeros((len(states0), nstep, model.nu), dtype) if control is None else jp.asarray(control, dtype)

        def one(time, qpos, qvel, controls):
            d = d0.replace(time=time, qpos=qpos, qvel=qvel)

            def body(d, c):
                d = mjx.step(m, d.replace(ctrl=c))
                return d, (d.time, d.qpos, d.qvel)

            return jax.lax.scan(body, d, controls)[1]

        run = jax.jit(jax.vmap(one))
        times, qpos, qvel = run(
            jp.asarray(states0[:, 0], dtype), jp.asarray(states0[:, q], dtype), jp.asarray(states0[:, v], dtype), ctrl
        )
        out = np.repeat(states0[:, None, :], nstep, axis=1)
        out[:, :, t] = np.asarray(times, dtype=np.float64)[..., None]
        out[:, :, q] = np.asarray(qpos, dtype=np.float64)
        out[:, :, v] = np.asarray(qvel, dtype=np.float64)
        return out


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
