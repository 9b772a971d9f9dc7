"""Path planning on the map a scenario describes: clearance grid, A*, smoothing, DWA."""
from .astar import PlanResult, astar
from .grid import ClearanceGrid
from .map import MapCircle, MapInfo, MapPolygon
from .paths import densify, path_length, shortcut

__all__ = ["ClearanceGrid", "MapCircle", "MapInfo", "MapPolygon", "PlanResult", "astar",
           "densify", "path_length", "shortcut"]
