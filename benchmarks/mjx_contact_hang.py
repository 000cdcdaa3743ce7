"""Reproduce the intermittent MJX hang on colliding models (docs/engines.md, "Runs, censuses and power tables").

The census `rigidbench census cross-section:equal-mass --n 2 --seed 1 --engine mjx` gathers two draws' beams (990
and 614 worlds of two colliding spheres) into one MJX rollout. This script captures that rollout's requests once,
then replays the first (990 worlds x 9 steps, the program sharing one model) in fresh processes, each with a time
limit, and counts the runs that never finished: XLA's threads idle and the result never set, on a 2-core CPU with
jaxlib 0.10.2. `--slices N` replays it as rigidbench now runs it on the CPU, in slices of N worlds.

    python benchmarks/mjx_contact_hang.py --runs 5                 # as one batch: 5 of 9 hung here (two runs)
    python benchmarks/mjx_contact_hang.py --runs 5 --slices 128    # rigidbench's slices: 0 of 9 hung here
    python benchmarks/mjx_contact_hang.py --runs 8 --plain argument --export hang/   # MJX alone: 3 of 8 hung here
    python benchmarks/mjx_contact_hang.py --runs 8 --plain closed                    # the model a constant: 0 of 8

Needs the `mjx` extra. Each run compiles MJX's program (~12 s on 2 cores); a run past `--limit` seconds counts as hung.
"""

from __future__ import annotations

import argparse
import os
import pickle
import subprocess
import sys
import tempfile
import time

import numpy as np

CAPTURE = """
import os, pickle, sys
from rigidbench.engines import mjx
from rigidbench.scenario import Scenario
mjx._collides = lambda model: False  # capture the gathered batch of both draws' models
# Both draws' contacts are too shallow for float32 (contact floors 0.14 and 0.86: refused since 2026-11-26 (e)); the
# hang is XLA's, whatever the physics, so the capture runs them anyway.
Scenario.check_precision = lambda *args, **kwargs: None
def capture(part):
    if len(part) > 1:
        rows = [dict(model=r.model, states0=r.states0, nstep=r.nstep, control=r.control) for r in part]
        pickle.dump(rows, open(sys.argv[1], "wb"))
        os._exit(0)
    raise SystemExit("no gathered batch to capture")
mjx._mjx_batch = capture
from rigidbench.cli import main
main(["census", "cross-section:equal-mass", "--n", "2", "--seed", "1", "--engine", "mjx", "--quiet"])
"""

REPLAY = """
import pickle, sys, time
from rigidbench import engines
from rigidbench.engines import mjx
mjx.MJX_CONTACT_WORLDS = int(sys.argv[2])
row = pickle.load(open(sys.argv[1], "rb"))[0]
request = engines._Request(engines.engine_for("mjx"), row["model"], row["states0"], row["nstep"], row["control"])
request.prepare()
t = time.perf_counter()
mjx._mjx_batch([request])
print(f"finished: {len(row['states0'])} worlds x {row['nstep']} steps in {time.perf_counter() - t:.1f} s", flush=True)
"""


# The same rollout with MJX alone (no rigidbench in the process): the model as MuJoCo's binary, the worlds' initial
# qpos, qvel and time from the captured states (mjSTATE_FULLPHYSICS: time, qpos, qvel, ...), and a plain
# jit(vmap(scan(mjx.step))) returning every step's qpos and qvel; the MJX model either closed over (a constant of the
# program) or, as rigidbench passes it so that one compiled program serves every model of a structure, an argument.
# What a JAX issue can attach.
REPLAY_PLAIN = """
import sys, time
import numpy as np, mujoco, jax, jax.numpy as jnp
from mujoco import mjx
model = mujoco.MjModel.from_binary_path(sys.argv[1] + "/model.mjb")
z = np.load(sys.argv[1] + "/worlds.npz")
nstep = int(z["nstep"])
mx = mjx.put_model(model)
d0 = mjx.put_data(model, mujoco.MjData(model))
def one(m, qpos, qvel, t):
    def body(d, _):
        d = mjx.step(m, d)
        return d, (d.qpos, d.qvel)
    return jax.lax.scan(body, d0.replace(qpos=qpos, qvel=qvel, time=t), None, length=nstep)[1]
args = [jnp.asarray(z[k], dtype=d0.qpos.dtype) for k in ("qpos", "qvel", "time")]
if sys.argv[2] == "argument":
    run = jax.jit(lambda m, *a: jax.vmap(lambda *w: one(m, *w))(*a))
    call = lambda: run(mx, *args)
else:
    run = jax.jit(lambda *a: jax.vmap(lambda *w: one(mx, *w))(*a))
    call = lambda: run(*args)
t = time.perf_counter()
out = np.asarray(call()[0])
took = time.perf_counter() - t
print(f"finished: {out.shape[0]} worlds x {nstep} steps (MJX alone, model {sys.argv[2]}) in {took:.1f} s")
"""


