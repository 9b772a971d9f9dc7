"""Active localization (localization/explore.py) and what a localizing controller does with it
(controllers/localizing.py).

Before: a robot that was not localized turned a full circle on the spot (12.6 s, with a
360-degree LiDAR showing the filter nothing new), then crept straight on at 0.15 m/s. In Nav2's
warehouse the filter kept two hypotheses that fit every scan (an aisle and the same aisle
turned 180 deg), and creeping along the aisle kept them both alive: global starts converged
within 20 s in 14 of 20 seeds, kidnappings in 15 of 20.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from pymunk_bot.controllers.localizing import (LOCALIZING_SPEED, LOCALIZING_TURN_RATE,
                                               localizing_command, most_open_heading, unseen_arc)
from pymunk_bot.localization.explore import (EXPLORE_STEP, Explorer, corridor_lengths,
                                             explore_heading, trace)
from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.robots.readings import LaserScan, Observation, RobotSpec

RES = 0.05  # [m]
RADIUS = 0.2  # [m]


def _hall() -> LikelihoodField:
    """A hall [0, 20] x [0, 8] m, solid all around, with a 1 x 4 m block at x = 15-16,
    y = 2-6."""
    x0, y0 = -0.5, -0.5  # [m] the grid's lower-left corner
    data = np.full((round(9.0 / RES), round(21.0 / RES)), 100, dtype=np.int8)

    def cells(xa, ya, xb, yb):
        return (slice(round((ya - y0) / RES), round((yb - y0) / RES)),
                slice(round((xa - x0) / RES), round((xb - x0) / RES)))

    data[cells(0.0, 0.0, 20.0, 8.0)] = 0
    data[cells(15.0, 2.0, 16.0, 6.0)] = 100
    return LikelihoodField(OccupancyGrid(data, RES, (x0, y0)))


# Two poses that see nothing within a 4 m LiDAR's range (the side walls are 4 m off): A faces
# the block 4.5 m ahead, B (turned 180 deg) the hall's far end 8 m ahead. Driving forward
# brings the block in range for A alone; driving back shows neither anything new.
LOOK_ALIKES = np.array([[10.5, 4.0, 0.0], [8.0, 4.0, math.pi]])
NOTHING_IN_RANGE = np.empty((0, 2))  # the scan's end points (robot frame)


def _scan(ranges, angles, max_range: float = 4.0) -> LaserScan:
    return LaserScan(np.asarray(ranges, dtype=float), np.asarray(angles, dtype=float), 0.05,
                     max_range, (0.0, 0.0, 0.0), 0.0)


def _robot() -> RobotSpec:
    return RobotSpec("r1", RADIUS, 0.3, 1.0, 3.0)


def _obs(scan, explore_heading=None) -> Observation:
    return Observation(0.0, np.zeros(3), np.zeros(3), None, 0.25, _robot(), scan=scan,
                       localized=False, explore_heading=explore_heading)


def test_tracing_the_map_gives_the_ranges_to_its_walls():
    field = _hall()
    ranges = trace(field, np.array([[12.0, 3.0]]), np.array([[0.0, math.pi, math.pi / 2]]), 10.0)
    assert ranges[0] == pytest.approx([3.0, 10.0, 5.0], abs=2 * RES)  # the block, capped, the wall


def test_a_corridor_is_blocked_only_by_returns_within_the_robots_width():
    points = np.array([[2.0, 0.0], [0.1, 0.5]])  # dead ahead at 2 m; 0.5 m to the left
    lengths = corridor_lengths(points, np.array([0.0, math.pi / 2, math.pi]), 0.3, 4.0)
    assert lengths == pytest.approx([2.0, 0.5, 4.0])


def test_the_robot_is_sent_where_look_alike_hypotheses_would_see_different_things():
    field = _hall()
    halves = np.array([0.5, 0.5])
    heading = explore_heading(field, LOOK_ALIKES, halves, NOTHING_IN_RANGE, 4.0, RADIUS, 0.1)
    assert heading is not None and abs(heading) <= math.radians(20.0)
    # One hypothesis, or a way the LiDAR shows blocked, is no reason to drive there
    assert explore_heading(field, LOOK_ALIKES[:1], np.ones(1), NOTHING_IN_RANGE, 4.0, RADIUS, 0.1) is None
    wall_ahead = np.array([[0.6, y] for y in np.linspace(-0.4, 0.4, 9)])
    heading = explore_heading(field, LOOK_ALIKES, halves, wall_ahead, 4.0, RADIUS, 0.1)
    assert heading is None or abs(heading) > math.radians(30.0)


def test_a_chosen_heading_is_held_until_the_robot_has_driven_there():
    field = _hall()
    explorer = Explorer(RADIUS, 0.1)
    explorer.update(field, LOOK_ALIKES, np.array([0.5, 0.5]), NOTHING_IN_RANGE, 4.0, np.zeros(3), 0.0)
    first = explorer.heading(np.zeros(3))
    assert first is not None
    # The robot turns by 0.5 rad: the heading stays put in the world (robot frame: 0.5 less),
    # even with hypotheses that would now point elsewhere
    turned = np.array([0.0, 0.0, 0.5])
    explorer.update(field, LOOK_ALIKES[::-1], np.array([0.9, 0.1]), NOTHING_IN_RANGE, 4.0, turned, 1.0)
    assert explorer.heading(turned) == pytest.approx(first - 0.5)
    # Once it has driven EXPLORE_STEP, it chooses again (one hypothesis left: no heading)
    far = np.array([EXPLORE_STEP + 0.1, 0.0, 0.0])
    explorer.update(field, LOOK_ALIKES[:1], np.ones(1), NOTHING_IN_RANGE, 4.0, far, 2.0)
    assert explorer.heading(far) is None
    explorer.update(field, LOOK_ALIKES, np.array([0.5, 0.5]), NOTHING_IN_RANGE, 4.0, far, 2.5)
    assert explorer.heading(far) is None  # none sought again before EXPLORE_RETRY
    explorer.update(field, LOOK_ALIKES, np.array([0.5, 0.5]), NOTHING_IN_RANGE, 4.0, far, 3.5)
    assert explorer.heading(far) is not None
    explorer.forget()
    assert explorer.heading(far) is None


def test_a_360_degree_lidar_sees_no_unseen_arc_and_the_robot_explores_at_once():
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    full = _scan(np.full(360, 4.0), angles)  # nothing in range
    assert unseen_arc(full) == pytest.approx(0.0, abs=1e-9)
    command = localizing_command(_obs(full), 0.0)
    assert command.v == pytest.approx(LOCALIZING_SPEED) and command.omega == 0.0


def test_a_lidar_with_a_blind_sector_turns_through_it_first():
    angles = np.linspace(-math.pi / 2, math.pi / 2, 181)  # 180 deg ahead
    half = _scan(np.full(181, 4.0), angles)
    assert unseen_arc(half) == pytest.approx(math.pi, abs=0.02)
    turning_for = math.pi / LOCALIZING_TURN_RATE  # [s]
    assert localizing_command(_obs(half), 0.5 * turning_for).v == 0.0
    assert localizing_command(_obs(half), turning_for + 0.1).v > 0.0


def test_the_robot_turns_to_the_localizers_heading_then_drives_along_it():
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    clear = _scan(np.full(360, 4.0), angles)
    left = localizing_command(_obs(clear, explore_heading=1.0), 0.0)
    assert left.v == 0.0 and left.omega > 0.0
    right = localizing_command(_obs(clear, explore_heading=-2.0), 0.0)
    assert right.v == 0.0 and right.omega < 0.0
    on = localizing_command(_obs(clear, explore_heading=0.1), 0.0)
    assert on.v == pytest.approx(LOCALIZING_SPEED) and 0.0 < on.omega <= 0.1 + 1e-9


def test_where_the_scan_shows_no_room_ahead_the_robot_turns_towards_the_most_open_way():
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    # A wall 0.5 m ahead, open to the right (negative angles), walls 1 m off elsewhere
    ranges = np.where(np.abs(angles) < 0.6, 0.5, np.where(angles < 0.0, 4.0, 1.0))
    boxed = _scan(ranges, angles)
    assert most_open_heading(_obs(boxed)) < 0.0
    command = localizing_command(_obs(boxed, explore_heading=0.0), 0.0)  # even when told ahead
    assert command.v == 0.0 and command.omega < 0.0


def test_an_explore_heading_with_no_way_there_is_left_for_the_most_open_way():
    """The localizer's heading lies behind a wall: the robot turns to the open side instead of
    towards the wall (it used to turn between the two on the spot until the run ended)."""
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    # A wall 0.5 m off from -1.2 to +0.6 rad, open to the left, walls 1 m off to the right
    ranges = np.where((angles > -1.2) & (angles < 0.6), 0.5, np.where(angles > 0.0, 4.0, 1.0))
    walled = _scan(ranges, angles)
    assert most_open_heading(_obs(walled)) > 0.0
    for target in (-0.1, -0.3, -1.0):  # aligned, a little and far off: all behind the wall
        command = localizing_command(_obs(walled, explore_heading=target), 0.0)
        assert command.v == 0.0 and command.omega > 0.0
    towards = localizing_command(_obs(walled, explore_heading=1.5), 0.0)  # open: followed
    assert towards.v == 0.0 and towards.omega > 0.0
