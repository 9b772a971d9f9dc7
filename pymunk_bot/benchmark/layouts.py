"""Crowd layouts after CrowdNav's, placed over any static world (open, cluttered, a map). They
are not CrowdNav's test cases (those are benchmark/crowdnav.py's ``crowdnav_circle_crossing``).

Each layout is drawn from a seed: a stage (a square of side ``stage`` [m], turned by a random
angle and centred where the world has room; it shrinks, down to half, in a world with little
open room), the robot's start and goal on it, and
``humans`` pedestrians with their routes:

- ``circle_crossing`` (after CrowdNav): everyone starts on a circle of radius stage / 2 - 0.5
  (3.5 m on an 8 m stage) and walks to the far side, the goal jittered (N(0, 0.25 m) each way),
  no pedestrian starting within ROBOT_BUFFER of the robot's start or goal beyond the bodies
  (CrowdNav: the start is jittered, 0.2 m beyond the bodies, and nobody walks back);
- ``square_crossing`` (CrowdNav): pedestrians cross the stage from one side to the other while
  the robot crosses it the other way;
- ``corridor_passing``: a 3 m corridor (two walls); people walk both ways along it, most of
  them toward the robot;
- ``doorway``: a wall across the stage with a 1.2 m door; people come through it both ways.

Every start and goal is free by the static map (with the layout's own walls) with a margin,
and reachable within ROUTE_MARGIN of the stage: pedestrians walk the string-pulled A* route to
their goal (then back), so both pedestrian policies find their way through clutter. A draw that fails these is drawn again.
"""
from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from pymunk_bot.config.outlines import obstacle_outline
from pymunk_bot.planning.astar import astar
from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.map import MapCircle, MapInfo, MapPolygon, map_polygons
from pymunk_bot.planning.paths import path_length, shortcut

LAYOUTS = ("circle_crossing", "square_crossing", "corridor_passing", "doorway")
GRID = 0.1  # [m] planning grid of the placement checks and routes
MARGIN = 0.15  # [m] free space kept around every start and goal beyond the body
SEPARATION = 0.3  # [m] between the bodies of any two starts
ROBOT_BUFFER = 1.0  # [m] no pedestrian starts closer to the robot's start or goal than this
CORRIDOR_WIDTH = 3.0  # [m]
DOOR_WIDTH = 1.2  # [m]
WALL_THICKNESS = 0.1  # [m]
ATTEMPTS = 200  # draws of the stage over which it shrinks to half its size ...
MAX_ATTEMPTS = 1000  # ... again and again (a small stage may fit nothing), before giving up
HUMAN_ATTEMPTS = 200  # draws per pedestrian
ROUTE_MARGIN = 3.0  # [m] routes may leave the stage's disc by this much


class LayoutError(ValueError):
    """The world has no room for the layout (one line)."""


def static_map(world: dict, obstacles: list[dict], map_geometry: Any = None) -> MapInfo:
    """The static map of a world section and obstacle list (plain data); ``map_geometry``
    the loaded ``world.map`` if it has one."""
    from pymunk_bot import plugins

    plugins.load()
    polygons: list[MapPolygon] = []
    circles: list[MapCircle] = []
    if map_geometry is not None:
        polygons += map_polygons(map_geometry)
        x0, y0, x1, y1 = map_geometry.extent
    else:
        x0, y0, (x1, y1) = 0.0, 0.0, world["size"]
    for o in obstacles:
        if o.get("movable") or o.get("motion") or o.get("type") == "pedestrian":
            continue
        model = plugins.obstacles.entry(o["type"]).config.model_validate(o)
        outline = obstacle_outline(model)
        if outline is None:
            circles.append(MapCircle(tuple(model.center), model.radius))
        else:
            polygons.append(MapPolygon(np.asarray(outline, dtype=float)))
    return MapInfo((x1 - x0, y1 - y0), tuple(polygons), tuple(circles), (x0, y0))


def _wall(a: np.ndarray, b: np.ndarray) -> dict:
    return {"type": "wall", "start": [round(float(a[0]), 3), round(float(a[1]), 3)],
            "end": [round(float(b[0]), 3), round(float(b[1]), 3)], "thickness": WALL_THICKNESS}


class Stage:
    """A square of side ``side`` centred at ``centre``, turned by ``angle``: layout
    coordinates (u, v) in [-side/2, side/2]^2 -> world points."""

    def __init__(self, centre: np.ndarray, angle: float, side: float) -> None:
        self.centre, self.side = centre, side
        c, s = math.cos(angle), math.sin(angle)
        self.rotation = np.array([[c, -s], [s, c]])

    def at(self, u: float, v: float) -> np.ndarray:
        return self.centre + self.rotation @ np.array([u, v])


