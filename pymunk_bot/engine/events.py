"""Scenario events (``events:``, config/events.py): things that happen at a simulated time.

The only kind so far is a teleport, a kidnapping: at ``at`` the robot is put somewhere else
(``Robot.teleport``) without its odometry or localizer being told, so a localizer must notice
and recover. The simulation calls :meth:`EventSchedule.fire` once per tick, before the physics.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

from pymunk_bot.sensors.schedule import TIME_TOLERANCE


class EventSchedule:
    """The scenario's events in time order; each fires once, at the first tick at or after it."""

    def __init__(self, events: Sequence[Any]) -> None:
        self._events = sorted(events, key=lambda e: e.at)  # stable: same-time events keep order
        self._next = 0
        self.fired: list[tuple[float, Any]] = []  # (time [s], event) as they happened, for logs
        self.next_at = self._events[0].at if self._events else math.inf  # [s] the next event

    def due(self, now: float) -> bool:
        """Whether an event is due at ``now`` [s] (cheap: the tick asks every time)."""
        return now + TIME_TOLERANCE >= self.next_at

    def fire(self, now: float, robots: dict[str, Any]) -> bool:
        """Apply every event due at ``now`` [s]; True when one fired."""
        moved = False
        events = self._events
        while self._next < len(events) and events[self._next].at <= now + TIME_TOLERANCE:
            event = events[self._next]
            self._next += 1
            x, y, theta = event.teleport
            robots[event.robot].teleport(x, y, theta)
            self.fired.append((now, event))
            moved = True
        self.next_at = events[self._next].at if self._next < len(events) else math.inf
        return moved
