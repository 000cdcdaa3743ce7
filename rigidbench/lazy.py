"""Modules imported on first use: scipy costs ~0.3 s to import and most commands (``rigidbench list``, ``--help``,
most runs of one scenario) never call it."""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import Any


class LazyModule(ModuleType):
    """A stand-in for the module `name`, imported when one of its attributes is first read."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self._module: ModuleType | None = None

    def __getattr__(self, attr: str) -> Any:
        if attr.startswith("__"):
            raise AttributeError(attr)
        if self._module is None:
            self._module = importlib.import_module(self.__name__)
        return getattr(self._module, attr)


def module(name: str) -> Any:
    """`name` (e.g. ``"scipy.special"``), imported on first attribute access."""
    return LazyModule(name)