def _walls(name: str, stage: Stage) -> list[dict]:
    h = stage.side / 2
    if name == "corridor_passing":
        w = CORRIDOR_WIDTH / 2
        return [_wall(stage.at(-h, -w), stage.at(h, -w)), _wall(stage.at(-h, w), stage.at(h, w))]
    if name == "doorway":
        d = DOOR_WIDTH / 2
        return [_wall(stage.at(0, -h), stage.at(0, -d)), _wall(stage.at(0, d), stage.at(0, h))]
    return []


def _human_route(name: str, stage: Stage, rng: np.random.Generator
                 ) -> tuple[np.ndarray, np.ndarray]:
    """A pedestrian's start and goal on the stage."""
    h = stage.side / 2
    if name == "circle_crossing":
        a = rng.uniform(0, 2 * math.pi)
        r = h - 0.5
        jitter = rng.normal(0.0, 0.25, 2)
        return stage.at(r * math.cos(a), r * math.sin(a)), stage.at(
            -r * math.cos(a) + jitter[0], -r * math.sin(a) + jitter[1])
    if name == "square_crossing":
        side = rng.choice([-1.0, 1.0])
        return (stage.at(side * (h - 0.5), rng.uniform(-h + 0.5, h - 0.5)),
                stage.at(-side * (h - 0.5), rng.uniform(-h + 0.5, h - 0.5)))
    if name == "corridor_passing":
        w = CORRIDOR_WIDTH / 2 - 0.4
        toward = rng.uniform() < 0.7  # most come toward the robot
        start_u = rng.uniform(-h + 1.5, h - 0.5)
        end_u = -h + 0.5 if toward else h - 0.5
        return stage.at(start_u, rng.uniform(-w, w)), stage.at(end_u, rng.uniform(-w, w))
    # doorway: from one side through the door to the other
    side = 1.0 if rng.uniform() < 0.7 else -1.0  # most come from the goal's side
    return (stage.at(side * rng.uniform(1.0, h - 0.5), rng.uniform(-h + 0.5, h - 0.5)),
            stage.at(-side * rng.uniform(1.0, h - 0.5), rng.uniform(-h + 0.5, h - 0.5)))


def _robot_route(name: str, stage: Stage) -> tuple[np.ndarray, np.ndarray]:
    h = stage.side / 2 - 0.5
    if name == "square_crossing":
        return stage.at(0.0, -h), stage.at(0.0, h)
    return stage.at(-h, 0.0), stage.at(h, 0.0)


class Placement:
    """Free-space checks and routes on a static map."""

    def __init__(self, world_map: MapInfo, grid: ClearanceGrid | None = None) -> None:
        self.map = world_map
        self.grid = ClearanceGrid.from_map(world_map, GRID, cap=3.0) if grid is None else grid
        self._labels: dict[float, np.ndarray] = {}

    def around(self, stage: "Stage", walls: list[dict]) -> "Placement":
        """The part of this map within ROUTE_MARGIN of the stage (routes stay there: A* then
        searches a few thousand cells, not a whole building), with the layout's walls added."""
        g = self.grid
        reach = stage.side * math.sqrt(0.5) + ROUTE_MARGIN
        r0, c0 = g.cell_of(float(stage.centre[0] - reach), float(stage.centre[1] - reach))
        r1, c1 = g.cell_of(float(stage.centre[0] + reach), float(stage.centre[1] + reach))
        grid = g.copy()
        grid.clearance = g.clearance[r0:r1 + 1, c0:c1 + 1].copy()
        grid.rows, grid.cols = grid.clearance.shape
        grid.ys, grid.xs = g.ys[r0:r1 + 1], g.xs[c0:c1 + 1]
        grid.origin = (g.origin[0] + c0 * g.resolution, g.origin[1] + r0 * g.resolution)
        grid.size = (grid.cols * g.resolution, grid.rows * g.resolution)
        for polygon in static_map({"size": self.map.size}, walls).polygons:
            grid.add_polygon(polygon.points)
        return Placement(self.map, grid)

    def free(self, point: np.ndarray, radius: float) -> bool:
        x, y = float(point[0]), float(point[1])
        if not self.grid.inside(x, y):
            return False
        return bool(self.grid.clearance[self.grid.cell_of(x, y)] >= radius + MARGIN)

    def _regions(self, hard: float) -> np.ndarray:
        """Connected regions of the cells with at least ``hard`` [m] of clearance (0: none)."""
        if hard not in self._labels:
            from scipy.ndimage import label
            self._labels[hard] = label(self.grid.clearance >= hard, np.ones((3, 3)))[0]
        return self._labels[hard]

    def route(self, start: np.ndarray, goal: np.ndarray, radius: float
              ) -> list[tuple[float, float]] | None:
        """Waypoints from start to goal for a disc of ``radius`` (goal last), or None."""
        hard = radius + 0.05
        regions = self._regions(hard)
        a = regions[self.grid.cell_of(float(start[0]), float(start[1]))]
        if a == 0 or a != regions[self.grid.cell_of(float(goal[0]), float(goal[1]))]:
            return None  # not connected: no search through the whole map to find that out
        plan = astar(self.grid, start, goal, hard=hard, soft=hard + 0.2, weight=1.0)
        if plan.path is None:
            return None
        return [(round(x, 3), round(y, 3)) for x, y in shortcut(self.grid, plan.path, hard)[1:]]


