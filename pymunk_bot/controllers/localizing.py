"""What a controller that drives on an estimate does while the estimate is not trustworthy.

Localize before driving (docs/localization.md): the robot never follows its plan on a guess.
It first turns on the spot through the part of the circle its LiDAR does not see (none for a
360-degree LiDAR: turning it in place shows the filter nothing new), then explores: towards the
localizer's ``explore_heading`` when it names one (where its hypotheses would see different
scans: MCL's active localization, localization/explore.py), else on its LiDAR alone, which
needs no estimate: straight on while the scan shows room ahead, and where it does not, a turn
on the spot towards the most open way (the heading whose corridor, as wide as the robot, runs
farthest before a return). It drives only where the scan shows room ahead. So the filter sees
the place from new poses (turning in place cannot tell identical rooms or aisles apart;
moving to where they differ can). A robot that cannot turn in place without sweeping its
outline over something (a non-round footprint, a car) stands still; one without a scan only
turns.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.robots.command import STOP, Command
from pymunk_bot.localization.explore import corridor_lengths
from pymunk_bot.localization.se2 import scan_points
from pymunk_bot.robots.readings import LaserScan, Observation

LOCALIZING = "localizing: waiting for a trustworthy estimate"  # the controller's message
LOCALIZING_TURN_RATE = 0.5  # [rad/s] turn on the spot while localizing
# [m/s] explore while localizing, where the scan shows room: at 0.15 m/s a robot got 3 m in
# 20 s, seldom to where a warehouse aisle and its look-alikes differ (docs/localization-journal.md);
# stopping from 0.3 m/s takes a few cm.
LOCALIZING_SPEED = 0.3
LOCALIZING_LOOKAHEAD = 0.6  # [m] free corridor ahead of the robot's disc needed to drive on
LOCALIZING_SIDE_MARGIN = 0.1  # [m] half-width margin of that corridor beyond the radius
EXPLORE_HEADINGS = 36  # candidate headings (every 10 deg) when choosing the most open way
ALIGNED = 0.2  # [rad] within this of the localizer's explore heading the robot drives on
STEER_GAIN = 1.0  # [1/s] turn rate per radian off that heading while driving
OPEN_TIE = 0.5  # [m] corridors whose free lengths differ by less are equally open


def can_turn_in_place(obs: Observation) -> bool:
    """A round robot turning about its centre sweeps nothing new (see the module docstring)."""
    robot = obs.robot
    outline = robot.footprint
    round_on_axis = outline is None or (outline.points is None
                                        and tuple(outline.center) == (0.0, 0.0))
    return round_on_axis and robot.min_turn_radius <= 0


def unseen_arc(scan: LaserScan) -> float:
    """[rad] The part of the circle the scan's beams do not cover (0 for a 360-degree LiDAR):
    the widest gap between neighbouring beams beyond their usual spacing, when it exceeds
    half that spacing (rounding leaves the gaps of a full circle a hair apart)."""
    angles = np.sort(np.mod(np.asarray(scan.angles, dtype=float), 2.0 * math.pi))
    if angles.size < 2:
        return 2.0 * math.pi
    gaps = np.append(np.diff(angles), 2.0 * math.pi - (angles[-1] - angles[0]))
    spacing = float(np.median(gaps))
    arc = float(gaps.max()) - spacing
    return arc if arc > 0.5 * spacing else 0.0


def free_lengths(obs: Observation, headings: np.ndarray) -> np.ndarray:
    """[m] Per heading (robot frame, rad), how far a corridor as wide as the robot (plus
    LOCALIZING_SIDE_MARGIN a side) runs from the robot's centre before a scan return;
    the scan's max range where none; 0 without a scan."""
    scan = obs.scan
    if scan is None:
        return np.zeros(headings.shape)
    points, _ = scan_points(scan)
    return corridor_lengths(points, headings, obs.robot.radius + LOCALIZING_SIDE_MARGIN,
                            scan.max_range)


def way_to(obs: Observation, heading: float) -> bool:
    """Whether the latest scan shows the corridor towards ``heading`` [rad, robot frame] free
    of returns for the robot's radius plus LOCALIZING_LOOKAHEAD."""
    if obs.scan is None:
        return False
    free = free_lengths(obs, np.array([heading]))[0]
    return bool(free >= obs.robot.radius + LOCALIZING_LOOKAHEAD)


def room_ahead(obs: Observation) -> bool:
    """Whether the latest scan shows the corridor ahead of the robot free of returns."""
    return way_to(obs, 0.0)


def most_open_heading(obs: Observation) -> float:
    """[rad, robot frame] The heading whose corridor runs farthest (free_lengths), among the
    headings the scan sees; of corridors within OPEN_TIE of the longest, the smallest turn
    (then a left turn), so the choice holds still while the robot turns towards it."""
    scan = obs.scan
    if scan is None:
        return math.pi
    headings = (np.linspace(-math.pi, math.pi, EXPLORE_HEADINGS, endpoint=False)
                + math.pi / EXPLORE_HEADINGS)
    free = free_lengths(obs, headings)
    angles = np.asarray(scan.angles, dtype=float)
    if unseen_arc(scan) > 0.0:  # a partial view: only headings within it are known to be open
        lo, hi = float(angles.min()), float(angles.max())
        free = np.where((headings >= lo) & (headings <= hi), free, 0.0)
    open_enough = free >= free.max() - OPEN_TIE
    order = np.lexsort((-headings, np.abs(headings), ~open_enough))
    return float(headings[order[0]])


def localizing_command(obs: Observation, waited: float) -> Command:
    """The command after ``waited`` [s] not localized: a turn on the spot through the part of
    the circle the LiDAR does not see (the whole circle without a scan), then exploring:
    towards the localizer's ``explore_heading`` where it names one (where its hypotheses
    would see different things), else straight on where the scan is clear (a bouncing walk
    leaves a room or an aisle; a curve would circle in it), else a turn on the spot towards
    the most open way. It drives only where the scan shows room ahead."""
    if not can_turn_in_place(obs):
        return STOP
    robot = obs.robot
    turn = float(min(LOCALIZING_TURN_RATE, 0.5 * robot.max_omega))
    scan = obs.scan
    if scan is None or waited < unseen_arc(scan) / turn:
        return Command(0.0, turn)
    speed = float(min(LOCALIZING_SPEED, 0.5 * robot.max_speed))
    target = obs.explore_heading
    # Towards the explore heading only where the scan shows a way there: a blocked one left
    # the robot turning between it and the most open way, on the spot, for good (measured:
    # a kidnapped warehouse run stood still from 6 s after the kidnapping to the end, 84 s).
    if target is not None and way_to(obs, target):
        if abs(target) > ALIGNED or not room_ahead(obs):  # the last bit of the turn too
            return Command(0.0, math.copysign(turn, target))
        return Command(speed, float(np.clip(STEER_GAIN * target, -turn, turn)))
    if room_ahead(obs):
        return Command(speed, 0.0)
    return Command(0.0, math.copysign(turn, most_open_heading(obs)))
