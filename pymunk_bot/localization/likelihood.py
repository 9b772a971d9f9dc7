"""The likelihood field of a map: distance from any point to the nearest surface of an obstacle.

Built once with scipy's exact Euclidean distance transform. Distances are measured to the
*edge* of the occupied region, where a LiDAR beam stops in this project's maps: the scenario
rasterizer and a ROS map turned into geometry both make occupied cells solid, surface at their
boundary. (ROS AMCL measures to cell centres, which puts every wall half a cell too far.) The
occupied mask is upsampled before the transform so that the edge is found to within half a
sub-cell; points off the grid read ``max_dist`` (as AMCL's beams ending off the map do).
Inside an obstacle the distance is to its surface, not 0: a ROS map's shelves and walls are
solid here (occupied and unknown cells alike), and a field that read 0 everywhere inside them
let an estimate slide half a metre into a shelf with every beam still "on" the map (measured in
Nav2's warehouse map, where AMCL's field, built from the occupied outline alone, would not).
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import distance_transform_edt

from pymunk_bot.maps.grid import FREE_THRESH, OccupancyGrid

MAX_FIELD_CELLS = 64_000_000  # upsampled cells; ~512 MB of float64


class LikelihoodField:
    """Distance [m] to the nearest occupied cell, capped at ``max_dist``, with a smooth lookup."""

    def __init__(self, grid: OccupancyGrid, max_dist: float = 2.0, upsample: int | None = None,
                 to_edges: bool = True) -> None:
        """``to_edges`` False: measure to occupied cell centres instead (maps built from LiDAR
        hits, where the surface lies inside the cell that a beam ended in)."""
        if upsample is None:  # as fine as a few MB allow
            upsample = next(k for k in (4, 2, 1) if grid.rows * grid.cols * k * k <= 4_000_000 or k == 1)
        if not max_dist > 0:
            raise ValueError(f"max_dist must be > 0 (got {max_dist})")
        if grid.rows * grid.cols * upsample * upsample > MAX_FIELD_CELLS:
            raise ValueError(f"the map is too large for a likelihood field: {grid.rows}x{grid.cols} "
                             f"cells x{upsample}^2 exceeds {MAX_FIELD_CELLS} cells")
        self.grid = grid
        self.max_dist = float(max_dist)  # [m]
        self.resolution = grid.resolution / upsample  # [m] per field cell
        self.origin = np.asarray(grid.origin, dtype=float)
        occupied = grid.occupied()
        fine = np.kron(occupied, np.ones((upsample, upsample), dtype=bool))
        if occupied.any():
            # From a sub-cell centre to the nearest occupied sub-cell's edge; inside a solid
            # region, to its surface (the nearest free sub-cell's edge): a beam stops at the
            # surface, so an end point deep inside a shelf is as wrong as one in the open.
            if to_edges:
                dist = distance_transform_edt(~fine) * self.resolution - 0.5 * self.resolution
                if not fine.all():
                    depth = distance_transform_edt(fine) * self.resolution - 0.5 * self.resolution
                    dist[fine] = depth[fine]
            else:  # the outermost sub-cell centre lies (res - res/k) / 2 past the cell's centre
                dist = distance_transform_edt(~fine) * self.resolution + 0.5 * (
                    grid.resolution - self.resolution)
                dist[fine] = 0.0
            self.field = np.clip(dist, 0.0, self.max_dist)
        else:
            self.field = np.full((grid.rows * upsample, grid.cols * upsample), self.max_dist)
        # Padded with max_dist so off-grid lookups need no special case.
        self._padded = np.pad(self.field, 1, constant_values=self.max_dist)
        self._solid = np.pad(fine, 1, constant_values=False)  # inside an obstacle
        self.free_xy = self._free_cell_centres(grid)

    @staticmethod
    def _free_cell_centres(grid: OccupancyGrid) -> np.ndarray:
        """World (x, y) of cells known to be free, where global localization seeds particles."""
        free = (grid.data >= 0) & (grid.data < round(100 * FREE_THRESH))
        rows, cols = np.nonzero(free)
        xs, ys = grid.cell_centers()
        return np.stack([xs[cols], ys[rows]], axis=-1)

    def distance(self, xy: np.ndarray) -> np.ndarray:
        """Distance [m] at points ``xy`` (..., 2) from the containing field cell (fast, MCL)."""
        return self._padded[self._cells(xy)]

    def clearance(self, xy: np.ndarray) -> np.ndarray:
        """:meth:`distance` outside obstacles and 0 inside them: how far a ray from ``xy``
        may go before it could hit something (a sphere tracer's step)."""
        cells = self._cells(xy)
        return np.where(self._solid[cells], 0.0, self._padded[cells])

    def _cells(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) of the padded field's cell holding each point of ``xy`` (..., 2)."""
        xy = np.asarray(xy, dtype=float)
        rows, cols = self._padded.shape
        col = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.intp) + 1
        row = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.intp) + 1
        np.clip(col, 0, cols - 1, out=col)
        np.clip(row, 0, rows - 1, out=row)
        return row, col

    def distance_and_gradient(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bilinear distance [m] at ``xy`` (n, 2) and its gradient d/d(x, y) (n, 2)."""
        xy = np.asarray(xy, dtype=float)
        rows, cols = self._padded.shape
        # Continuous index of padded-field cell centres.
        u = (xy[:, 0] - self.origin[0]) / self.resolution + 0.5
        v = (xy[:, 1] - self.origin[1]) / self.resolution + 0.5
        u = np.clip(u, 0.0, cols - 1.000001)
        v = np.clip(v, 0.0, rows - 1.000001)
        c0, r0 = np.floor(u).astype(np.intp), np.floor(v).astype(np.intp)
        fu, fv = u - c0, v - r0
        f = self._padded
        d00, d01 = f[r0, c0], f[r0, c0 + 1]
        d10, d11 = f[r0 + 1, c0], f[r0 + 1, c0 + 1]
        dist = (d00 * (1 - fu) * (1 - fv) + d01 * fu * (1 - fv)
                + d10 * (1 - fu) * fv + d11 * fu * fv)
        gx = ((d01 - d00) * (1 - fv) + (d11 - d10) * fv) / self.resolution
        gy = ((d10 - d00) * (1 - fu) + (d11 - d01) * fu) / self.resolution
        return dist, np.stack([gx, gy], axis=-1)
