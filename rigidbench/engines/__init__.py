"""Engines: where a compiled model and initial states become trajectories (DESIGN.md "Engine").

C MuJoCo (`mujoco.rollout`) is the default. An engine is chosen by the settings (``Settings.engine``, the CLI's
``--engine``) and is in effect for the simulation of a case (`use`): `rigidbench.simulate.simulate` and
`final_states` route through the engine in effect, so scenarios, predictions and measurements never branch on it.
Trajectories always come back as float64 arrays in MuJoCo's full-physics state layout.

An engine that lacks a feature the model uses (an integrator, a solver, a contact type) refuses it before
anything is simulated (`Engine.check`: a `ValueError` naming the engine and the feature); there is no silent
fallback. Every result records the engine, its version, its device and its float precision (`Engine.record`).

One module per concern, each importing only those listed above it:

- `base`: the adapter interface (`Engine`, `EngineRefused`, `STATE`) and the engine in effect (`current`, `use`);
- `cpu`: C MuJoCo (`CEngine`);
- `precision`: what float32 costs (`roundoff_floor`, `advance_error`, `steady_change_error`, `stored`, `clock`);
- `batching`: the rollouts of a run's concurrent cases as one batch per model structure (`Gather`, `gathering`);
- `warp`, `mjx`: MuJoCo Warp (`WarpEngine`) and MJX (`MjxEngine`, `matmul_precision`);
- `vector`: N worlds of one model stepped together for the batched vector envs (`worlds`, `Worlds`);
- `registry`: the engine of a name (`engine_for`).

This package re-exports their names as ``rigidbench.engines.X``. To patch a module-level name (a test replacing
`_run_part`, a constant such as `MJX_CONTACT_WORLDS`), patch it in the module that reads it, not here.
"""

from rigidbench.engines.base import ENGINES, STATE, Engine, EngineRefused, _layout, current, use
from rigidbench.engines.batching import GATHER_BYTES, Gather, _Request, _run_part, gathering
from rigidbench.engines.cpu import CEngine
from rigidbench.engines.mjx import MJX_CONTACT_WORLDS, MjxEngine, _collides, _mjx_batch, matmul_precision
from rigidbench.engines.precision import (
    ROUNDOFF_FACTOR,
    STEADY_CHANGE_RULE,
    advance_error,
    clock,
    roundoff_floor,
    steady_change_error,
    stored,
    stored_model,
    stored_state,
)
from rigidbench.engines.registry import batched_engine, engine_for
from rigidbench.engines.vector import (
    CWorlds,
    HostWorlds,
    MjxWorlds,
    WarpWorlds,
    Worlds,
    _pack,
    _pack_plan,
    _unpack,
    worlds,
)
from rigidbench.engines.warp import WarpEngine

__all__ = [
    "CEngine",
    "CWorlds",
    "ENGINES",
    "Engine",
    "EngineRefused",
    "GATHER_BYTES",
    "Gather",
    "HostWorlds",
    "MJX_CONTACT_WORLDS",
    "MjxEngine",
    "MjxWorlds",
    "ROUNDOFF_FACTOR",
    "STATE",
    "STEADY_CHANGE_RULE",
    "WarpEngine",
    "WarpWorlds",
    "Worlds",
    "_Request",
    "_collides",
    "_layout",
    "_mjx_batch",
    "_pack",
    "_pack_plan",
    "_run_part",
    "_unpack",
    "advance_error",
    "batched_engine",
    "clock",
    "current",
    "engine_for",
    "gathering",
    "matmul_precision",
    "roundoff_floor",
    "steady_change_error",
    "stored",
    "stored_model",
    "stored_state",
    "use",
    "worlds",
]
