"""Cross-case batching: the rollouts of a run's concurrent cases stepped as one batch per model structure.

A batched engine (MuJoCo Warp, MJX) steps thousands of worlds in one launch or one compiled program, and compiling
that program costs seconds; a case alone asks for a handful of worlds. Its `rollout` therefore goes through
`_rollout_request`: run now, or, inside a gathering (`gathering`, `Gather`: a run's cases on threads), wait until
every running case waits on one, then run the waiting requests together (`_run_requests`).

An engine that batches provides two hooks, called here and defined in its own module:

- ``engine._structure(model) -> (leaves, structure)``: the model on the device, and what another model must share
  with it to be stepped in the same batch (`rigidbench.engines.mjx.MjxEngine._structure`,
  `rigidbench.engines.warp.WarpEngine._structure`);
- ``engine._batch(part)``: step a list of `_Request` of one structure as one batch and `finish` each
  (`rigidbench.engines.mjx._mjx_batch`, `rigidbench.engines.warp._warp_batch`), with `_stacked_controls` and
  `_finish_all` to lay the requests' worlds side by side and hand each its rows back.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from rigidbench.engines.base import Engine, _layout
from rigidbench.engines.precision import clock


def _rollout_request(
    engine: Engine, model: mujoco.MjModel, states0: np.ndarray, nstep: int, control: np.ndarray | None
) -> np.ndarray:
    """A Warp or MJX rollout: run now, or, inside a gathering (`Gather`), with the others waiting."""
    states0 = np.asarray(states0, dtype=np.float64)
    if control is not None and np.shape(control) != (len(states0), nstep, model.nu):
        # here, in the case that asked: in a gathered batch it would fail every case of the batch
        raise ValueError(f"control has shape {np.shape(control)}, expected ({len(states0)}, {nstep}, {model.nu})")
    request = _Request(engine, model, states0, int(nstep), control)
    gather = _GATHERING
    if gather is not None and gather.member():
        return gather.submit(request)
    _run_requests([request])
    if request.error is not None:
        raise request.error
    return request.result


@dataclass(eq=False)
class _Request:
    """One rollout asked of an engine: a model, its initial states, steps and controls; its result when run."""

    engine: Any  # MjxEngine or WarpEngine
    model: mujoco.MjModel
    states0: np.ndarray
    nstep: int
    control: np.ndarray | None
    result: np.ndarray | None = None
    error: BaseException | None = None
    leaves: Any = None  # the model on the device (MJX: its flat arrays; Warp: the `mjw.Model`)
    key: Any = None

    def prepare(self) -> None:
        """The model on the device and the key of what it may share a batch with: the engine, the model's
        structure (`MjxEngine._structure`, `WarpEngine._structure`), the state's fields outside time, qpos and qvel
        (one start state for every world), and the number of controls."""
        self.leaves, structure = self.engine._structure(self.model)
        t, q, v = _layout(self.model)
        rest = np.delete(self.states0[0], np.r_[t, q, v]).tobytes()
        self.key = (self.engine, structure, rest, self.model.nu)

    def finish(self, states: np.ndarray) -> None:
        """This request's worlds' states after each step (its first `nstep`), float64; its clock `clock`."""
        t = _layout(self.model)[0]
        out = np.array(states[:, : self.nstep], dtype=np.float64)  # a copy: the batch's array is let go
        out[:, :, t] = clock(self.states0[:, 0], self.model.opt.timestep, self.nstep)[..., None]
        self.result, self.leaves = out, None


# A gathered batch's recorded states (float32 qpos and qvel per world and step, on the device and again on the host)
# are kept under this many bytes: a larger group is split, its requests sorted by run length so that each part pads
# the fewest steps.
GATHER_BYTES = 1 << 30


def _run_requests(requests: list[_Request], done: Callable[[list[_Request]], None] | None = None) -> None:
    """Run requests: each group of one engine and model structure (`_Request.key`) as one batch (the engine's
    `_batch`: `_mjx_batch`, `_warp_batch`), split where its recorded states would pass `GATHER_BYTES`; every world
    stepped to the longest run of its part and each request's own steps kept. `done` is told of each part as it
    finishes (and of the requests that failed to prepare), so their cases go on while the other parts run."""
    done = done or (lambda part: None)
    groups: dict[Any, list[_Request]] = {}
    for request in requests:
        try:
            request.prepare()
        except BaseException as exc:  # noqa: BLE001 - handed back to the case that asked (a refusal, say)
            request.error = exc
            done([request])
            continue
        groups.setdefault(request.key, []).append(request)
    for group in groups.values():
        group.sort(key=lambda r: r.nstep)
        part: list[_Request] = []
        for request in group:
            width = 4 * (request.model.nq + request.model.nv)
            worlds = sum(len(r.states0) for r in part) + len(request.states0)
            if part and worlds * request.nstep * width > GATHER_BYTES:
                _run_part(part)
                done(part)
                part = []
            part.append(request)
        _run_part(part)
        done(part)


def _run_part(part: list[_Request]) -> None:
    try:
        part[0].engine._batch(part)
    except BaseException as exc:  # noqa: BLE001 - every case of the batch gets it
        for request in part:
            request.error = exc


def _stacked_controls(part: list[_Request], nstep: int, nu: int) -> np.ndarray | None:
    """Every world's controls for `nstep` steps (zeros past a request's own steps), or None if none has any."""
    if all(r.control is None for r in part):
        return None
    controls = np.zeros((sum(len(r.states0) for r in part), nstep, nu))
    row = 0
    for r in part:
        if r.control is not None:
            controls[row : row + len(r.states0), : r.nstep] = r.control
        row += len(r.states0)
    return controls


def _finish_all(part: list[_Request], states: np.ndarray) -> None:
    """Hand each request its worlds' rows of a batch's `states` (worlds, steps, state)."""
    row = 0
    for r in part:
        r.finish(states[row : row + len(r.states0)])
        row += len(r.states0)


class Gather:
    """Gathers the MJX rollouts of cases running at once on threads (`rigidbench.runner.Gathered`): a member's
    rollout waits until every member is waiting on one, then the waiting rollouts run as one compiled batch per
    model structure (`_run_requests`). A census's draws of a case differ in their parameters, timestep and run
    length but share a structure: one program and one batch instead of one compile (8-24 s on this CPU) per draw.

    The members are the calls running or about to run: `calls` of them, at most `width` at once. A call that
    finishes (or fails) without a rollout hands its place to the next call, or, with none left, lets the others go
    on without it. After `close` (the run ended or was interrupted) every rollout runs at once.
    """

    def __init__(self, calls: int, width: int) -> None:
        self._cv = threading.Condition()
        self._members = min(calls, width)
        self._unstarted = calls - self._members
        self._waiting = 0
        self._closed = False
        self._pending: list[_Request] = []
        self._local = threading.local()

    @contextlib.contextmanager
    def member_of(self) -> Iterator[None]:
        self._local.member = True
        try:
            yield
        finally:
            self._local.member = False
            with self._cv:
                if self._unstarted > 0:  # the next call takes this place
                    self._unstarted -= 1
                else:
                    self._members -= 1
            self._flush_if_all_wait()

    def member(self) -> bool:
        return getattr(self._local, "member", False)

    def close(self) -> None:
        """No more calls will start: what waits runs now, and every later rollout at once."""
        with self._cv:
            self._closed = True
        self._flush_if_all_wait()

    def submit(self, request: _Request) -> np.ndarray:
        with self._cv:
            self._pending.append(request)
            self._waiting += 1
        self._flush_if_all_wait()
        with self._cv:
            while request.result is None and request.error is None:
                self._cv.wait()
        if request.error is not None:
            raise request.error
        return request.result

    def _flush_if_all_wait(self) -> None:
        """Run what is pending once every member waits (this thread runs it; the others wake with their results)."""
        with self._cv:
            if not self._pending or (self._waiting < self._members and not self._closed):
                return
            batch, self._pending = self._pending, []
        answered: set[int] = set()

        def done(part: list[_Request]) -> None:  # those cases go on (and journal) while the other parts run
            with self._cv:
                self._waiting -= len(part)  # answered: a member asking again is waiting anew
                answered.update(id(r) for r in part)
                self._cv.notify_all()

        try:
            _run_requests(batch, done)
        finally:
            left = [r for r in batch if id(r) not in answered]
            for request in left:
                if request.result is None and request.error is None:
                    request.error = RuntimeError("the gathered batch did not run")
            done(left)


_GATHERING: Gather | None = None


@contextlib.contextmanager
def gathering(gather: Gather) -> Iterator[Gather]:
    """Route the MJX rollouts of `gather`'s members through it for the block."""
    global _GATHERING
    previous, _GATHERING = _GATHERING, gather
    try:
        yield gather
    finally:
        _GATHERING = previous