def export(path: str, folder: str) -> int:
    """Write the captured rollout's first request as `folder`/model.mjb and `folder`/worlds.npz (qpos, qvel, time,
    nstep); return its number of worlds."""
    import mujoco

    row = pickle.load(open(path, "rb"))[0]
    model, states = row["model"], row["states0"]
    if row["control"] is not None and model.nu:
        raise SystemExit("mjx_contact_hang.py: the captured rollout has controls; --plain replays none")
    try:
        os.makedirs(folder, exist_ok=True)
        mujoco.mj_saveModel(model, os.path.join(folder, "model.mjb"), None)
        nq, nv = model.nq, model.nv
        np.savez(
            os.path.join(folder, "worlds.npz"),
            time=states[:, 0],
            qpos=states[:, 1 : 1 + nq],
            qvel=states[:, 1 + nq : 1 + nq + nv],
            nstep=row["nstep"],
        )
    except (OSError, ValueError) as exc:
        raise SystemExit(f"mjx_contact_hang.py: cannot write the rollout to {folder!r}: {exc}") from None
    return len(states)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="fresh processes to replay in (default 5)")
    parser.add_argument("--slices", type=int, default=0, help="worlds per program call (default 0: one batch)")
    parser.add_argument("--limit", type=float, default=90.0, help="seconds before a run counts as hung (default 90)")
    parser.add_argument(
        "--plain",
        choices=("closed", "argument"),
        help="replay with MJX alone (jit(vmap(scan(mjx.step)))), no rigidbench: the model closed over or an argument",
    )
    parser.add_argument("--export", metavar="DIR", help="also keep the rollout as DIR/model.mjb and DIR/worlds.npz")
    args = parser.parse_args(argv)
    if args.runs < 1 or args.limit <= 0 or args.slices < 0:
        parser.error("--runs >= 1, --limit > 0 and --slices >= 0")
    if args.plain and args.slices:
        parser.error("--plain replays one batch: no --slices")
    try:
        import mujoco.mjx  # noqa: F401
    except ImportError:
        parser.exit(2, "mjx_contact_hang.py: needs MJX: pip install 'rigidbench[mjx]'\n")
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "requests.pkl")
        capture = subprocess.run([sys.executable, "-c", CAPTURE, path], capture_output=True, text=True, timeout=600)
        if capture.returncode != 0:
            parser.exit(1, f"mjx_contact_hang.py: capturing the census's rollout failed: {capture.stderr[-300:]}\n")
        folder = args.export or os.path.join(tmp, "plain")
        worlds = export(path, folder) if args.plain or args.export else len(pickle.load(open(path, "rb"))[0]["states0"])
        width = args.slices or worlds
        code, where, how = (REPLAY_PLAIN, folder, args.plain) if args.plain else (REPLAY, path, str(width))
        hung = 0
        for i in range(args.runs):
            t = time.perf_counter()
            try:
                out = subprocess.run(
                    [sys.executable, "-c", code, where, how],
                    capture_output=True,
                    text=True,
                    timeout=args.limit,
                )
                verdict = out.stdout.strip().splitlines()[-1] if out.returncode == 0 else f"failed: {out.stderr[-300:]}"
            except subprocess.TimeoutExpired:
                hung += 1
                verdict = f"hung (no result after {args.limit:.0f} s)"
            print(f"run {i + 1}/{args.runs} ({time.perf_counter() - t:.0f} s): {verdict}", flush=True)
    mode = f"MJX alone, the model {args.plain}" if args.plain else f"slices of {width}"
    print(f"{hung} of {args.runs} runs hung ({worlds} worlds, {mode})")
    return 1 if hung else 0


if __name__ == "__main__":
    raise SystemExit(main())
