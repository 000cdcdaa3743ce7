"""An append-only JSON-lines record of a run, so that nothing a user ran is lost.

Line 1 is a header: the format, the journal's kind (``run``, ``census``, ``sweep``), the rigidbench and MuJoCo
versions, and the invocation: *what to run* (targets, parameters, settings, grid), never where to write. Every
following line is one finished result row, carrying the ``job`` it belongs to (its key: ``scenario:case`` plus the
job's own parameters, if any) and ``job_size`` (how many rows that job has). All rows of a job are written with one
``write`` on an ``O_APPEND`` descriptor (completed if the kernel writes fewer bytes) and fsync'd before the next job
starts, so after a crash, Ctrl-C or SIGTERM the file holds every finished job.

Reading is strict about what must be right and tolerant of what a crash can do:

- a header that is not a rigidbench journal of this format and kind, or of another rigidbench or MuJoCo version,
  a row that is not an object with a ``job`` and a ``job_size``, bytes that are not UTF-8: `JournalError` naming
  the file and line (exit 2);
- a torn last line (power loss mid-write) is dropped; a damaged line in the middle (not JSON) is named in a
  warning and skipped, and the valid rows after it are kept;
- a job counts as done only when all its rows are present; rows beyond its size are ignored with a warning.

Whether the rows were produced by the jobs and settings the invocation plans is for the caller to check
(`verify`). One process writes a journal at a time: `lock` holds an exclusive lock on it for the run's life.
"""

from __future__ import annotations

import fcntl
import json
import os
import sys
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import mujoco

from rigidbench.outputs import write_all as _write_all
from rigidbench.results import _jsonable

FORMAT = "rigidbench-journal/2"
KINDS = ("run", "census", "sweep", "frontier")


class JournalError(ValueError):
    """A journal that cannot be used (malformed, foreign, busy, unwritable); one line, exit status 2."""


@dataclass
class Journal:
    """The contents of a journal file: its header and the rows of every completed job.

    Attributes
    ----------
    lines : dict of str to int
        The line number (1-based) at which each completed job's first row stands.
    end : int
        Byte offset just past the last line of the last completed job (what `truncate_tail` keeps).
    warnings : list of str
        Damaged lines skipped, duplicate rows ignored.
    """

    header: dict[str, Any]
    rows: list[dict[str, Any]] = field(default_factory=list)
    lines: dict[str, int] = field(default_factory=dict)
    end: int = 0
    warnings: list[str] = field(default_factory=list)

    @property
    def done(self) -> set[str]:
        return set(self.lines)

    @property
    def invocation(self) -> dict[str, Any]:
        return self.header["invocation"]

    def by_job(self) -> dict[str, list[dict[str, Any]]]:
        """The rows of every complete job, by job key (what `rigidbench.runner.run_jobs` skips)."""
        out: dict[str, list[dict[str, Any]]] = {}
        for row in self.rows:
            out.setdefault(row["job"], []).append(row)
        return out


def header(kind: str, invocation: Mapping[str, Any]) -> dict[str, Any]:
    from rigidbench import __version__

    if kind not in KINDS:
        raise ValueError(f"journal kind {kind!r} is not one of {', '.join(KINDS)}")
    return {
        "format": FORMAT,
        "kind": kind,
        "rigidbench": __version__,
        "mujoco": mujoco.__version__,
        "invocation": dict(invocation),
    }


def start(path: str, kind: str, invocation: Mapping[str, Any]) -> None:
    """Make `path` a journal holding only the header (truncating what was there; hold its `lock` first).

    Raises
    ------
    JournalError
        If it cannot be written.
    """
    text = json.dumps(header(kind, invocation)) + "\n"
    try:
        directory = os.path.dirname(os.path.abspath(path))
        os.makedirs(directory, exist_ok=True)
        fd = os.open(path, os.O_WRONLY | os.O_CREAT, 0o666)
        try:
            os.ftruncate(fd, 0)
            _write_all(fd, text.encode())
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError as exc:
        raise JournalError(f"cannot write journal {path}: {exc.strerror}") from None


