"""The ``crowd_state`` observation: what a crowd policy sees when it is given the humans' true
states (CrowdNav's setting) instead of a LiDAR. The one implementation that
``pymunk_bot/Navigation-v0``, its vector env, ``MultiRobotEnv`` and the ``policy`` controller
use (``observation="crowd_state"``). Units: metres, seconds, radians.

Everything is in the robot frame (x forward, y left), so a policy does not depend on where the
robot is or which way it faces. For an action of A numbers and k humans (the robot's
``crowd_state.max_humans``), float32::

    0          goal distance d / (d + GOAL_SCALE)                    in [0, 1)
    1, 2       cos, sin of the goal bearing                          in [-1, 1]
    3 .. 3+A   the previous action (the velocity the robot asked)    in [-1, 1]
    then per human, nearest first, HUMAN_FEATURES numbers:
      +0       present: 1 (0: no human in this slot)                 in [0, 1]
      +1, +2   its centre relative to the robot's, p / (|p| + POSITION_SCALE)    in (-1, 1)
      +3, +4   its velocity relative to the robot's, / VELOCITY_SCALE, clipped   in [-1, 1]
      +5       radius sum r / (r + POSITION_SCALE)                   in [0, 1)
      +6       proximity of the gap g between the bodies (centre distance less the radius
               sum, 0 while overlapping): s / (s + g), s = PROXIMITY_SCALE     in (0, 1]
      +7       1 / (1 + t / TTC_SCALE), t the time to collision at constant velocities
               (0 when they do not meet; 1 while overlapping)        in [0, 1]

An absent human (fewer than k in range) is all zeros: present 0, and it reads as infinitely far
(proximity 0) and never meeting the robot (0). The robot's own velocity is the one it asked for
in the previous action (CrowdNav's robot state holds its velocity; a holonomic agent's is the
one it asked for): known exactly in the env and on a robot alike.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from pymunk_bot.policy.io import GOAL_SCALE, ActionScale, action_size

OBSERVATIONS = ("lidar", "crowd_state")  # what a policy may observe (lidar: policy.io's)
HUMAN_FEATURES = 8
GOAL_FEATURES = 3  # distance, cos, sin of the bearing
POSITION_SCALE = 1.0  # [m] relative position (and radius sum) at which its feature is 0.5
VELOCITY_SCALE = 2.0  # [m/s] relative speed read as 1 (two walkers at 1 m/s head-on)
PROXIMITY_SCALE = 0.5  # [m] gap at which a human's proximity is 0.5
TTC_SCALE = 1.0  # [s] time to collision at which its feature is 0.5
MAX_HUMANS_OBSERVED = 64  # an observation of more humans is a mistake, not a sensor


def crowd_observation_size(humans: int, holonomic: bool) -> int:
    """Length of the crowd observation of ``humans`` slots."""
    return GOAL_FEATURES + action_size(holonomic) + HUMAN_FEATURES * humans


def humans_of(inputs: int | None, holonomic: bool) -> int | None:
    """The humans a crowd observation of ``inputs`` numbers holds (None: no whole number)."""
    if inputs is None:
        return None
    humans, rest = divmod(inputs - GOAL_FEATURES - action_size(holonomic), HUMAN_FEATURES)
    return humans if rest == 0 and 0 < humans <= MAX_HUMANS_OBSERVED else None


def crowd_observation_bounds(humans: int, holonomic: bool) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of every crowd observation entry (float32)."""
    size = crowd_observation_size(humans, holonomic)
    low = np.full(size, -1.0, dtype=np.float32)
    high = np.ones(size, dtype=np.float32)
    low[0] = 0.0  # goal distance
    first = GOAL_FEATURES + action_size(holonomic)
    for offset in (0, 5, 6, 7):  # present, radius sum, proximity, time to collision
        low[first + offset::HUMAN_FEATURES] = 0.0
    return low, high


