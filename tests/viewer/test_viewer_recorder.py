"""Recordings: short GIF and MP4 files that read back with the right frames and pixels."""
from __future__ import annotations

import json

import imageio.v2 as iio2
import imageio.v3 as iio
import numpy as np
import pytest

from pymunk_bot.cli import main
from pymunk_bot.viewer import palette as pal
from pymunk_bot.viewer import record_video
from pymunk_bot.viewer.camera import Camera
from pymunk_bot.viewer.recorder import MARGIN
from viewer_helpers import build, near, wheels

SIZE = (320, 240)


def moving_robot():
    return build([{"name": "r", "pose": [1.0, 1.5, 0.0], "radius": 0.3,
                   "controller": wheels(0.8, 0.8)}])


def robot_pixel(frame, pose, size=SIZE, arena=(4.0, 3.0)):
    cam = Camera(size)
    cam.fit(0, 0, *arena, margin=MARGIN)
    px, py = cam.to_screen(pose[0] - 0.12, pose[1] - 0.08)  # inside the disc, off the heading
    return tuple(int(v) for v in frame[int(py), int(px)])


def test_gif_frames_show_the_robot_moving(tmp_path):
    sim = moving_robot()
    start = sim.robots["r"].pose
    path = tmp_path / "clip.gif"
    frames = record_video(sim, path, 1.0, fps=10, size=SIZE, progress=False)
    assert frames == 11
    assert sim.steps == 60  # the run went exactly as far as a headless run of 1 s
    video = iio.imread(path, index=None)
    assert video.shape == (11, SIZE[1], SIZE[0], 3)
    colour = pal.robot_colour(0)
    assert near(robot_pixel(video[0], start), colour, 10)
    end = sim.robots["r"].pose
    assert near(robot_pixel(video[-1], end), colour, 10)
    assert not near(robot_pixel(video[-1], start), colour, 40)
    assert not list(tmp_path.glob(".*"))  # no temporary file left behind


def test_mp4_reads_back_with_every_frame(tmp_path):
    sim = moving_robot()
    start = sim.robots["r"].pose
    path = tmp_path / "clip.mp4"
    assert record_video(sim, path, 1.0, fps=10, size=SIZE, progress=False) == 11
    reader = iio2.get_reader(path, format="FFMPEG")
    try:
        assert reader.get_meta_data()["fps"] == pytest.approx(10)
        video = [frame for frame in reader]
    finally:
        reader.close()
    assert len(video) == 11
    assert video[0].shape == (SIZE[1], SIZE[0], 3)
    colour = pal.robot_colour(0)
    assert near(robot_pixel(video[0], start), colour, 40)  # lossy: a looser match
    assert near(robot_pixel(video[-1], sim.robots["r"].pose), colour, 40)


def test_recording_gives_the_headless_result(tmp_path):
    base = ["run", "--seed", "3", "--duration", "1.5"]
    assert main([*base, "--headless", "--out", str(tmp_path / "a.json")]) in (0, 1)
    assert main([*base, "--record", str(tmp_path / "v.gif"), "--fps", "4", "--size", "96x64",
                 "--out", str(tmp_path / "b.json")]) in (0, 1)
    a = json.loads((tmp_path / "a.json").read_text())
    b = json.loads((tmp_path / "b.json").read_text())
    assert a["robots"] == b["robots"] and a["steps"] == b["steps"]
    assert iio.imread(tmp_path / "v.gif", index=None).shape == (7, 64, 96, 3)


@pytest.mark.parametrize("args, message", [
    (["--record", "x.avi"], "unsupported file type ('.avi')"),
    (["--record", "nodir/x.mp4"], "does not exist"),
    (["--record", "x.gif", "--fps", "-3"], "--fps: must be > 0"),
    (["--fps", "10"], "--fps: only applies with --record"),
    (["--log", "x.txt"], "use .npz"),
])
def test_bad_output_options_exit_2_with_one_line(tmp_path, monkeypatch, capsys, args, message):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--headless", "--duration", "0.1", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not list(tmp_path.iterdir())  # nothing ran, nothing written


def test_bad_frame_size_is_refused(capsys):
    with pytest.raises(SystemExit) as info:
        main(["run", "--record", "x.mp4", "--size", "big"])
    assert info.value.code == 2
    assert "WIDTHxHEIGHT" in capsys.readouterr().err


def test_default_frame_size_follows_the_arena():
    from pymunk_bot.viewer.recorder import default_size

    w, h = default_size((12.0, 4.0), ".mp4")
    assert w % 16 == 0 and h % 16 == 0
    assert w == 1280 and 2.5 < w / h < 3.2
    assert np.all(np.array(default_size((3.0, 3.0), ".gif")) == 720)
