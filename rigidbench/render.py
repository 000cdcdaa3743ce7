"""Headless rendering of a scenario: a GIF, an MP4 or one PNG frame of the simulated case.

The case is simulated exactly as `rigidbench run` simulates it (`Scenario.run`, same settings), then the stored
states are replayed into MuJoCo's offscreen renderer. No display is needed: importing `rigidbench` selects EGL
when there is none, and if EGL cannot create a context the CLI retries once with OSMesa (`MUJOCO_GL=osmesa`).

The camera frames the motion: a free camera looks at the centre of the box swept by every moving geom over the
whole run, from far enough that the box's bounding sphere fits the field of view, along the direction of the
model's ``side`` camera when it has one. A trail (a polyline over the last quarter of the run) of each moving
body's *tip*, the point of its geoms farthest from its joint, makes the path visible: the heavy top's axis tip
traces the nutation cusps or loops, the asymmetric top's long axis swings over at each flip.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from rigidbench import registry
from rigidbench.settings import Settings
from rigidbench.simulate import Trajectory

FORMATS = (".gif", ".mp4", ".png")


class RenderError(RuntimeError):
    """Rendering is impossible here (no GL backend, no encoder, no imaging library); the message says what to do."""


class NoGLContext(RenderError):
    """MuJoCo could not create an offscreen OpenGL context with the selected backend (``MUJOCO_GL``)."""


@dataclass(frozen=True)
class Clip:
    """Rendered frames of one case.

    Attributes
    ----------
    frames : ndarray, shape (n, height, width, 3), uint8
    times : ndarray, shape (n,)
        Simulated time (s) of each frame.
    fps : float
        Playback rate; the clip plays at ``(times[-1] - times[0]) * fps / (n - 1)`` simulated seconds per second.
    """

    frames: np.ndarray
    times: np.ndarray
    fps: float

    @property
    def slowdown(self) -> float:
        """Wall seconds of playback per simulated second."""
        span = float(self.times[-1] - self.times[0]) if len(self.times) > 1 else 0.0
        return (len(self.times) - 1) / self.fps / span if span > 0 else math.inf


def frame_camera(model: mujoco.MjModel, qpos: np.ndarray, *, margin: float = 1.15) -> mujoco.MjvCamera:
    """A free camera that keeps every moving geom in view over the states `qpos`.

    Parameters
    ----------
    qpos : ndarray, shape (n, nq)
        States to frame (a subsample of the run is enough).
    margin : float
        Distance factor beyond the tight fit.
    """
    data = mujoco.MjData(model)
    moving = np.nonzero(model.geom_bodyid > 0)[0]
    if moving.size == 0:
        moving = np.arange(model.ngeom)
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    rbound = model.geom_rbound[moving]
    for q in qpos:
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        pos = data.geom_xpos[moving]
        lo = np.minimum(lo, (pos - rbound[:, None]).min(axis=0))
        hi = np.maximum(hi, (pos + rbound[:, None]).max(axis=0))
    center = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 1e-3)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = center
    half_fov = math.radians(model.vis.global_.fovy) / 2
    cam.distance = margin * radius / math.sin(half_fov)
    cam.azimuth, cam.elevation = 135.0, -20.0
    side = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "side")
    if side >= 0:  # look along the model's own side camera (its -z axis in the world frame)
        mujoco.mj_kinematics(model, data)
        mujoco.mj_camlight(model, data)  # camera poses: mj_kinematics leaves cam_xmat at zero
        forward = -data.cam_xmat[side].reshape(3, 3)[:, 2]
        cam.azimuth = math.degrees(math.atan2(forward[1], forward[0]))
        cam.elevation = math.degrees(math.asin(np.clip(forward[2], -1, 1)))
    return cam


def _add_trail(scene: mujoco.MjvScene, points: np.ndarray, width: float, rgba: Sequence[float]) -> None:
    for a, b in zip(points[:-1], points[1:], strict=True):
        if scene.ngeom >= scene.maxgeom:
            return
        geom = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_LINE, np.zeros(3), np.zeros(3), np.zeros(9), np.asarray(rgba))
        mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_LINE, width, a, b)
        scene.ngeom += 1


def render_clip(
    target: str,
    *,
    overrides: Mapping[str, object] | None = None,
    settings: Settings | None = None,
    frames: int = 90,
    fps: float = 30.0,
    width: int = 480,
    height: int = 360,
    at: float | None = None,
    trail: bool = True,
) -> Clip:
    """Simulate a case and render `frames` evenly spaced states of the whole run (one state if `at` is given).

    Parameters
    ----------
    target : str
        ``scenario`` (its first case) or ``scenario:case``.
    frames : int
        Number of frames spread over the run (>= 2).
    at : float, optional
        Render only the state nearest this simulated time (s), for a still image.
    width, height : int
        Pixels; at most the model's offscreen buffer (``<visual><global offwidth offheight>``).

    Raises
    ------
    ValueError
        For an unknown target or bad parameters, settings or sizes.
    RenderError
        If no OpenGL context can be created.
    """
    if frames < 2:
        raise ValueError(f"frames = {frames} must be >= 2")
    if not fps > 0:
        raise ValueError(f"fps = {fps} must be positive")
    scenario, cases = registry.parse_target(target)
    case = cases[0]
    params = scenario.resolve(scenario.case(case), overrides)
    model = scenario.build(params, settings)
    run = scenario.run(case, overrides, settings, keep_trajectory=True)
    traj: Trajectory = run.trajectory
    n = len(traj.time)
    if run.diverged_at is not None:
        n = int(np.searchsorted(traj.time, run.diverged_at, side="right"))  # the sane part only
    if at is not None:
        if not 0 <= at <= traj.time[n - 1]:
            raise ValueError(f"at = {at:g} s is outside the run [0, {traj.time[n - 1]:.6g}] s")
        index = np.array([int(np.argmin(np.abs(traj.time[:n] - at)))])
    else:
        index = np.unique(np.round(np.linspace(0, n - 1, frames)).astype(int))
    max_w, max_h = model.vis.global_.offwidth, model.vis.global_.offheight
    if not (0 < width <= max_w and 0 < height <= max_h):
        raise ValueError(f"size {width}x{height} px exceeds the model's offscreen buffer {max_w}x{max_h} px")
    camera = frame_camera(model, traj.qpos[np.linspace(0, n - 1, 64).astype(int)])
    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    except Exception as exc:  # mujoco raises several types when no GL context can be made
        raise NoGLContext(
            f"no OpenGL context (MUJOCO_GL={os.environ.get('MUJOCO_GL', 'default')}): {exc}; install EGL "
            "(Debian: libegl1 libegl-mesa0 libgl1-mesa-dri) or OSMesa (libosmesa6)"
        ) from None
    data = mujoco.MjData(model)
    com = tip_paths(model, traj.qpos[:n]) if trail else None
    out = np.empty((len(index), height, width, 3), dtype=np.uint8)
    try:
        for k, i in enumerate(index):
            data.qpos[:] = traj.qpos[i]
            data.qvel[:] = traj.qvel[i]
            data.time = traj.time[i]
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera=camera)
            if com is not None:
                start = max(0, i - max(n // 4, 2))
                step = max(1, (i - start) // 400)
                for path in com:
                    pts = path[start : i + 1 : step]
                    if len(pts) >= 2:
                        _add_trail(renderer.scene, pts, 2.0, (1.0, 0.85, 0.2, 1.0))
            out[k] = renderer.render()
    finally:
        renderer.close()
    return Clip(frames=out, times=traj.time[index].copy(), fps=fps)


def _tip_local(model: mujoco.MjModel, body: int) -> np.ndarray:
    """Body-frame point of the body's geoms farthest from its joint anchor (its CM if it has no joint)."""
    anchor = model.jnt_pos[model.body_jntadr[body]] if model.body_jntnum[body] else model.body_ipos[body]
    best, far = anchor.copy(), -1.0
    for g in np.nonzero(model.geom_bodyid == body)[0]:
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, model.geom_quat[g])
        rot = rot.reshape(3, 3)
        size = model.geom_size[g]
        kind = model.geom_type[g]
        if kind in (mujoco.mjtGeom.mjGEOM_CAPSULE, mujoco.mjtGeom.mjGEOM_CYLINDER):
            half = [0.0, 0.0, size[1] + (size[0] if kind == mujoco.mjtGeom.mjGEOM_CAPSULE else 0.0)]
        elif kind == mujoco.mjtGeom.mjGEOM_SPHERE:
            half = [size[0]] * 3
        else:
            half = list(size)
        for axis in range(3):
            for sign in (1.0, -1.0):
                p = model.geom_pos[g] + sign * half[axis] * rot[:, axis]
                d = float(np.linalg.norm(p - anchor))
                if d > far + 1e-12:
                    best, far = p, d
    return best


def tip_paths(model: mujoco.MjModel, qpos: np.ndarray) -> list[np.ndarray] | None:
    """World paths, shape (n, 3) each, of every moving body's tip (`_tip_local`) whose tip moves visibly."""
    data = mujoco.MjData(model)
    tips = [_tip_local(model, b) for b in range(1, model.nbody)]
    paths = np.empty((len(qpos), model.nbody - 1, 3))
    for k, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        for j, tip in enumerate(tips):
            paths[k, j] = data.xpos[j + 1] + data.xmat[j + 1].reshape(3, 3) @ tip
    extent = np.linalg.norm(paths.max(axis=0) - paths.min(axis=0), axis=-1)
    scale = max(float(model.stat.extent), 1e-9)
    moving = [paths[:, j] for j in range(model.nbody - 1) if extent[j] > 1e-3 * scale]
    return moving or None


def write(clip: Clip, path: str) -> str:
    """Write a clip to ``.gif`` (Pillow), ``.mp4`` (ffmpeg) or ``.png`` (its first frame). Returns a summary line.

    Raises
    ------
    ValueError
        For an unsupported extension.
    RenderError
        If the encoder is missing (Pillow for GIF/PNG, an ``ffmpeg`` executable for MP4).
    """
    ext = os.path.splitext(path)[1].lower()
    if ext not in FORMATS:
        raise ValueError(f"output {path!r}: the extension must be one of {', '.join(FORMATS)}")
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    if ext == ".mp4":
        _write_mp4(clip, path)
    else:
        try:
            from PIL import Image
        except ImportError:
            raise RenderError(
                f"writing {ext} needs Pillow: pip install 'rigidbench[render]' (or pip install pillow)"
            ) from None
        images = [Image.fromarray(f) for f in clip.frames]
        if ext == ".png":
            images[0].save(path)
        else:
            images[0].save(
                path,
                save_all=True,
                append_images=images[1:],
                duration=int(round(1000 / clip.fps)),
                loop=0,
                optimize=False,
            )
    h, w = clip.frames.shape[1:3]
    if len(clip.frames) == 1:
        return f"{path}: {w}x{h} px, t = {clip.times[0]:.4g} s"
    return (
        f"{path}: {len(clip.frames)} frames, {w}x{h} px, {clip.fps:g} fps, t = {clip.times[0]:.4g} .. "
        f"{clip.times[-1]:.4g} s (plays at {1 / clip.slowdown:.3g}x real time)"
    )


def _write_mp4(clip: Clip, path: str) -> None:
    ffmpeg = shutil.which("ffmpeg")
    if ffmpeg is None:
        raise RenderError(
            "no MP4 encoder: 'ffmpeg' is not on PATH (Debian: apt-get install ffmpeg); write a .gif instead"
        )
    n, h, w, _ = clip.frames.shape
    cmd = [
        ffmpeg,
        "-loglevel",
        "error",
        "-y",
        "-f",
        "rawvideo",
        "-pix_fmt",
        "rgb24",
        "-s",
        f"{w}x{h}",
        "-r",
        f"{clip.fps:g}",
        "-i",
        "-",
        "-vf",
        "pad=ceil(iw/2)*2:ceil(ih/2)*2",
        "-pix_fmt",
        "yuv420p",
        path,
    ]
    done = subprocess.run(cmd, input=clip.frames.tobytes(), capture_output=True, check=False)
    if done.returncode != 0:
        raise RenderError(f"ffmpeg failed ({done.returncode}): {done.stderr.decode(errors='replace').strip()}")
