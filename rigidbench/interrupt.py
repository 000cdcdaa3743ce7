"""The exception a SIGINT or SIGTERM becomes in the command (`rigidbench.cli`).

A module of its own that imports nothing of rigidbench: the signal may arrive while another module is half
imported (planning starts within the first second), and the handler and `cli.main` must still be able to name it.
"""

from __future__ import annotations

import signal

# The signals that arrived (`note`): the handler's exception can be lost where it lands, so the run loop also asks.
_PENDING: list[int] = []


def note(signum: int) -> None:
    """Remember that signal `signum` arrived (the CLI's handler, before it raises `Interrupted`)."""
    _PENDING.append(signum)


def pending() -> int | None:
    """The first signal that arrived since `clear`, or None."""
    return _PENDING[0] if _PENDING else None


def clear() -> None:
    _PENDING.clear()


def check() -> None:
    """Raise `Interrupted` if a signal arrived whose exception was lost: raised inside a callback that swallows it
    (JAX's garbage-collection callback during `import jax`, importlib's module-lock weakref callback during any
    import: Python hands it to `sys.unraisablehook`, which `cli.main` keeps quiet for it) or wrapped by the code it
    landed in. The run loop calls it after every case, so such a run stops at the next case."""
    if _PENDING:
        raise Interrupted(_PENDING[0])


class Interrupted(BaseException):
    """SIGINT or SIGTERM during a run; the exit status is 128 + the signal number."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.status = 128 + signum
        self.name = signal.Signals(signum).name
