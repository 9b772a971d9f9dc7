"""Turning a target point into a body-velocity command that each drive can follow.

- diff: pure pursuit (turns on the spot for large errors), see :func:`.pursuit.pursue`;
- omni: drives straight at the target in the robot frame (vx, vy) and turns toward a heading
  at the same time, so it never has to stop to turn;
- ackermann: pure pursuit with the curvature clipped to 1 / min_turn_radius; it never stops to
  turn, and in reverse it pursues with its rear (the heading flipped by pi).
"""
from __future__ import annotations

import math
from typing import Any, Sequence

from pymunk_bot.robots.command import Command
from pymunk_bot.geometry.plane import wrap_angle

K_FACE = 2.5  # [1/s] turn rate per radian of heading error for an omni robot
MIN_CAR_SPEED_FRACTION = 0.3  # a car facing away from its target still creeps at this fraction


def holonomic_toward(pose: Sequence[float] | Any, target: Sequence[float] | Any, speed: float,
                     face: float | None, max_omega: float, period: float = 0.1) -> Command:
    """Move at ``speed`` [m/s] straight toward ``target`` [m], turning toward ``face`` [rad].

    The command holds for a control ``period`` [s] while the robot turns, so the world
    direction is turned into the robot frame at the heading of the period's middle."""
    x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
    omega = 0.0
    if face is not None:
        omega = max(-max_omega, min(max_omega, K_FACE * wrap_angle(face - theta)))
    dx, dy = float(target[0]) - x, float(target[1]) - y
    distance = math.hypot(dx, dy)
    if distance < 1e-9:
        return Command(0.0, omega, 0.0)
    mid = theta + 0.5 * omega * period
    c, s = math.cos(mid), math.sin(mid)
    vx = speed * (c * dx + s * dy) / distance
    vy = speed * (-s * dx + c * dy) / distance
    return Command(vx, omega, vy)


def car_pursue(pose: Sequence[float] | Any, carrot: Sequence[float] | Any, speed: float,
               min_turn_radius: float, reverse: bool = False) -> Command:
    """Drive a car along the arc through ``carrot`` at ``speed`` [m/s] (backwards if
    ``reverse``), the arc no tighter than ``min_turn_radius`` [m]."""
    x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
    if reverse:
        theta += math.pi
    dx, dy = float(carrot[0]) - x, float(carrot[1]) - y
    distance = math.hypot(dx, dy)
    if distance < 1e-9:
        return Command()
    alpha = wrap_angle(math.atan2(dy, dx) - theta)
    curvature = 2.0 * math.sin(alpha) / distance
    limit = 1.0 / min_turn_radius if min_turn_radius > 0 else math.inf
    curvature = max(-limit, min(limit, curvature))
    # Slow while the heading is far off; behind us it cannot turn on the spot: full lock, creep.
    v = speed * max(MIN_CAR_SPEED_FRACTION, math.cos(alpha))
    if abs(alpha) > math.pi / 2:
        curvature = math.copysign(limit if math.isfinite(limit) else 2.0 / distance, alpha)
    # In reverse the yaw rate has the sign of the curvature in the flipped frame, times |v|.
    return Command(-v, v * curvature) if reverse else Command(v, v * curvature)