_placements: dict[tuple, Placement] = {}
MAX_CACHED = 8  # static worlds' placement grids kept per process


def _placement(world: dict, obstacles: list[dict], map_geometry: Any) -> Placement:
    """The static world's Placement, built once per process (a map's grid takes a second)."""
    key = (json.dumps(world, sort_keys=True), json.dumps(obstacles, sort_keys=True),
           id(map_geometry))
    if key not in _placements:
        if len(_placements) >= MAX_CACHED:
            _placements.pop(next(iter(_placements)))
        _placements[key] = Placement(static_map(world, obstacles, map_geometry))
    return _placements[key]


def draw_layout(name: str, world: dict, obstacles: list[dict], robot: dict, humans: int,
                pedestrian: dict, stage: float, seed: int, map_geometry: Any = None
                ) -> tuple[list[dict], dict]:
    """(obstacles with the layout's walls and pedestrians, the robot with pose and goal) for
    layout ``name`` drawn from ``seed``. LayoutError when the world has no room for it."""
    if name not in LAYOUTS:
        raise LayoutError(f"unknown layout '{name}' (choose from {', '.join(LAYOUTS)})")
    rng = np.random.default_rng(seed)
    radius = float(robot.get("radius", 0.2))
    human_radius = float(pedestrian.get("radius", 0.25))
    whole = _placement(world, obstacles, map_geometry)
    x0, y0, x1, y1 = whole.map.extent
    side = min(stage, x1 - x0 - 0.4, y1 - y0 - 0.4)
    if side < 3.0:
        raise LayoutError(f"the world is too small for a {name} stage (needs 3 m, has {side:.2f} m)")
    for attempt in range(MAX_ATTEMPTS):
        # A world with little open room gets a stage that shrinks, down to half (or 3 m).
        size = max(3.0, side * (1.0 - 0.5 * (attempt % ATTEMPTS) / ATTEMPTS))
        centre = np.array([rng.uniform(x0 + size / 2, x1 - size / 2),
                           rng.uniform(y0 + size / 2, y1 - size / 2)])
        if map_geometry is None and not obstacles:
            centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
        st = Stage(centre, rng.uniform(0, 2 * math.pi), size)
        walls = _walls(name, st)
        place = whole.around(st, walls)
        start, goal = _robot_route(name, st)
        if not (place.free(start, radius) and place.free(goal, radius)):
            continue
        if place.route(start, goal, radius) is None:
            continue
        walkers = _walkers(name, st, place, rng, humans, human_radius, (start, goal), radius,
                           pedestrian)
        if walkers is None:
            continue
        heading = math.atan2(goal[1] - start[1], goal[0] - start[0])
        placed = dict(robot, pose=[round(float(start[0]), 3), round(float(start[1]), 3),
                                   round(heading, 4)])
        placed["goal"] = dict(robot.get("goal", {}), position=[round(float(goal[0]), 3),
                                                               round(float(goal[1]), 3)])
        return obstacles + walls + walkers, placed
    raise LayoutError(f"no room for the {name} layout in {MAX_ATTEMPTS} draws of seed {seed}")


def _walkers(name: str, stage: Stage, place: Placement, rng: np.random.Generator, humans: int,
             radius: float, robot_ends: tuple[np.ndarray, np.ndarray], robot_radius: float,
             pedestrian: dict) -> list[dict] | None:
    starts: list[np.ndarray] = []
    out: list[dict] = []
    for _ in range(humans):
        for _ in range(HUMAN_ATTEMPTS):
            start, goal = _human_route(name, stage, rng)
            if not (place.free(start, radius) and place.free(goal, radius)):
                continue
            if any(np.hypot(*(start - end)) < robot_radius + radius + ROBOT_BUFFER
                   for end in robot_ends):
                continue
            if any(np.hypot(*(start - s)) < 2 * radius + SEPARATION for s in starts):
                continue
            route = place.route(start, goal, radius)
            if route is None or path_length([tuple(start)] + route) < 1.0:
                continue
            starts.append(start)
            out.append(dict(pedestrian, type="pedestrian",
                            center=[round(float(start[0]), 3), round(float(start[1]), 3)],
                            goals=[list(p) for p in route], mode="pingpong"))
            break
        else:
            return None
    return out
