"""The engine of a name: what ``--engine``, ``--device`` and ``--precision`` (`rigidbench.settings.Settings`) and
the vector envs' ``engine=`` choose, checked to be installed and to have that device and precision."""

from __future__ import annotations

from rigidbench.engines.base import ENGINES, Engine
from rigidbench.engines.mjx import MjxEngine
from rigidbench.engines.warp import WarpEngine


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
