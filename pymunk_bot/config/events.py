"""The scenario's ``events:`` list: things that happen at a simulated time.

    events:
      - {at: 20.0, robot: r1, teleport: [3.0, 2.0, 1.57]}   # a kidnapping: x [m], y [m], theta [rad]

The checks (semantics) refuse an event naming no robot of the scenario or a teleport outside
the arena.
"""
from __future__ import annotations

from typing import Annotated

from pydantic import Field

from pymunk_bot.config.types import Float, Name, Pose, Section

MAX_EVENTS = 10_000
EventTime = Annotated[Float, Field(ge=0.0, le=86_400.0)]  # [s] of simulated time


class EventConfig(Section):
    """One event: at simulated time ``at`` [s], ``robot`` is teleported to ``teleport``."""

    at: EventTime
    robot: Name
    teleport: Pose  # [x, y, theta]: where the robot is put (its odometry and localizer are not told)


EventList = Annotated[list[EventConfig], Field(max_length=MAX_EVENTS)]
