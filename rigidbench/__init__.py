"""rigidbench: textbook rigid-body scenarios in MuJoCo, scored against closed-form classical mechanics.

Importing the package registers every scenario's gymnasium environment (``rigidbench/<Name>-v0``).
"""

import os as _os
import sys as _sys


def _cli_starting() -> bool:
    """Whether this process is the ``rigidbench`` command starting (its console script, or ``python -m
    rigidbench``, during whose package import ``sys.argv[0]`` is still ``-m``)."""
    argv0 = _sys.argv[0] if _sys.argv else ""
    return _os.path.basename(argv0) == "rigidbench" or (argv0 == "-m" and "rigidbench" in _sys.orig_argv)


def _early_signals() -> None:
    """Until the command line installs its own handlers (`rigidbench.cli.main`), a SIGINT or SIGTERM while the
    command is still importing ends it with one line and 130/143, as one later does, and never a traceback."""
    import signal

    def stop(signum: int, _frame: object) -> None:
        _os.write(2, f"rigidbench: interrupted by {signal.Signals(signum).name}\n".encode())
        _os._exit(128 + signum)

    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, stop)


_CLI = _cli_starting()
if _CLI:
    _early_signals()


def _headless_gl() -> str | None:
    """The OpenGL backend MuJoCo can use without a display: EGL, else OSMesa, whichever library loads here; None
    if neither does. MuJoCo's Python package imports the backend named by MUJOCO_GL with `import mujoco` itself,
    and ``MUJOCO_GL=egl`` without libEGL makes that import fail (PyOpenGL: 'NoneType' object has no attribute
    'eglQueryString'), so a machine without either keeps MuJoCo's default and renders nothing."""
    import ctypes

    for backend, names in (("egl", ("libEGL.so.1", "libEGL.so")), ("osmesa", ("libOSMesa.so.8", "libOSMesa.so"))):
        for name in names:
            try:
                ctypes.CDLL(name)
            except OSError:
                continue
            return backend
    return None


# MuJoCo picks its OpenGL backend when it is first imported: on a machine with no display, one that loads here.
if "MUJOCO_GL" not in _os.environ and not _os.environ.get("DISPLAY"):
    _backend = _headless_gl()
    if _backend is not None:
        _os.environ["MUJOCO_GL"] = _backend

__version__ = "0.1.0"


def __getattr__(name: str):
    """`get`, `scenarios` and `register_envs` of `rigidbench.registry`, imported on first use."""
    if name in ("get", "scenarios", "register_envs"):
        from rigidbench import registry

        return getattr(registry, name)
    raise AttributeError(f"module 'rigidbench' has no attribute {name!r}")


# Importing the package registers the gymnasium environments (which imports every scenario). The command line
# does not use gymnasium's registry, so it skips that and starts in a fraction of the time (`rigidbench.cli`
# registers them itself where a command needs them).
if not _CLI:
    from rigidbench.registry import register_envs as _register

    _register()

__all__ = ["__version__", "get", "scenarios"]
