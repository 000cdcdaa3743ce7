"""The files a command writes (``--json``, ``--junit``, ``--jsonl``, ``--out``, ...): checked before anything is
simulated, written so that a reader never sees half a file, and never at the cost of the machine's devices.

Rules (issue 20):

- `check` runs while planning: a directory, a parent that is a file, a directory that cannot be written, a name
  longer than the file system allows, or the same path given to two options is refused (`OutputError`, exit 2,
  one line naming the option and the path); nothing has been simulated yet.
- ``-`` is standard output. A character device (``/dev/null``, ``/dev/full``, ``/dev/stdout``) or a FIFO is
  written in place, never replaced. A symbolic link is followed: its target is written, the link stays.
- A regular file (or a new one) is written to a temporary file in the same directory, flushed and fsync'd, given
  the mode of the file it replaces (a new file: 0666 less the umask), renamed over the target, and the directory
  is fsync'd: after a crash the path holds the old file or the new one, whole.
- A failure while writing (a full disk, a file-size limit, an I/O error) leaves the previous file intact and no
  temporary file behind, and raises `OutputError` with one line.
"""

from __future__ import annotations

import errno
import os
import stat
import sys
import tempfile
from collections.abc import Iterable

STDOUT = "-"
_TEMP_PREFIX = ".rigidbench-"


class OutputError(Exception):
    """An output path that cannot be written; reported in one line (exit status 2)."""


def _target(path: str) -> str:
    """The path a write lands on: symbolic links followed (``/dev/stdout`` included)."""
    return os.path.realpath(path)


def in_place(path: str) -> bool:
    """Whether `path` is written in place (standard output, a character device or a FIFO), not replaced."""
    if path == STDOUT:
        return True
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode)


def check(path: str, option: str) -> None:
    """Refuse an output path that cannot be written, before anything is simulated.

    Raises
    ------
    OutputError
        Naming the option and the path, and what is wrong with it.
    """
    if path == STDOUT:
        return
    if not path:
        raise OutputError(f"{option}: an empty path")
    target = _target(path)
    where = f"{option} {path}" + (f" (-> {target})" if os.path.islink(path) else "")
    try:
        st = os.stat(target)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise OutputError(f"{where}: {exc.strerror}") from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise OutputError(f"{where} is a directory; give a file name")
        if stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode):
            if not os.access(target, os.W_OK):
                raise OutputError(f"{where}: permission denied")
            return
        if not stat.S_ISREG(st.st_mode):
            raise OutputError(f"{where} is neither a regular file nor a device or FIFO")
    name = os.path.basename(target)
    parent = os.path.dirname(target)
    # The first ancestor that exists must be a directory we can write (the missing ones are created).
    ancestor = parent
    while not os.path.exists(ancestor):
        ancestor = os.path.dirname(ancestor)
    if not os.path.isdir(ancestor):
        raise OutputError(f"{where}: {ancestor} is not a directory")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise OutputError(f"{where}: the directory {ancestor} is not writable")
    try:
        name_max = os.pathconf(ancestor, "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    longest = max([len(part.encode()) for part in target.split(os.sep)] + [len(name.encode())])
    if longest > name_max:
        raise OutputError(f"{where}: a file name longer than {name_max} bytes")
    try:
        path_max = os.pathconf(ancestor, "PC_PATH_MAX")
    except (OSError, ValueError):
        path_max = 4096
    if len(target.encode()) >= path_max:
        raise OutputError(f"{where}: the path is longer than {path_max} bytes")


def check_all(outputs: Iterable[tuple[str, str | None]]) -> None:
    """`check` every (option, path) given, and refuse one file given to two options.

    Raises
    ------
    OutputError
    """
    seen: dict[str, str] = {}
    for option, path in outputs:
        if path is None:
            continue
        check(path, option)
        if path == STDOUT or in_place(path):
            continue
        target = _target(path)
        if target in seen:
            raise OutputError(f"{option} {path} is the same file as {seen[target]}; give each output its own file")
        seen[target] = f"{option} {path}"


def write(path: str, text: str, option: str = "output") -> None:
    """Write `text` to `path` by the rules of the module docstring.

    Raises
    ------
    OutputError
        If the write fails; the previous file is left as it was and no temporary file remains.
    """
    write_bytes(path, text.encode(), option)


def write_bytes(path: str, data: bytes, option: str = "output") -> None:
    """`write` for bytes (a PNG)."""
    if path == STDOUT:
        try:
            sys.stdout.flush()
            write_all(sys.stdout.fileno(), data)
        except OSError as exc:
            raise OutputError(f"{option} -: cannot write to standard output: {exc.strerror}") from None
        return
    target = _target(path)
    if in_place(target):
        try:
            fd = os.open(target, os.O_WRONLY)
            try:
                write_all(fd, data)
            finally:
                os.close(fd)
        except OSError as exc:
            raise OutputError(f"{option} {path}: cannot write: {exc.strerror}") from None
        return
    directory = os.path.dirname(target)
    try:
        os.makedirs(directory, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=_TEMP_PREFIX, suffix=".tmp")
    except OSError as exc:
        raise OutputError(f"{option} {path}: cannot write in {directory}: {exc.strerror}") from None
    try:
        try:
            write_all(fd, data)
            os.fsync(fd)
            os.fchmod(fd, _mode_for(target))
        finally:
            os.close(fd)
        os.replace(tmp, target)
    except OSError as exc:
        _unlink(tmp)
        raise OutputError(f"{option} {path}: cannot write: {exc.strerror}") from None
    except BaseException:
        _unlink(tmp)
        raise
    _fsync_directory(directory)


def write_all(fd: int, data: bytes) -> None:
    """Write every byte (`os.write` may write fewer than asked); a write that makes no progress is an error."""
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        if n <= 0:
            raise OSError(errno.EIO, "short write")
        view = view[n:]


def _mode_for(target: str) -> int:
    try:
        return stat.S_IMODE(os.stat(target).st_mode)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _fsync_directory(directory: str) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass  # some file systems cannot fsync a directory; the rename is done either way
    finally:
        os.close(fd)


def _unlink(path: str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass
