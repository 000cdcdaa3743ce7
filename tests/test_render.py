"""Headless rendering: a GIF with many distinct, non-blank frames; a PNG still; clear errors without an encoder."""

import numpy as np
import pytest

from rigidbench import cli, render


def test_gif_has_several_distinct_nonblank_frames(tmp_path, gl_available):
    from PIL import Image

    clip = render.render_clip("heavy-top:nutation", frames=6, width=160, height=120)
    path = tmp_path / "top.gif"
    render.write(clip, str(path))
    with Image.open(path) as im:
        assert im.n_frames == 6
        frames = []
        for k in range(im.n_frames):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB"), dtype=float))
    for f in frames:
        assert f.shape == (120, 160, 3) and f.std() > 5, "a blank frame"
    assert np.abs(frames[0] - frames[3]).mean() > 0.5, "the top does not move between frames"
    assert clip.times[0] == 0 and clip.times[-1] > 0.4  # the clip spans the whole run (3.3 nutation periods)


def test_the_camera_keeps_the_moving_body_in_view(gl_available):
    """The framed camera sees the top in every frame: the middle of the image differs from the empty corners."""
    clip = render.render_clip("heavy-top:looping", frames=4, width=120, height=90, trail=False)
    for f in clip.frames.astype(float):
        centre = f[30:60, 40:80].mean(axis=(0, 1))
        corner = f[:10, :10].mean(axis=(0, 1))
        assert np.abs(centre - corner).sum() > 30


def test_png_is_one_frame_at_the_requested_time(tmp_path, gl_available):
    path = tmp_path / "top.png"
    assert cli.main(["render", "heavy-top", "--out", str(path), "--at", "0.2", "--size", "160x120"]) == 0
    from PIL import Image

    with Image.open(path) as im:
        assert im.size == (160, 120)


def test_mp4_without_an_encoder_says_so(tmp_path, monkeypatch):
    monkeypatch.setattr(render.shutil, "which", lambda _name: None)
    clip = render.Clip(frames=np.zeros((2, 8, 8, 3), np.uint8), times=np.array([0.0, 1.0]), fps=10)
    with pytest.raises(render.RenderError, match="ffmpeg"):
        render.write(clip, str(tmp_path / "x.mp4"))


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["heavy-top", "--out", "x.avi"], "extension"),
        (["no-such", "--out", "x.gif"], "unknown scenario"),
        (["heavy-top", "--out", "x.gif", "--size", "big"], "WxH"),
        (["heavy-top", "--out", "x.gif", "--size", "4000x4000"], "offscreen buffer"),
        (["heavy-top", "--out", "x.gif", "--frames", "1"], "frames"),
    ],
)
def test_bad_render_input_exits_2(args, named, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["render", *args]) == 2
    assert named in capsys.readouterr().err
