"""A replay shows the logged run as it happened, and cannot be steered."""
from __future__ import annotations

import numpy as np
import pygame

from pymunk_bot.outcomes.runlog import RunLogger
from pymunk_bot.viewer import palette as pal
from pymunk_bot.viewer.sources import LiveSource, ReplaySource
from viewer_helpers import Harness, build, near, wheels


def logged_run():
    sim = build([{"name": "r", "pose": [0.6, 1.5, 0.0], "controller": wheels(0.6, 0.5),
                  "lidar": {"beams": 24, "max_range": 3.0}}],
                obstacles=[{"type": "box", "center": [2.0, 2.3], "size": [0.4, 0.4],
                            "movable": True}])
    live = LiveSource(sim)
    logger = RunLogger().attach(sim)
    scenes = []
    for _ in range(90):
        live.step()
        scenes.append(live.scene())
    return sim, logger.log(), scenes


def test_replay_scenes_match_the_live_ones():
    sim, log, live_scenes = logged_run()
    replay = ReplaySource(log)
    for i in (1, 6, 45, 90):
        replay.index = i
        got, want = replay.scene(), live_scenes[i - 1]
        assert got.time == want.time
        assert np.array_equal(got.robots[0].pose, want.robots[0].pose)
        assert np.array_equal(got.robots[0].odometry, want.robots[0].odometry)
        assert np.allclose(got.robots[0].scan_points, want.robots[0].scan_points, atol=1e-5)
        for a, b in zip(got.shapes, want.shapes):
            assert np.allclose(a.points, b.points, atol=1e-12)


def test_replay_keys_step_back_and_forth_and_refuse_goals():
    _, log, _ = logged_run()
    h = Harness(ReplaySource(log))
    h.viewer.advance(0.5)
    assert h.source.index == 30
    h.key(pygame.K_SPACE, " ")
    h.key(pygame.K_PERIOD, ".")
    assert h.source.index == 31
    h.key(pygame.K_COMMA, ",")
    h.key(pygame.K_COMMA, ",")
    assert h.source.index == 29
    h.key(pygame.K_RIGHT)
    assert h.source.index == 89
    h.key(pygame.K_LEFT)
    assert h.source.index == 29
    h.click((5, 5))
    assert "cannot" in h.viewer.message
    h.key(pygame.K_UP)  # no teleop in a replay
    h.key(pygame.K_SPACE, " ")
    h.viewer.advance(10.0)
    assert h.source.at_end and h.viewer.ended
    h.key(pygame.K_r, "r")
    assert h.source.index == 0


def test_replay_frame_shows_the_robot_where_the_log_says():
    _, log, _ = logged_run()
    h = Harness(ReplaySource(log))
    h.viewer.layers.grid = False
    h.source.index = 60
    h.draw()
    x, y, _ = log.pose[60, 0]
    assert near(h.pixel((x - 0.1, y + 0.05)), pal.robot_colour(0), 2)
