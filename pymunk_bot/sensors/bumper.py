"""A contact bumper all around the robot: touching now, where, and how many contact episodes."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import pymunk


@dataclass(frozen=True)
class BumperReading:
    """One bumper measurement."""

    time: float  # when it was taken [s]
    touching: bool  # in contact with anything (wall, obstacle, other robot) now
    # One unit vector per touching shape, in the robot frame (x forward, y left), pointing from
    # the robot into what it touches: (1, 0) is a hit straight ahead.
    normals: tuple[tuple[float, float], ...]
    episodes: int  # contact episodes so far (the run result's "collisions")


class Bumper:
    """Reads the robot body's contacts of the last physics substep, after every tick."""

    name = "bumper"

    passive = True  # needs no update per tick when it has a clock: its reading is built on demand

    def __init__(self, body: pymunk.Body, episodes: Callable[[], int],
                 clock: Callable[[], float] | None = None) -> None:
        self._body = body
        self._episodes = episodes
        self._clock = clock  # the simulation's time [s]; without one, update() sets the time
        self._time: float | None = None  # when the simulation last asked for a reading [s]

    @property
    def reading(self) -> BumperReading | None:
        """The contacts as of the last update (None before the first).

        Built on demand: contacts change only inside a physics step and update() runs after
        every step, so reading the body's arbiters now gives what update() time saw, without
        paying for it on every tick of every robot."""
        time = self._clock() if self._clock is not None else self._time
        if time is None:
            return None
        world_normals: list[tuple[float, float]] = []

        def collect(arbiter: pymunk.Arbiter) -> None:
            # pymunk orders each arbiter so that this body's shape comes first: the normal
            # points from the robot to the other shape.
            if arbiter.is_removal or not arbiter.contact_point_set.points:
                return
            n = arbiter.normal
            world_normals.append((n.x, n.y))

        self._body.each_arbiter(collect)
        angle = self._body.angle
        c, s = math.cos(angle), math.sin(angle)
        normals = tuple((c * nx + s * ny, -s * nx + c * ny) for nx, ny in world_normals)
        return BumperReading(time=time, touching=bool(normals), normals=normals,
                             episodes=self._episodes())

    @property
    def touching(self) -> bool:
        """True while the robot touches something."""
        reading = self.reading
        return reading is not None and reading.touching

    @property
    def normals(self) -> tuple[tuple[float, float], ...]:
        """Contact directions in the robot frame (see :class:`BumperReading`)."""
        reading = self.reading
        return () if reading is None else reading.normals

    @property
    def episodes(self) -> int:
        """Contact episodes so far."""
        return self._episodes()

    def update(self, time: float) -> None:
        """Mark a reading taken now (called after every tick)."""
        self._time = time