def time_to_collision(p: np.ndarray, w: np.ndarray, reach: float) -> float:
    """Seconds until two discs whose centres are ``p`` apart [m] (one relative to the other)
    and close at ``w`` [m/s] (the other's velocity relative to the one) come within ``reach``
    [m] (their radius sum): 0 if they already are, inf if they never will."""
    c = float(p @ p) - reach * reach
    if c <= 0.0:
        return 0.0
    b = float(p @ w)
    a = float(w @ w)
    if b >= 0.0 or a == 0.0:  # moving apart, or not moving relative to each other
        return math.inf
    disc = b * b - a * c
    if disc < 0.0:
        return math.inf
    return (-b - math.sqrt(disc)) / a


def nearest_gap(xy: Sequence[float], radius: float, crowd: Any) -> float:
    """The gap [m] between a disc of ``radius`` at ``xy`` and the nearest human's body (negative
    while they overlap; inf with no human)."""
    positions = np.asarray(crowd.positions, dtype=float).reshape(-1, 2)
    if not len(positions):
        return math.inf
    distance = np.hypot(*(positions - np.asarray(xy, dtype=float)[:2]).T)
    return float(np.min(distance - np.asarray(crowd.radii, dtype=float) - radius))


class CrowdObservationBuilder:
    """Writes crowd observations of robots that see ``humans`` humans (see the module doc)."""

    def __init__(self, humans: int, scale: ActionScale, radius: float) -> None:
        if not 0 < humans <= MAX_HUMANS_OBSERVED:
            raise ValueError(f"a crowd policy observes 1 to {MAX_HUMANS_OBSERVED} humans "
                             f"(got {humans})")
        self.humans = int(humans)
        self.scale = scale
        self.radius = float(radius)  # [m] the robot's
        self.size = crowd_observation_size(self.humans, scale.vy_max is not None)

    def fill(self, out: np.ndarray, pose: Sequence[float],
             goal: tuple[float, float, float], previous: np.ndarray, crowd: Any) -> None:
        """Write one observation into ``out`` (size floats) for a robot at ``pose`` (x, y,
        theta), the goal's features ``goal`` (distance [m], cos, sin of its bearing,
        :func:`~pymunk_bot.policy.io.goal_features`), its previous clipped action and
        ``crowd`` (a :class:`~pymunk_bot.sensors.crowd_state.CrowdState`, nearest first)."""
        x, y, theta = (float(v) for v in pose[:3])
        actions = np.asarray(previous, dtype=np.float64).reshape(-1)
        out[:] = 0.0
        d = goal[0]
        out[0], out[1], out[2] = d / (d + GOAL_SCALE), goal[1], goal[2]
        out[GOAL_FEATURES:GOAL_FEATURES + actions.size] = actions
        # the robot's velocity [m/s, robot frame]: what its previous action asked for
        own = np.array([actions[0] * self.scale.v_max,
                        0.0 if self.scale.vy_max is None else actions[2] * self.scale.vy_max])
        c, s = math.cos(theta), math.sin(theta)
        to_robot = np.array([[c, -s], [s, c]])  # world -> robot frame: v @ to_robot
        positions = np.asarray(crowd.positions, dtype=float).reshape(-1, 2)[:self.humans]
        velocities = np.asarray(crowd.velocities, dtype=float).reshape(-1, 2)[:self.humans]
        radii = np.asarray(crowd.radii, dtype=float).reshape(-1)[:self.humans]
        rel_p = (positions - (x, y)) @ to_robot
        rel_v = velocities @ to_robot - own
        first = GOAL_FEATURES + actions.size
        for i in range(len(positions)):
            p, w = rel_p[i], rel_v[i]
            reach = radii[i] + self.radius
            distance = math.hypot(p[0], p[1])
            gap = max(distance - reach, 0.0)
            ttc = time_to_collision(p, w, reach)
            row = out[first + i * HUMAN_FEATURES:first + (i + 1) * HUMAN_FEATURES]
            row[0] = 1.0
            row[1:3] = p / (distance + POSITION_SCALE)
            row[3:5] = np.clip(w / VELOCITY_SCALE, -1.0, 1.0)
            row[5] = reach / (reach + POSITION_SCALE)
            row[6] = PROXIMITY_SCALE / (PROXIMITY_SCALE + gap)
            row[7] = 0.0 if math.isinf(ttc) else 1.0 / (1.0 + ttc / TTC_SCALE)
