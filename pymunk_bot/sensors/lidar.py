"""A 2D LiDAR: beams cast from the sensor's mount on the robot, with the errors real scanners have.

Measurement model, per beam (true range d from the ray caster, which stops at max_range):
    no return           if d < min_range or d >= max_range, or with probability ``dropout``
    d + N(0, noise_std^2), clipped to [min_range, max_range]   otherwise
A beam without a return reads max_range. Beam angles are fixed in the robot frame (see
:func:`beam_angles`); the robot's own body is invisible because the rays use its shape filter.
"""
from __future__ import annotations

import math
from typing import Protocol

import numpy as np
import pymunk

from pymunk_bot.config.schema import LidarConfig
from pymunk_bot.robots.readings import LaserScan
from pymunk_bot.sensors.schedule import Schedule

FULL_CIRCLE_TOLERANCE = 1e-9  # [rad]; a fov this close to 2*pi is a full circle


class Caster(Protocol):
    """What the LiDAR needs from a ray caster (``raycast.RayCaster`` is the real one)."""

    def cast(self, origin: tuple[float, float], world_angles: np.ndarray, max_range: float,
             shape_filter: pymunk.ShapeFilter) -> np.ndarray: ...


def beam_angles(beams: int, fov: float) -> np.ndarray:
    """Beam angles [rad] in the sensor frame, ascending (counter-clockwise), centred on 0.

    A full circle has ``beams`` equal steps and no beam repeated at +-pi; beam ``beams // 2``
    looks straight ahead (for an even count the first beam is at -pi). A partial field of
    view has beams at both ends, -fov/2 and +fov/2; a single beam looks straight ahead.
    """
    if beams < 1:
        raise ValueError(f"beams must be >= 1 (got {beams})")
    if fov >= 2.0 * math.pi - FULL_CIRCLE_TOLERANCE:
        step = 2.0 * math.pi / beams
        return (np.arange(beams) - beams // 2) * step
    if beams == 1:
        return np.zeros(1)
    return np.linspace(-0.5 * fov, 0.5 * fov, beams)


# Standard normals a LiDAR draws ahead for its periodic scans' noise (whole scans of them) [draws]:
# 16 kB each, so a thousand LiDARs hold 16 MB.
NORMALS_AHEAD = 2048


class Lidar:
    """A scanning range finder mounted at ``config.offset`` on a robot body.

    ``ranges`` / ``latest`` hold the measurement taken at the sensor's own rate (the simulation
    calls :meth:`update` after every tick); :meth:`scan` measures now, on demand, from its own
    random stream so that calling it never changes the periodic scans.
    """

    name = "lidar"

    def __init__(self, config: LidarConfig, body: pymunk.Body, shape_filter: pymunk.ShapeFilter,
                 caster: Caster, rng: np.random.Generator, start_time: float = 0.0) -> None:
        self.config = config
        self.body = body
        self.shape_filter = shape_filter
        self._caster = caster
        self._periodic_rng, self._on_demand_rng = rng.spawn(2)
        self._schedule = Schedule(config.rate, start_time)
        x, y, yaw = config.offset
        self._mount = (float(x), float(y))  # [m] in the robot frame
        self.offset = (float(x), float(y), float(yaw))
        angles = float(yaw) + beam_angles(config.beams, config.fov)
        angles.setflags(write=False)
        self._angles = angles
        # The error model as floats, for LidarRows.store: (noise_std, min_range,
        # max_range, dropout).
        self.model = (float(config.noise_std), float(config.min_range),
                       float(config.max_range), float(config.dropout))
        # The latest periodic scan as kept (time [s], ranges [m]), and as a LaserScan once read:
        # a fleet's scans mostly go to arrays (policies, the vector env) and are never read as one.
        self._kept: tuple[float, np.ndarray] | None = None
        self._latest: LaserScan | None = None
        self._normals_ahead: np.ndarray | None = None  # periodic noise drawn ahead (_normals)
        self._normals_used = 0

    # ------------------------------------------------------------------ public API
    @property
    def angles(self) -> np.ndarray:
        """Beam angles relative to the robot heading [rad] (mount yaw included), read-only."""
        return self._angles

    @property
    def ranges(self) -> np.ndarray | None:
        """Ranges [m] of the latest periodic scan (read-only), None before the first."""
        return None if self._kept is None else self._kept[1]

    @property
    def reading(self) -> LaserScan | None:
        """The latest periodic scan (the sensor contract's name for ``latest``)."""
        return self.latest

    def origin(self) -> tuple[float, float]:
        """Where the beams start now, in the world frame [m]."""
        body = self.body
        # At the body's origin: its position, exactly (what local_to_world gives, cheaper).
        p = body.position if self._mount == (0.0, 0.0) else body.local_to_world(self._mount)
        return (p.x, p.y)

    def cast_request(self) -> tuple[tuple[float, float], np.ndarray, float, pymunk.ShapeFilter]:
        """(origin, world-frame beam angles, max range, filter) of a cast from here now."""
        return self.origin(), self.body.angle + self._angles, self.config.max_range, self.shape_filter

    def true_ranges(self) -> np.ndarray:
        """Noise-free distances [m] to the first thing each beam meets, capped at max_range."""
        return self._caster.cast(*self.cast_request())

    def scan(self) -> np.ndarray:
        """Cast the beams now at the current pose: ranges [m] with the configured errors."""
        return self._measure(self._on_demand_rng)

    @property
    def schedule(self) -> Schedule:
        """When periodic scans are due (the simulation checks every LiDAR's at once)."""
        return self._schedule

    def update(self, time: float) -> None:
        """Take a scan if one is due at ``time`` [s] (called after every tick)."""
        if self._schedule.due(time):
            self.record(time, self.true_ranges())

    def record(self, time: float, true_ranges: np.ndarray) -> None:
        """Store the periodic scan taken at ``time`` [s] from these noise-free ranges [m]."""
        ranges = self._apply_model(true_ranges, self._periodic_rng)
        ranges.setflags(write=False)
        self.keep(time, ranges)

    def keep(self, time: float, ranges: np.ndarray) -> None:
        """Make ``ranges`` [m] (the error model applied, read-only) the latest periodic scan,
        taken at ``time`` [s]."""
        self._kept = (time, ranges)
        self._latest = None

    @property
    def latest(self) -> LaserScan | None:
        """The latest periodic scan, None before the first."""
        if self._latest is None and self._kept is not None:
            time, ranges = self._kept
            c = self.config
            self._latest = LaserScan(ranges=ranges, angles=self._angles, min_range=c.min_range,
                                     max_range=c.max_range, offset=self.offset, time=time)
        return self._latest

    @property
    def latest_time(self) -> float | None:
        """When the latest periodic scan was taken [s] (None before the first), without
        building it."""
        return None if self._kept is None else self._kept[0]

    # ------------------------------------------------------------------ model
    def _measure(self, rng: np.random.Generator) -> np.ndarray:
        return self._apply_model(self.true_ranges(), rng)

    def _apply_model(self, true: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        c = self.config
        if c.noise_std == 0.0 and c.dropout == 0.0:  # exact ranges: the limits only
            np.minimum(true, c.max_range, out=true)
            short = true < c.min_range
            if short.any():
                true[short] = c.max_range
            return true
        no_return = (true < c.min_range) | (true >= c.max_range)
        if c.noise_std > 0.0:
            ranges = true + c.noise_std * self._normals(rng, true.shape[0])
            np.maximum(ranges, c.min_range, out=ranges)  # np.clip costs twice as much
            np.minimum(ranges, c.max_range, out=ranges)
        else:
            ranges = true
        if c.dropout > 0.0:
            no_return |= rng.random(true.shape[0]) < c.dropout
        ranges[no_return] = c.max_range
        return ranges

    def periodic_normals(self, n: int) -> np.ndarray:
        """``n`` standard normals of the periodic scans' noise stream (LidarRows.store draws a
        batch of scans' noise through this, as each scan would)."""
        return self._normals(self._periodic_rng, n)

    def periodic_dropout(self, n: int, dropout: float) -> np.ndarray:
        """Which of ``n`` beams of a periodic scan drop out (probability ``dropout``)."""
        return self._periodic_rng.random(n) < dropout

    def _normals(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` standard normal draws from ``rng``. The periodic stream's come from a block
        drawn ahead, several scans at once (a draw costs ~2 us of call for 1 us of numbers);
        they are the same numbers in the same order, as the stream gives nothing else unless
        dropout draws from it too (then they are drawn scan by scan)."""
        if rng is not self._periodic_rng or self.config.dropout > 0.0:
            return rng.standard_normal(n)
        block, used = self._normals_ahead, self._normals_used
        if block is None or used + n > block.shape[0]:
            block = self._normals_ahead = rng.standard_normal(max(1, NORMALS_AHEAD // n) * n)
            used = 0
        self._normals_used = used + n
        return block[used:used + n]
