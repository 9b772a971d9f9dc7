"""Path geometry for followers: rounded corners stay inside, the speed profile brakes."""
import math

import numpy as np

from pymunk_bot.planning.pursuit import PathTracker, PursuitGains, round_corners


def test_rounded_corners_stay_inside_the_polyline_corner():
    square = [(0, 0), (4, 0), (4, 4), (0, 4)]
    loop = np.array(round_corners(square, 0.5, loop=True))
    assert loop[:, 0].min() >= -1e-9 and loop[:, 0].max() <= 4 + 1e-9
    assert loop[:, 1].min() >= -1e-9 and loop[:, 1].max() <= 4 + 1e-9
    # each corner is cut by r * (sqrt(2) - 1) along its bisector, not more
    nearest = np.hypot(loop[:, 0] - 4, loop[:, 1] - 4).min()
    assert math.isclose(nearest, 0.5 * (math.sqrt(2) - 1), rel_tol=0.02)


def test_speed_profile_brakes_before_bends_and_the_end():
    gains = PursuitGains(max_speed=1.0, decel=1.0, lateral_accel=0.6)
    tracker = PathTracker(round_corners([(0, 0), (6, 0), (6, 6)], 0.5), False, gains)
    end_speed = tracker.speed_at(tracker.length)
    assert end_speed == 0.0
    # v <= sqrt(2 a d) toward the end
    for d in (0.1, 0.5, 1.0):
        assert tracker.speed_at(tracker.length - d) <= math.sqrt(2 * d) + 1e-6
    bend = tracker.speed_at(5.5 + 0.25 * math.pi / 2)  # the middle of the fillet arc
    assert bend <= math.sqrt(0.6 * 0.5) + 0.05
    assert tracker.speed_at(2.0) == 1.0


def test_progress_never_jumps_to_a_later_part_of_a_path_that_returns():
    gains = PursuitGains()
    hairpin = [(0, 0), (5, 0), (5, 0.6), (0, 0.6)]
    tracker = PathTracker(hairpin, False, gains)
    tracker.update(1.0, 0.3, window=1.0)  # between both legs: must stay on the first
    assert tracker.s < 1.5
