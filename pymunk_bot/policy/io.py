"""What a navigation policy sees and how its action drives a robot: the one implementation that
``pymunk_bot/Navigation-v0`` (:mod:`pymunk_bot.envs`) and the ``policy`` controller
(:mod:`pymunk_bot.controllers.policy`) both use, so a policy trained in the env drives the same
way in a scenario. No RL library here. Units: metres, seconds, radians.

Observation (float32), for a robot with B LiDAR beams and an action of A numbers::

    [0, B)     proximity of each beam: (s/R) (R - r) / (s + r)   in [0, 1]  (1: touching, 0: no
                                                                            return; R max_range,
                                                                            s PROXIMITY_SCALE)
    B          proximity of the nearest return (the largest above)  in [0, 1]
    B+1, B+2   cos, sin of that beam's direction (robot frame)      in [-1, 1]
    B+3        goal distance d / (d + GOAL_SCALE)                   in [0, 1)
    B+4, B+5   cos, sin of the goal bearing (robot frame)           in [-1, 1]
    B+6 ...    the previous action (A numbers)                      in [-1, 1]

The proximity is steep near obstacles (r = 0.2 m: 0.70, 0.5 m: 0.47, 1 m: 0.29, 2 m: 0.15 for
R = 8 m), where a policy must tell a graze from a pass, and flat far away. The goal distance
needs no arena size, so one policy fits worlds of any size. Every feature is plain arithmetic
(correctly rounded) or a per-robot ``math`` call, so one robot or a batch gives the same floats.

Action (``[-1, 1]``, clipped): (v, omega), or (v, omega, vy) for a holonomic (omni) robot, times
the robot's limits (:class:`ActionScale`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from pymunk_bot.robots.command import Command
from pymunk_bot.robots.readings import RobotSpec

PROXIMITY_SCALE = 0.5  # [m] range at which a beam's proximity falls to about half
GOAL_SCALE = 1.0  # [m] goal distance at which its feature is 0.5
EXTRA_FEATURES = 6  # nearest proximity, its direction (2), goal distance, goal bearing (2)
# Where each feature after the B beam proximities sits: observation[B + GOAL_SIN] is the sine
# of the goal bearing (steer by it); the previous action starts at B + EXTRA_FEATURES.
NEAREST_PROXIMITY, NEAREST_COS, NEAREST_SIN, GOAL_DISTANCE, GOAL_COS, GOAL_SIN = \
    range(EXTRA_FEATURES)
MAX_BEAMS = 4096  # an observation larger than this is a mistake, not a sensor


@dataclass(frozen=True)
class ActionScale:
    """What an action of 1 commands: forward speed [m/s], yaw rate [rad/s], lateral speed
    [m/s] (None: the robot cannot move sideways, the action has 2 numbers)."""

    v_max: float
    omega_max: float
    vy_max: float | None

    @classmethod
    def of(cls, spec: RobotSpec) -> "ActionScale":
        """The limits of a robot (a diff drive turns fastest on the spot:
        2 max_wheel_speed / track_width; a car at its tightest circle)."""
        return cls(float(spec.max_speed), float(spec.max_omega),
                   float(spec.max_speed) if spec.holonomic else None)

    @property
    def size(self) -> int:
        """Numbers in an action."""
        return 2 if self.vy_max is None else 3

    def clipped(self, action: object) -> list[float]:
        """The action as ``size`` floats clipped to [-1, 1]; ValueError if it has the wrong
        length or a non-finite number."""
        values = np.asarray(action, dtype=np.float64).reshape(-1).tolist()
        if len(values) != self.size or not all(map(math.isfinite, values)):
            raise ValueError(f"action must be {self.size} finite numbers (got {action!r:.80})")
        return [min(1.0, max(-1.0, value)) for value in values]

    def command(self, a: Sequence[float]) -> Command:
        """The body velocity of a clipped action."""
        if self.vy_max is None:
            return Command(a[0] * self.v_max, a[1] * self.omega_max)
        return Command(a[0] * self.v_max, a[1] * self.omega_max, a[2] * self.vy_max)


def action_size(holonomic: bool) -> int:
    """Numbers in the action of a robot that can (or cannot) move sideways."""
    return 3 if holonomic else 2


def observation_size(beams: int, holonomic: bool) -> int:
    """Length of the observation of a robot with ``beams`` LiDAR beams."""
    return beams + EXTRA_FEATURES + action_size(holonomic)


def observation_bounds(beams: int, holonomic: bool) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of every observation entry (float32)."""
    size = observation_size(beams, holonomic)
    low = np.full(size, -1.0, dtype=np.float32)
    high = np.ones(size, dtype=np.float32)
    low[: beams + 1] = 0.0  # proximities
    low[beams + GOAL_DISTANCE] = 0.0
    return low, high


def goal_features(x: float, y: float, theta: float, gx: float, gy: float
                  ) -> tuple[float, float, float]:
    """(distance [m], cos, sin of the bearing in the robot frame) of the goal (gx, gy) seen
    from the pose (x, y, theta)."""
    dx, dy = gx - x, gy - y
    bearing = math.atan2(dy, dx) - theta
    return math.sqrt(dx * dx + dy * dy), math.cos(bearing), math.sin(bearing)


class ObservationBuilder:
    """Writes observations of robots with the same LiDAR (beam count, range, angles)."""

    def __init__(self, angles: np.ndarray, max_range: float, holonomic: bool) -> None:
        angles = np.array(angles, dtype=np.float64)  # a copy: the caller's may change
        if not 0 < angles.size <= MAX_BEAMS:
            raise ValueError(f"a policy observes 1 to {MAX_BEAMS} beams (got {angles.size})")
        self.beams = int(angles.size)
        self.angles = angles  # [rad] of each beam, robot frame
        self.max_range = float(max_range)  # [m]
        self.size = observation_size(self.beams, holonomic)
        self._cos, self._sin = np.cos(angles), np.sin(angles)  # beam directions, robot frame
        self._factor = PROXIMITY_SCALE / self.max_range
        # Loaded here, not with the module: config reads this module's constants.
        from pymunk_bot.policy.observation_rows import fill_rows
        self._fill_rows = fill_rows

    def fill(self, out: np.ndarray, ranges: np.ndarray, goals: Sequence[tuple[float, float, float]],
             previous: np.ndarray) -> None:
        """Write one observation per row of ``out`` (n x size, float32) from each robot's
        ranges [m] (n x beams), :func:`goal_features` and previous clipped action (n x A);
        compiled (``observation_rows``: the proximity (s/R) (R - r) / (s + r) of each range)."""
        # a writeable copy of the ranges: one array type for the kernel (a scan's may be
        # read-only), so numba compiles it once
        self._fill_rows(out, np.array(ranges, dtype=np.float64),
                        np.asarray(goals, dtype=np.float64).reshape(-1, 3),
                        np.asarray(previous, dtype=np.float64).reshape(len(goals), -1),
                        self.max_range, PROXIMITY_SCALE, self._factor, GOAL_SCALE, self._cos,
                        self._sin)