def append(path: str, job: str, rows: Iterable[dict[str, Any]]) -> None:
    """Append one finished job's rows in a single write (completed if short), then fsync.

    Raises
    ------
    JournalError
        If the rows cannot be written whole (a full disk, a file-size limit): the run must stop, since a row it
        could not journal would be lost to a resume.
    """
    rows = list(rows)
    text = "".join(json.dumps(_jsonable({**r, "job": job, "job_size": len(rows)})) + "\n" for r in rows)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND)
        try:
            _write_all(fd, text.encode())
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError as exc:
        raise JournalError(
            f"cannot append to journal {path}: {exc.strerror}; it holds the jobs finished before this one"
        ) from None


def read(path: str, kind: str) -> Journal:
    """Read a journal of `kind`, keeping only the rows of complete jobs (module docstring for what is refused,
    skipped or dropped).

    Raises
    ------
    JournalError
        Naming the file (and the line) for a journal that is missing, malformed, of another kind, or written by
        another rigidbench or MuJoCo version.
    """
    from rigidbench import __version__

    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise JournalError(f"cannot read journal {path}: {exc.strerror}") from None
    lines = data.split(b"\n")
    head = _json_line(path, 1, lines[0])
    if not isinstance(head, dict) or not str(head.get("format", "")).startswith("rigidbench-journal/"):
        raise JournalError(f"{path}:1: not a rigidbench journal")
    if head["format"] != FORMAT:
        raise JournalError(
            f"{path}:1: a journal of format {head['format']!r}, this rigidbench reads {FORMAT!r}; start a new journal"
        )
    for key, kinds in (("kind", str), ("rigidbench", str), ("mujoco", str), ("invocation", dict)):
        if not isinstance(head.get(key), kinds):
            raise JournalError(f"{path}:1: the header has no valid {key!r}")
    if head["kind"] != kind:
        raise JournalError(f"{path} is a {head['kind']} journal; resume it with 'rigidbench {head['kind']} --resume'")
    if head["rigidbench"] != __version__:
        raise JournalError(
            f"{path} was written by rigidbench {head['rigidbench']}, this is {__version__}: results would mix versions"
        )
    if head["mujoco"] != mujoco.__version__:
        raise JournalError(
            f"{path} was written with mujoco {head['mujoco']}, this is {mujoco.__version__}: results would mix versions"
        )
    journal = Journal(head, end=len(lines[0]) + 1)
    # A job's rows are written contiguously in one write: a group cut short (by a damaged line, or followed by
    # another job's rows) is dropped and its job runs again; it is never completed with rows of another run.
    group: list[dict[str, Any]] = []
    group_line = 0
    offset = len(lines[0]) + 1
    last = len(lines) - 1
    while last > 0 and not lines[last].strip():
        last -= 1

    def drop(reason: str) -> None:
        if group:
            journal.warnings.append(f"{path}:{group_line}: the rows of job {group[0]['job']!r} {reason}; it runs again")
            group.clear()

    for number, raw in enumerate(lines[1:], start=2):
        offset += len(raw) + 1
        if not raw.strip():
            continue
        try:
            text = raw.decode()
        except UnicodeDecodeError:
            raise JournalError(f"{path}:{number}: the line is not UTF-8 text") from None
        try:
            row = json.loads(text)
        except json.JSONDecodeError:
            if number - 1 == last:
                continue  # a torn last line: everything before it is intact
            journal.warnings.append(f"{path}:{number}: a damaged line (not JSON) was skipped")
            drop("were cut short by it")
            continue
        if not isinstance(row, dict):
            raise JournalError(f"{path}:{number}: a row must be a JSON object, not {type(row).__name__}")
        job, size = row.get("job"), row.get("job_size")
        if not isinstance(job, str) or not job or not isinstance(size, int) or isinstance(size, bool) or size < 1:
            raise JournalError(f"{path}:{number}: a row needs a 'job' name and a positive integer 'job_size'")
        if group and (group[0]["job"] != job or group[0]["job_size"] != size):
            drop("stop short of its size")
        if job in journal.lines:
            journal.warnings.append(f"{path}:{number}: a further row of the finished job {job!r} was ignored")
            continue
        if not group:
            group_line = number
        group.append(row)
        if len(group) == size:
            journal.rows.extend(group)
            journal.lines[job] = group_line
            journal.end = min(offset, len(data))
            group.clear()
    return journal


