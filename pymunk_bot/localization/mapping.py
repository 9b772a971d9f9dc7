"""Occupancy-grid mapping from LiDAR scans at known poses (log-odds, inverse sensor model).

Each cell holds the log-odds l = log(p / (1 - p)) that it is occupied, 0 (p = 0.5) until seen.
For every beam of a scan, the cells it crosses before its end are a *miss* (l += logit(miss),
they were seen empty) and the cell where it ends is a *hit* (l += logit(hit)) when the beam
returned; a beam without a return (it reads max_range) only clears. Each cell is updated at most
once per scan (a cell crossed by many beams near the sensor is not cleared many times over),
and a hit wins over a miss in the same scan. l is clamped to [logit(min), logit(max)] so the map
can change its mind when the world does. Vectorised: all beams are sampled at half-cell steps.

Free-space clearing with decay (for people and other things that move): a cell held occupied
(l > 0) that a beam now crosses first has its log-odds multiplied by ``clear_decay`` and then
takes the miss. A walker's cells, hit for the second it stood there, end free after two or three
scans that see through them instead of the seven that the miss alone needed from the clamp,
while the robot may look elsewhere. A cell hit in the same scan is never cleared (a hit wins),
so a wall is kept by the beams that end on it.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.maps.grid import UNKNOWN, OccupancyGrid
from pymunk_bot.config.localization import MAX_MAP_CELLS, MappingConfig
from pymunk_bot.localization.se2 import transform_points


def logit(p: float) -> float:
    return float(np.log(p / (1.0 - p)))


class OccupancyMapper:
    """Builds an occupancy grid over ``extent`` = ((xmin, ymin), (xmax, ymax)) [m]."""

    def __init__(self, config: MappingConfig, extent: tuple[tuple[float, float], tuple[float, float]]) -> None:
        (x0, y0), (x1, y1) = extent
        if not (x1 > x0 and y1 > y0):
            raise ValueError(f"mapping extent must have positive size (got {extent})")
        res = config.resolution
        cols, rows = int(np.ceil((x1 - x0) / res)), int(np.ceil((y1 - y0) / res))
        if rows * cols > MAX_MAP_CELLS:
            raise ValueError(f"mapping: {cols}x{rows} cells at {res} m exceeds the limit of "
                             f"{MAX_MAP_CELLS} cells; use a coarser resolution")
        self.config = config
        self.origin = (float(x0), float(y0))
        self.log_odds = np.zeros((rows, cols))
        self.observed = np.zeros((rows, cols), dtype=bool)
        self._is_hit = np.zeros(rows * cols, dtype=bool)  # scratch: this scan's hit cells
        self._hit, self._miss = logit(config.hit_probability), logit(config.miss_probability)
        self._lo, self._hi = logit(config.min_probability), logit(config.max_probability)
        self.scans = 0  # scans integrated
        self._last_time: float | None = None

    @classmethod
    def for_arena(cls, config: MappingConfig, arena: tuple[float, float],
                  origin: tuple[float, float] = (0.0, 0.0)) -> "OccupancyMapper":
        """A mapper over the arena [x0, x0 + w] x [y0, y0 + h] (``origin`` = (x0, y0) [m], a
        ROS map's origin) plus ``config.margin`` on every side."""
        m = config.margin
        (x0, y0), (w, h) = origin, arena
        return cls(config, ((x0 - m, y0 - m), (x0 + w + m, y0 + h + m)))

    def due(self, time: float) -> bool:
        """Whether a scan taken at ``time`` [s] should be integrated (``rate`` limits it)."""
        rate = self.config.rate
        return rate is None or self._last_time is None or time - self._last_time >= 1.0 / rate - 1e-9

    def reset(self) -> None:
        """Forget every observation: the whole grid back to unknown."""
        self.log_odds[:] = 0.0
        self.observed[:] = False
        self.scans = 0
        self._last_time = None

    def integrate(self, pose: np.ndarray, scan) -> None:
        """Fold one LaserScan taken at robot ``pose`` [x, y, theta] into the map."""
        res = self.config.resolution
        ranges = np.asarray(scan.ranges, dtype=float)
        angles = np.asarray(scan.angles, dtype=float)
        valid = np.isfinite(ranges) & (ranges >= scan.min_range)
        ranges, angles = np.minimum(ranges[valid], scan.max_range), angles[valid]
        if ranges.size == 0:
            return
        hit = ranges < scan.max_range
        origin = transform_points(pose, np.array([[scan.offset[0], scan.offset[1]]]))[0]
        heading = float(pose[2]) + angles
        direction = np.stack([np.cos(heading), np.sin(heading)], axis=-1)  # (m, 2)
        step = 0.5 * res
        # Samples at half-cell steps from the sensor to just short of each beam's end cell.
        counts = np.maximum(np.ceil(ranges / step).astype(np.intp) - 1, 0)
        beam = np.repeat(np.arange(ranges.size), counts)
        first = np.cumsum(counts) - counts
        t = (np.arange(beam.size) - first[beam]) * step
        miss_cells = self._flat_cells(origin + t[:, None] * direction[beam])
        hit_cells = self._flat_cells(origin + ranges[hit, None] * direction[hit])
        # Fancy-index updates apply once per distinct index: each cell changes once per scan.
        self._is_hit[hit_cells] = True
        miss_cells = miss_cells[~self._is_hit[miss_cells]]
        self._is_hit[hit_cells] = False
        flat_l, flat_seen = self.log_odds.reshape(-1), self.observed.reshape(-1)
        held = miss_cells[flat_l[miss_cells] > 0.0]
        flat_l[held] *= self.config.clear_decay
        flat_l[miss_cells] += self._miss
        flat_l[hit_cells] += self._hit
        np.clip(flat_l, self._lo, self._hi, out=flat_l)
        flat_seen[miss_cells] = True
        flat_seen[hit_cells] = True
        self.scans += 1
        self._last_time = scan.time

    def near_surface(self, xy: np.ndarray, radius: float, probability: float = 0.5) -> np.ndarray:
        """Boolean (m,): which world points ``xy`` (m, 2) [m] have a cell within ``radius`` [m]
        (a square of cells; cells off the grid read as its edge) that the map holds occupied
        with more than ``probability``."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        rows, cols = self.log_odds.shape
        res = self.config.resolution
        reach = int(np.ceil(radius / res))
        offsets = np.arange(-reach, reach + 1)
        col = np.floor((xy[:, 0] - self.origin[0]) / res).astype(np.intp)
        row = np.floor((xy[:, 1] - self.origin[1]) / res).astype(np.intp)
        r = np.clip(row[:, None, None] + offsets[None, :, None], 0, rows - 1)  # (m, k, 1)
        c = np.clip(col[:, None, None] + offsets[None, None, :], 0, cols - 1)  # (m, 1, k)
        held = self.observed[r, c] & (self.log_odds[r, c] > logit(probability) + 1e-9)
        return held.reshape(xy.shape[0], -1).any(axis=1)

    def _flat_cells(self, xy: np.ndarray) -> np.ndarray:
        rows, cols = self.log_odds.shape
        col = np.floor((xy[..., 0] - self.origin[0]) / self.config.resolution).astype(np.intp)
        row = np.floor((xy[..., 1] - self.origin[1]) / self.config.resolution).astype(np.intp)
        inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
        return (row[inside] * cols + col[inside]).ravel()

    @property
    def grid(self) -> OccupancyGrid:
        """The map so far: -1 unknown, else the occupancy probability in percent."""
        p = 1.0 / (1.0 + np.exp(-self.log_odds))
        data = np.where(self.observed, np.rint(100.0 * p), UNKNOWN).astype(np.int8)
        return OccupancyGrid(data, self.config.resolution, self.origin)
