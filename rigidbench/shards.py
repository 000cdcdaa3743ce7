"""Shards: a Monte Carlo batch split into independent calls that a cluster can run (issue 17).

A scenario whose `simulate` is a batch of independent samples (the cross-section's beam) cuts it into shards fixed
by its parameters (never by the number of workers) and maps them through `map`: one after another in this process
by default; under ``--cluster`` the runner puts the cluster's map in effect (`use`) while it runs such a case, and
each shard runs on a worker. Shard results are merged exactly (integer counts), so the result does not depend on
where, or in how many processes, the shards ran.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Callable, Iterator, Sequence
from typing import Any

_MAP: contextvars.ContextVar[Callable | None] = contextvars.ContextVar("rigidbench_shard_map", default=None)


@contextlib.contextmanager
def use(map_fn: Callable[[Callable, Sequence[tuple]], Iterator[tuple[int, Any]]] | None) -> Iterator[None]:
    """Run the shards of the cases simulated inside this block with `map_fn` (an executor's ``map``)."""
    token = _MAP.set(map_fn)
    try:
        yield
    finally:
        _MAP.reset(token)


def map(fn: Callable, calls: Sequence[tuple]) -> Iterator[tuple[int, Any]]:  # noqa: A001 - the executors' name
    """Yield ``(index, fn(*calls[index]))`` for every call, in any order: here in turn, or with the map in effect.

    Raises
    ------
    Exception
        The first exception a shard raised (a cluster hands failed calls back as values; they are raised here).
    """
    map_fn = _MAP.get()
    if map_fn is None:
        for i, args in enumerate(calls):
            yield i, fn(*args)
        return
    for i, result in map_fn(fn, calls):
        if isinstance(result, BaseException):
            raise result
        yield i, result
