"""Path planning on the map a scenario describes: clearance grid, A*, smoothing, DWA."""
from pymunk_bot.planning.astar import PlanResult, astar
from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.map import MapCircle, MapInfo, MapPolygon
from pymunk_bot.planning.paths import densify, path_length, shortcut

__all__ = ["ClearanceGrid", "MapCircle", "MapInfo", "MapPolygon", "PlanResult", "astar",
           "densify", "path_length", "shortcut"]