def _json_line(path: str, number: int, raw: bytes) -> Any:
    try:
        return json.loads(raw.decode())
    except UnicodeDecodeError:
        raise JournalError(f"{path}:{number}: the line is not UTF-8 text") from None
    except json.JSONDecodeError:
        raise JournalError(f"{path}:{number}: not a rigidbench journal (the header is not JSON)") from None


def truncate_tail(path: str, journal: Journal) -> None:
    """Drop what follows the last complete job (a torn line, the rows of a job cut short) in place, keeping the
    file (and its lock) the same.

    Raises
    ------
    JournalError
        If it cannot be written.
    """
    try:
        with open(path, "r+b") as f:
            f.seek(0, os.SEEK_END)
            if f.tell() > journal.end:
                f.truncate(journal.end)
                f.flush()
                os.fsync(f.fileno())
    except OSError as exc:
        raise JournalError(f"cannot write journal {path}: {exc.strerror}") from None


def verify(path: str, journal: Journal, expected: Mapping[str, tuple[dict[str, Any], int]]) -> None:
    """Check that every finished job in `journal` is one the invocation plans, ran with the settings it plans,
    and has as many rows as its case has checks.

    Parameters
    ----------
    expected : mapping of job key to (settings record, number of checks)
        The settings each planned job runs with, read back from its compiled model (`read_settings`), and the
        rows it yields (a diverged or failed job yields one row instead).

    Raises
    ------
    JournalError
        Naming the file, the line and the job: results would mix settings, or a forged or truncated job would
        pass as done.
    """
    for job, rows in journal.by_job().items():
        line = journal.lines[job]
        if job not in expected:
            raise JournalError(f"{path}:{line}: job {job!r} is not one this journal's invocation plans")
        settings, nchecks = expected[job]
        want = _normal(settings)
        for i, row in enumerate(rows):
            got = _normal(row.get("settings"))
            if got != want:
                diff = sorted(k for k in set(want) | set(got or {}) if (got or {}).get(k) != want.get(k))
                raise JournalError(
                    f"{path}:{line + i}: job {job!r} ran with other settings ({', '.join(diff) or 'none'}) than this "
                    "run plans: results would mix settings"
                )
        single = len(rows) == 1 and rows[0].get("status") in ("diverged", "error")
        if len(rows) != nchecks and not single:
            raise JournalError(f"{path}:{line}: job {job!r} has {len(rows)} rows, its case has {nchecks} checks")


def _normal(settings: Any) -> Any:
    return json.loads(json.dumps(_jsonable(settings))) if settings is not None else None


def warn(journal: Journal) -> None:
    for message in journal.warnings:
        print(f"rigidbench: warning: {message}", file=sys.stderr)


# ---- one writer at a time ------------------------------------------------------------------------------------


@contextmanager
def lock(path: str, *, create: bool = True) -> Iterator[None]:
    """Hold an exclusive lock on the journal at `path` for the life of the block (creating the file if `create`).

    Raises
    ------
    JournalError
        If the journal is missing (and not to be created), cannot be opened, or another process holds it,
        naming that process when the system says which.
    """
    try:
        if create:
            os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        fd = os.open(path, os.O_RDWR | (os.O_CREAT if create else 0), 0o666)
    except FileNotFoundError:
        raise JournalError(f"no journal at {path}") from None
    except OSError as exc:
        raise JournalError(f"cannot open journal {path}: {exc.strerror}") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            who = f"process {holder}" if holder else "another process"
            raise JournalError(f"journal {path} is being written by {who}; one run per journal") from None
        yield
    finally:
        os.close(fd)  # releases the lock


def _holder(fd: int) -> int | None:
    """The pid holding a flock on the file open at `fd` (Linux: /proc/locks), or None."""
    st = os.fstat(fd)
    inode = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}:{st.st_ino}"
    try:
        with open("/proc/locks") as f:
            for line in f:
                parts = line.split()
                if len(parts) >= 6 and parts[1] == "FLOCK" and parts[5] == inode:
                    pid = int(parts[4])
                    if pid != os.getpid():
                        return pid
    except (OSError, ValueError):
        return None
    return None
