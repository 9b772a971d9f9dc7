"""An occupancy grid in the ROS ``nav_msgs/OccupancyGrid`` convention, in world metres.

``data[row, col]`` is -1 (unknown) or an occupancy probability in percent, 0..100. Row 0 is the
bottom row (smallest y): the array is stored with y up, as the world frame is, so cell
(row, col) covers ``origin + (col, row) * resolution`` to one cell further. Images (PGM/PNG) are
stored top row first: flip rows when reading or writing one.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

UNKNOWN = -1
FREE = 0
OCCUPIED = 100
# ROS map_server's defaults for what counts as occupied / free [probability]
OCCUPIED_THRESH = 0.65
FREE_THRESH = 0.196


@dataclass(frozen=True)
class OccupancyGrid:
    """A 2D grid of occupancy values; see the module docstring for the layout."""

    data: np.ndarray  # int8, (rows, cols): -1 unknown, 0..100 percent occupied
    resolution: float  # [m] per cell
    origin: tuple[float, float] = (0.0, 0.0)  # [m] world position of cell (0, 0)'s lower-left corner

    def __post_init__(self) -> None:
        data = np.asarray(self.data)
        if data.ndim != 2 or data.size == 0:
            raise ValueError(f"an occupancy grid needs a non-empty 2D array (got shape {data.shape})")
        if not (np.isfinite(self.resolution) and self.resolution > 0):
            raise ValueError(f"resolution must be > 0 (got {self.resolution})")

    @property
    def rows(self) -> int:
        return int(self.data.shape[0])

    @property
    def cols(self) -> int:
        return int(self.data.shape[1])

    @property
    def size(self) -> tuple[float, float]:
        """Width and height of the grid [m]."""
        return (self.cols * self.resolution, self.rows * self.resolution)

    def occupied(self, threshold: float = OCCUPIED_THRESH) -> np.ndarray:
        """Boolean (rows, cols): cells at or above ``threshold`` probability."""
        return self.data >= round(100 * threshold)

    def unknown(self) -> np.ndarray:
        """Boolean (rows, cols): cells with no information."""
        return self.data < 0

    def cell_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) integer indices of world points ``xy`` [m], shape (..., 2); may be out of range."""
        xy = np.asarray(xy, dtype=float)
        col = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.intp)
        row = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.intp)
        return row, col

    def inside(self, row: np.ndarray, col: np.ndarray) -> np.ndarray:
        """Which (row, col) lie on the grid."""
        return (row >= 0) & (row < self.rows) & (col >= 0) & (col < self.cols)

    def cell_centers(self) -> tuple[np.ndarray, np.ndarray]:
        """World x (cols,) and y (rows,) of the cell centres [m]."""
        r = self.resolution
        return (self.origin[0] + (np.arange(self.cols) + 0.5) * r,
                self.origin[1] + (np.arange(self.rows) + 0.5) * r)
