"""An append-only JSON-lines record of a run, so that nothing a user ran is lost.

Line 1 is a header: the rigidbench and MuJoCo versions and the invocation (targets, profile, overrides), enough
to resume the run. Every following line is one finished result row, carrying the ``job`` it belongs to
(``scenario:case``) and ``job_size`` (how many rows that job has). All rows of a job are written with one
``write`` on an ``O_APPEND`` descriptor and fsync'd before the next job starts, so after a crash, Ctrl-C or
SIGTERM the file holds every finished job; a torn last line (power loss mid-write) is ignored on reading, and a
job counts as done only when all its rows are present.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import mujoco

from rigidbench.results import _jsonable

FORMAT = "rigidbench-journal/1"


@dataclass
class Journal:
    """The contents of a journal file: its header and the rows of every completed job."""

    header: dict[str, Any]
    rows: list[dict[str, Any]] = field(default_factory=list)

    @property
    def done(self) -> set[str]:
        counts: dict[str, int] = {}
        sizes: dict[str, int] = {}
        for row in self.rows:
            counts[row["job"]] = counts.get(row["job"], 0) + 1
            sizes[row["job"]] = row["job_size"]
        return {job for job, n in counts.items() if n == sizes[job]}

    def by_job(self) -> dict[str, list[dict[str, Any]]]:
        """The rows of every complete job, by job key (what `rigidbench.runner.run_jobs` skips)."""
        out: dict[str, list[dict[str, Any]]] = {}
        for row in self.rows:
            out.setdefault(row["job"], []).append(row)
        return out


def header(invocation: Mapping[str, Any]) -> dict[str, Any]:
    from rigidbench import __version__

    return {"format": FORMAT, "rigidbench": __version__, "mujoco": mujoco.__version__, "invocation": dict(invocation)}


def start(path: str, invocation: Mapping[str, Any]) -> None:
    """Create (or truncate) a journal at `path` holding only the header."""
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    with open(path, "w") as f:
        f.write(json.dumps(header(invocation)) + "\n")
        f.flush()
        os.fsync(f.fileno())


def append(path: str, job: str, rows: Iterable[dict[str, Any]]) -> None:
    """Append one finished job's rows in a single write, then fsync."""
    rows = list(rows)
    text = "".join(json.dumps(_jsonable({**r, "job": job, "job_size": len(rows)})) + "\n" for r in rows)
    fd = os.open(path, os.O_WRONLY | os.O_APPEND)
    try:
        os.write(fd, text.encode())
        os.fsync(fd)
    finally:
        os.close(fd)


def read(path: str) -> Journal:
    """Read a journal, keeping only the rows of complete jobs and ignoring a torn last line.

    Raises
    ------
    ValueError
        If the file is missing, empty, or not a rigidbench journal.
    """
    try:
        with open(path) as f:
            lines = f.read().split("\n")
    except OSError as exc:
        raise ValueError(f"cannot read journal {path!r}: {exc.strerror}") from None
    try:
        head = json.loads(lines[0])
    except (json.JSONDecodeError, IndexError):
        raise ValueError(f"{path!r} is not a rigidbench journal (no header line)") from None
    if not isinstance(head, dict) or head.get("format") != FORMAT:
        raise ValueError(f"{path!r} is not a rigidbench journal (format {head.get('format')!r})")
    rows = []
    for line in lines[1:]:
        if not line.strip():
            continue
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:
            break  # a torn last line: everything before it is intact
    journal = Journal(head, rows)
    done = journal.done
    journal.rows = [r for r in rows if r["job"] in done]
    return journal


def rewrite(path: str, journal: Journal) -> None:
    """Rewrite the journal with only its complete jobs (dropping a torn tail before resuming)."""
    from rigidbench.results import atomic_write

    lines = [json.dumps(journal.header)] + [json.dumps(r) for r in journal.rows]
    atomic_write(path, "\n".join(lines) + "\n")
