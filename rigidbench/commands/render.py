"""``rigidbench render``: a case rendered headless to .gif, .mp4 or .png."""

from __future__ import annotations

import argparse
import sys

from rigidbench.commands import shared
from rigidbench.exits import EXIT_FAIL, EXIT_OK, UsageError


def arguments(sub) -> None:
    p = sub.add_parser(
        "render",
        help="render a case headless to .gif, .mp4 (needs ffmpeg) or .png",
        description="Simulate a case (as 'run' does) and render it offscreen (EGL, or OSMesa as a fallback) with "
        "a camera that frames the whole motion. The clip spans the whole run in slow motion.",
    )
    p.add_argument("target", metavar="TARGET", help="'scenario' (its first case) or 'scenario:case'")
    p.add_argument("--out", required=True, metavar="FILE", help="output file: .gif, .mp4 or .png")
    shared.settings_arguments(p)
    shared.sets_argument(p, "override a parameter")
    p.add_argument("--frames", type=int, default=90, help="frames over the run (default 90)")
    p.add_argument("--fps", type=shared.positive_float, default=30.0, help="playback frames per second (default 30)")
    p.add_argument("--size", default="480x360", metavar="WxH", help="pixels (default 480x360)")
    p.add_argument("--at", type=float, metavar="SECONDS", help="for .png: the simulated time (default 0)")
    p.add_argument("--no-trail", action="store_true", help="do not draw the centre-of-mass trail")


def main(args: argparse.Namespace) -> int:
    import os
    import subprocess

    from rigidbench import outputs, registry, render

    outputs.check_all([("--out", args.out)])
    try:
        settings = shared.settings(args)
        width, _, height = args.size.lower().partition("x")
        try:
            size = (int(width), int(height))
        except ValueError:
            raise ValueError(f"--size expects WxH in pixels, got {args.size!r}") from None
        scenario, cases = registry.parse_target(args.target)
        overrides = {n: scenario.param(n).parse(v) for n, v in shared.parse_sets(args.sets).items()}
        if os.path.splitext(args.out)[1].lower() not in render.FORMATS:
            raise ValueError(f"--out {args.out!r}: the extension must be one of {', '.join(render.FORMATS)}")
        still = os.path.splitext(args.out)[1].lower() == ".png"
        clip = render.render_clip(
            f"{scenario.slug}:{cases[0]}",
            overrides=overrides,
            settings=settings,
            frames=args.frames,
            fps=args.fps,
            width=size[0],
            height=size[1],
            at=(args.at or 0.0) if still else None,
            trail=not args.no_trail,
        )
        print(render.write(clip, args.out))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    except render.RenderError as exc:
        # EGL is what `import rigidbench` picks without a display; OSMesa is the software fallback. A backend
        # is chosen once per process, so the retry is a fresh process.
        if (
            isinstance(exc, render.NoGLContext)
            and os.environ.get("MUJOCO_GL") == "egl"
            and not os.environ.get("RIGIDBENCH_NO_GL_FALLBACK")
        ):
            print(f"rigidbench: {exc}; retrying with MUJOCO_GL=osmesa", file=sys.stderr)
            env = {**os.environ, "MUJOCO_GL": "osmesa", "PYOPENGL_PLATFORM": "osmesa", "RIGIDBENCH_NO_GL_FALLBACK": "1"}
            return subprocess.run([sys.executable, "-m", "rigidbench", *sys.argv[1:]], env=env, check=False).returncode
        print(f"rigidbench: error: {exc}", file=sys.stderr)
        return EXIT_FAIL
    return EXIT_OK
