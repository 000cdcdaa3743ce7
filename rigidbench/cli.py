"""The ``rigidbench`` command line: the parser, dispatch to the verbs and signal handling.

Each verb (``run``, ``list``, ``sweep``, ...) is a module of `rigidbench.commands` holding its arguments and its
main; this module builds the parser from them, runs the one asked for, and turns what a user can cause into one
line and an exit status.

Exit status (README "CI"): 0 when every check passed; 1 when any check failed, a simulation diverged or a case
raised an error (each in its row); 2 for bad usage, a parameter set outside the theory's domain, an output that
cannot be written or a journal that cannot be used (one line on stderr naming it, no traceback); 130 when
interrupted by Ctrl-C (SIGINT), 143 by SIGTERM, after writing every finished row (``--jsonl`` journals them as
they finish, ``--resume`` continues; ``--json`` and ``--junit`` say the run is incomplete).
"""

from __future__ import annotations

import argparse
import functools
import importlib
import signal
import sys
from collections.abc import Sequence

from rigidbench.commands import VERBS
from rigidbench.exits import EXIT_FAIL, EXIT_OK, EXIT_USAGE, UsageError

__all__ = ["EXIT_FAIL", "EXIT_OK", "EXIT_USAGE", "UsageError", "entry", "main"]


def _command(verb: str):
    """A verb's module (`rigidbench.commands`): light to import, its main imports what it runs."""
    return importlib.import_module(f"rigidbench.commands.{verb}")


def _parser() -> argparse.ArgumentParser:
    from rigidbench import __version__

    parser = argparse.ArgumentParser(
        prog="rigidbench",
        description="Textbook rigid-body scenarios in MuJoCo, scored against closed-form classical mechanics.",
    )
    parser.add_argument("--version", action="version", version=f"rigidbench {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for verb in VERBS:
        _command(verb).arguments(sub)
    return parser


def _raise_interrupted(signum: int, _frame: object) -> None:
    # never rigidbench.runner: it may be half imported right now. The signal is noted first: the exception may come
    # out wrapped by the code it landed in (ctypes, during `import mujoco`'s EGL probing, turns it into an
    # ArgumentError) or be swallowed (`rigidbench.interrupt.check`).
    from rigidbench import interrupt

    interrupt.note(signum)
    raise interrupt.Interrupted(signum)


def _quiet_interrupted(previous, unraisable) -> None:
    """`sys.unraisablehook` during a command: the handler's exception, raised inside a callback that cannot pass it
    on (importlib's module-lock weakref callback, JAX's garbage-collection callback), is not printed as "Exception
    ignored ... Traceback": `_raise_interrupted` noted the signal, and the run loop or `main` raises it again."""
    from rigidbench.interrupt import Interrupted

    if isinstance(unraisable.exc_value, Interrupted):
        return
    previous(unraisable)


def main(argv: Sequence[str] | None = None, *, last: bool = False) -> int:
    """Run one command; its exit status. `last`: the process ends after it (`entry`), so SIGINT and SIGTERM are left
    at the system default afterwards instead of the handlers found on entry: a SIGINT in the interpreter's last
    moments (atexit callbacks, such as the worker pools' joins) then ends the process with 130 and no output,
    where Python's own handler would print a KeyboardInterrupt traceback. The run's files are whole by then."""
    # Signals first: from here on SIGINT/SIGTERM end the command with one line and 130/143, planning included.
    from rigidbench import interrupt

    interrupt.clear()
    handlers = {sig: signal.signal(sig, _raise_interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
    unraisable_hook = sys.unraisablehook
    sys.unraisablehook = functools.partial(_quiet_interrupted, unraisable_hook)
    try:
        status = _main(argv)
        signum = interrupt.pending()
        if signum is not None and status not in (128 + signal.SIGINT, 128 + signal.SIGTERM):
            # swallowed where it landed (a weakref callback) in a command that never asks again: still 130/143
            raise interrupt.Interrupted(signum)
        return status
    except BaseException as exc:  # noqa: BLE001 - sorted below: everything a user can cause is one line
        from rigidbench.interrupt import Interrupted

        if not isinstance(exc, Interrupted) and interrupt.pending() is not None:
            exc = Interrupted(interrupt.pending())  # raised inside code that wrapped it (e.g. ctypes' ArgumentError)
        if isinstance(exc, Interrupted):
            print(f"rigidbench: interrupted by {exc.name}", file=sys.stderr)
            return exc.status
        # SystemExit (--help, --version, argparse's usage errors) is passed on without importing the error types
        if isinstance(exc, UsageError) or isinstance(exc, Exception) and _is_one_line(exc):
            print(f"rigidbench: error: {exc}", file=sys.stderr)
            return EXIT_USAGE
        raise
    finally:
        for sig, handler in handlers.items():
            # Python's KeyboardInterrupt handler only: an ignored signal (nohup, a background job) stays ignored
            signal.signal(sig, signal.SIG_DFL if last and handler is signal.default_int_handler else handler)
        sys.unraisablehook = unraisable_hook
        interrupt.clear()  # a later command (or runner call) in this process starts uninterrupted


def _is_one_line(exc: BaseException) -> bool:
    """An error a user's input or machine causes (an output, a journal), reported in one line with status 2."""
    from rigidbench.journal import JournalError
    from rigidbench.outputs import OutputError
    from rigidbench.runner import ClusterError

    return isinstance(exc, (OutputError, JournalError, ClusterError))


def _main(argv: Sequence[str] | None) -> int:
    args = _parser().parse_args(argv)
    return _command(args.command).main(args)


def entry() -> None:
    """The `rigidbench` command and `python -m rigidbench`: the command's status is the process's."""
    sys.exit(main(last=True))


if __name__ == "__main__":
    entry()
