"""Where an env's step spends its time: py-spy samples a loop of zero-action steps, and the samples inside
``env.step`` are summed by source line (the line a sample was executing, C calls included in their line).

    python benchmarks/profile_step.py                                  # rigidbench/SimplePendulum-v0
    python benchmarks/profile_step.py rigidbench/StruckStick-v0 --steps 300000 --top 20

Needs py-spy (``pip install -e ".[bench]"``). The share of ``mujoco.mj_step``'s line is the physics; the rest is
the Python layer (gymnasium's wrappers included). Shares, not times: they hold on a loaded machine.
"""

from __future__ import annotations

import argparse
import collections
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]


def loop(env_id: str, steps: int) -> None:
    """`steps` zero-action steps of `env_id` (frame_skip 1), resetting when an episode ends."""
    import gymnasium as gym
    import numpy as np

    import rigidbench.envs  # noqa: F401 (registers the envs)

    env = gym.make(env_id, frame_skip=1)
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape)
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()


def top_lines(raw: pathlib.Path, root: str = "step") -> tuple[int, list[tuple[str, int]]]:
    """Samples under a frame of a function or method named `root` (``step``, ``ScenarioEnv.step``; not ``rk_step``)
    that no ``reset`` frame encloses (the ODE solver a reset may run has its own ``OdeSolver.step``), by the line
    they were executing."""
    counts: collections.Counter[str] = collections.Counter()
    total = 0
    for line in raw.read_text().splitlines():
        stack, _, n = line.rpartition(" ")
        frames = stack.split(";")
        names = [f.split(" (")[0].rpartition(".")[2] for f in frames]
        outer = next((name for name in names if name in (root, "reset")), None)
        if outer != root:
            continue
        total += int(n)
        counts[frames[-1]] += int(n)
    return total, counts.most_common()


def _short(frame: str) -> str:
    """A frame with its path relative to the repository or to site-packages."""
    return re.sub(r"\((?:.*/site-packages/|" + re.escape(str(ROOT)) + "/)", "(", frame)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("env_id", nargs="?", default="rigidbench/SimplePendulum-v0")
    parser.add_argument("--steps", type=int, default=200_000, help="steps to sample (default 200000)")
    parser.add_argument("--top", type=int, default=15, help="lines to print (default 15)")
    parser.add_argument("--loop", action="store_true", help=argparse.SUPPRESS)  # the sampled child
    args = parser.parse_args(argv)
    if args.steps < 1 or args.top < 1:
        parser.error("--steps and --top must be positive")
    if args.loop:
        loop(args.env_id, args.steps)
        return 0
    spy = shutil.which("py-spy") or str(pathlib.Path(sys.executable).with_name("py-spy"))
    if not pathlib.Path(spy).exists():
        print("py-spy is not installed: pip install -e '.[bench]'", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        raw = pathlib.Path(tmp) / "samples.txt"
        child = [sys.executable, __file__, args.env_id, "--steps", str(args.steps), "--loop"]
        subprocess.run([spy, "record", "-r", "2000", "-f", "raw", "-o", str(raw), "--", *child], check=True)
        total, lines = top_lines(raw)
    if not total:
        print("no samples inside env.step", file=sys.stderr)
        return 1
    print(f"{args.env_id}: {total} samples inside env.step")
    for frame, n in lines[: args.top]:
        print(f"{100 * n / total:5.1f} %  {_short(frame)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
