"""The world <-> pixel transform: y up in the world, y down on screen, zoom and pan."""
from __future__ import annotations

import numpy as np
import pytest

from pymunk_bot.viewer.camera import Camera


def test_fit_shows_the_whole_arena_with_y_up():
    cam = Camera((800, 600))
    cam.fit(0.0, 0.0, 10.0, 5.0, margin=20)
    corners = cam.points_to_screen(np.array([[0, 0], [10, 0], [10, 5], [0, 5]]))
    assert corners[:, 0].min() >= 20 - 1e-9 and corners[:, 0].max() <= 780 + 1e-9
    assert corners[:, 1].min() >= 0 and corners[:, 1].max() <= 600
    # The long side touches the margins: the arena is as large as it can be.
    assert corners[:, 0].min() == pytest.approx(20) and corners[:, 0].max() == pytest.approx(780)
    # World y up is screen y down.
    assert cam.to_screen(5, 5)[1] < cam.to_screen(5, 0)[1]


def test_round_trip_and_lengths():
    cam = Camera((640, 480), scale=37.5, centre=(3.0, -2.0))
    for x, y in [(0.0, 0.0), (3.0, -2.0), (-7.25, 11.5)]:
        px, py = cam.to_screen(x, y)
        assert cam.to_world(px, py) == pytest.approx((x, y))
    assert cam.to_screen(3.0, -2.0) == pytest.approx((320, 240))
    assert cam.length(2.0) == pytest.approx(75.0)


def test_zoom_keeps_the_point_under_the_cursor():
    cam = Camera((640, 480))
    cam.fit(0, 0, 8, 6)
    cursor = (100.0, 400.0)
    before = cam.to_world(*cursor)
    cam.zoom(2.5, cursor)
    assert cam.to_world(*cursor) == pytest.approx(before)
    assert cam.user_moved


def test_pan_follows_the_mouse():
    cam = Camera((640, 480))
    cam.fit(0, 0, 8, 6)
    point = (2.0, 3.0)
    px, py = cam.to_screen(*point)
    cam.pan(30, -12)
    assert cam.to_screen(*point) == pytest.approx((px + 30, py - 12))
