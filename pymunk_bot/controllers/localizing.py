"""What a controller that drives on an estimate does while the estimate is not trustworthy.

Localize before driving (docs/localization.md): the robot never follows its plan on a guess.
It turns once on the spot, so the LiDAR sweeps the place; if that is not enough it explores on
its LiDAR alone, which needs no estimate: it creeps straight on while the scan shows room ahead
and turns on the spot where it does not, so the filter sees the place from new poses (turning
in place cannot tell identical rooms apart). A robot that cannot turn in place without
sweeping its outline over something (a non-round footprint, a car) stands still; one without
a scan only turns.
"""
from __future__ import annotations

import numpy as np

from ..command import STOP, Command
from ..readings import Observation

LOCALIZING = "localizing: waiting for a trustworthy estimate"  # the controller's message
LOCALIZING_TURN_RATE = 0.5  # [rad/s] turn on the spot while localizing
LOCALIZING_SPEED = 0.15  # [m/s] creep forward while localizing, where the scan shows room
LOCALIZING_LOOKAHEAD = 0.6  # [m] free corridor ahead of the robot's disc needed to creep
LOCALIZING_SIDE_MARGIN = 0.1  # [m] half-width margin of that corridor beyond the radius


def can_turn_in_place(obs: Observation) -> bool:
    """A round robot turning about its centre sweeps nothing new (see the module docstring)."""
    robot = obs.robot
    outline = robot.footprint
    round_on_axis = outline is None or (outline.points is None
                                        and tuple(outline.center) == (0.0, 0.0))
    return round_on_axis and robot.min_turn_radius <= 0


def room_ahead(obs: Observation) -> bool:
    """Whether the latest scan shows the corridor ahead of the robot free of returns."""
    scan = obs.scan
    if scan is None:
        return False
    ranges = np.asarray(scan.ranges, dtype=float)
    angles = np.asarray(scan.angles, dtype=float)
    hit = np.isfinite(ranges) & (ranges < scan.max_range)
    x = scan.offset[0] + ranges[hit] * np.cos(angles[hit])
    y = scan.offset[1] + ranges[hit] * np.sin(angles[hit])
    radius = obs.robot.radius
    blocked = (x > 0.0) & (x < radius + LOCALIZING_LOOKAHEAD) & (
        np.abs(y) < radius + LOCALIZING_SIDE_MARGIN)
    return not bool(blocked.any())


def localizing_command(obs: Observation, waited: float) -> Command:
    """The command after ``waited`` [s] not localized: one full turn on the spot first (it
    keeps the robot where its plan expects it, and often suffices), then creep straight on
    where the scan is clear (a bouncing walk leaves a room; a curve would circle in it) and
    turn on the spot where not."""
    if not can_turn_in_place(obs):
        return STOP
    robot = obs.robot
    turn = float(min(LOCALIZING_TURN_RATE, 0.5 * robot.max_omega))
    if waited >= 2.0 * np.pi / turn and room_ahead(obs):
        return Command(float(min(LOCALIZING_SPEED, 0.5 * robot.max_speed)), 0.0)
    return Command(0.0, turn)
