"""A recording ends once the run has settled, shows the robot where the simulation had it, and
the simulation still runs its whole duration (issue 35)."""
from __future__ import annotations

import imageio.v2 as iio2
import imageio.v3 as iio
import numpy as np
import pytest

from pymunk_bot.viewer import palette as pal
from pymunk_bot.viewer import record_video, recorder
from pymunk_bot.viewer.settling import SETTLE_TIME
from test_viewer_recorder import SIZE, robot_pixel
from viewer_helpers import build, near

FPS = 10.0  # [Hz]
DURATION = 12.0  # [s]: the robot arrives after about 2 s


def to_a_near_goal():
    return build([{"name": "r", "pose": [1.0, 1.5, 0.0], "radius": 0.3,
                   "controller": {"type": "go_to_goal"},
                   "goal": {"position": [2.6, 1.5], "tolerance": 0.1}}])


def poses_after_each_step(sim) -> list[np.ndarray]:
    poses = [sim.robots["r"].pose.copy()]
    sim.attach(lambda s: poses.append(s.robots["r"].pose.copy()))
    return poses


def test_the_video_ends_about_a_second_after_the_robot_has_arrived(tmp_path):
    sim = to_a_near_goal()
    poses = poses_after_each_step(sim)
    path = tmp_path / "clip.gif"
    frames = record_video(sim, path, DURATION, fps=FPS, size=SIZE, progress=False)
    robot = sim.robots["r"]
    assert robot.goal_reached and robot.controller.status == "arrived"
    assert sim.steps == round(DURATION / sim.dt)  # the run itself went all the way
    video = iio.imread(path, index=None)
    assert len(video) == frames  # every frame written is in the file
    ends = (frames - 1) / FPS  # [s] the last frame's time
    # The robot stops a little after its goal's tolerance is reached; then a second of stillness.
    assert robot.time_to_goal + SETTLE_TIME <= ends <= robot.time_to_goal + SETTLE_TIME + 1.0
    colour = pal.robot_colour(0)
    for k in (0, frames // 2, frames - 1):  # frame k shows the state after round(k / fps / dt)
        pose = poses[round(k / FPS / sim.dt)]
        assert near(robot_pixel(video[k], pose), colour, 10), k
    assert not near(robot_pixel(video[frames // 2], poses[0]), colour, 40)  # it had moved


def test_a_robot_still_driving_is_recorded_to_the_end(tmp_path):
    sim = build([{"name": "r", "pose": [0.5, 1.5, 0.0], "radius": 0.3,
                  "controller": {"type": "wheels", "left": 0.3, "right": 0.3}}])
    path = tmp_path / "clip.mp4"
    assert record_video(sim, path, 2.0, fps=FPS, size=SIZE, progress=False) == 21
    reader = iio2.get_reader(path, format="FFMPEG")
    try:
        assert sum(1 for _ in reader) == 21
    finally:
        reader.close()


def test_until_settled_false_records_the_whole_duration(tmp_path):
    path = tmp_path / "all.gif"
    assert record_video(to_a_near_goal(), path, 6.0, fps=FPS, size=SIZE, progress=False,
                        until_settled=False) == 61
    assert len(iio.imread(path, index=None)) == 61


def test_an_encoder_that_fails_midway_stops_the_recording_with_its_error(tmp_path, monkeypatch):
    class Failing:  # an encoder that gives up at its third frame, as ffmpeg with a full disk
        def __init__(self, *args) -> None:
            self.frames = 0
            self.aborted = False

        def append(self, frame: bytes) -> None:
            self.frames += 1
            if self.frames == 3:
                raise RuntimeError("ffmpeg failed (exit 1): No space left on device")

        def close(self) -> None:
            raise AssertionError("a failed recording is not closed as if complete")

        def abort(self) -> None:
            self.aborted = True

    made: list[Failing] = []
    monkeypatch.setattr(recorder, "_open_writer", lambda *args: made.append(Failing()) or made[-1])
    sim = build([{"name": "r", "pose": [0.5, 1.5, 0.0], "controller": {"type": "wheels",
                                                                     "left": 0.3, "right": 0.3}}])
    with pytest.raises(RuntimeError, match="No space left on device"):
        record_video(sim, tmp_path / "clip.mp4", 30.0, fps=FPS, size=SIZE, progress=False)
    assert made[0].aborted and made[0].frames == 3  # nothing was fed after the error
    assert not list(tmp_path.iterdir())  # no part file left behind
