"""rigidbench: textbook rigid-body scenarios in MuJoCo, scored against closed-form classical mechanics.

Importing the package registers every scenario's gymnasium environment (``rigidbench/<Name>-v0``).
"""

import os as _os

# MuJoCo picks its OpenGL backend when it is first imported: default to EGL on a machine with no display.
if "MUJOCO_GL" not in _os.environ and not _os.environ.get("DISPLAY"):
    _os.environ["MUJOCO_GL"] = "egl"

__version__ = "0.1.0"

from rigidbench.registry import get, register_envs, scenarios  # noqa: E402

register_envs()

__all__ = ["__version__", "get", "scenarios"]
