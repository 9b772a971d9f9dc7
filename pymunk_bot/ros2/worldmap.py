"""The occupancy grid served on ``/map``: the arena and its fixed obstacles, rasterised by
:func:`pymunk_bot.maps.rasterize.grid_from_map` (the one rasteriser, which the localizers' maps
use too), from a scenario or from the shapes a run log keeps."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from pymunk_bot.maps.grid import OccupancyGrid

MAP_RESOLUTION = 0.05  # [m] of /map (Nav2's usual)
MAX_MAP_CELLS = 4_000_000  # a bigger arena gets coarser cells rather than a huge message


def _resolution(width: float, height: float) -> float:
    return max(MAP_RESOLUTION, math.sqrt(width * height / MAX_MAP_CELLS))


def world_grid(config) -> OccupancyGrid:
    """The scenario's arena and fixed obstacles (a ROS map file's own cells included)."""
    from pymunk_bot.maps.rasterize import scenario_grid

    x0, y0, x1, y1 = config.world.extent
    return scenario_grid(config, _resolution(x1 - x0, y1 - y0))


def geometry_grid(geometry) -> OccupancyGrid:
    """The fixed shapes of a :class:`~pymunk_bot.foxglove.snapshot.RunGeometry` (what a run
    log keeps: a converted log has no scenario). Arena walls are left to the rasteriser,
    which marks everything outside the arena occupied."""
    from pymunk_bot.maps.rasterize import grid_from_map
    from pymunk_bot.planning.map import MapCircle, MapInfo, map_polygons

    pieces, segments, radii, circles = [], [], [], []
    for shape in geometry.fixed:
        points = np.asarray(shape.points, dtype=float).reshape(-1, 2)
        if shape.wall:
            continue
        if shape.kind == "circle":
            circles.append(MapCircle((float(points[0, 0]), float(points[0, 1])),
                                     float(shape.radius)))
        elif shape.kind == "segment":
            segments.append(points[:2].reshape(4))
            radii.append(float(shape.radius))
        else:
            pieces.append(points)
    # a segment with a thickness is the rectangle it sweeps, as for a map file's strokes
    polygons = map_polygons(SimpleNamespace(polygons=pieces, segments=np.reshape(segments, (-1, 4)),
                                            segment_radius=np.array(radii)))
    origin = tuple(float(v) for v in geometry.meta.get("origin", (0.0, 0.0)))
    info = MapInfo(size=(float(geometry.width), float(geometry.height)), polygons=tuple(polygons),
                   circles=tuple(circles), origin=(origin[0], origin[1]))
    return grid_from_map(info, _resolution(geometry.width, geometry.height))

