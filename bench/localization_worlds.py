"""The worlds localization is measured in: a 10 x 8 m office, and a ROS-style map image.

The office is a scenario (walls, doorways, desks). The "ROS map" is a map_server-style image
(0 = occupied, 254 = free, 205 = unknown outside the building, ragged walls, furniture),
read with map_server's trinary thresholds into an OccupancyGrid; the simulation's geometry is
built from that grid's occupied cells (merged into boxes), so MCL and EKF localize against the
map itself, unknown cells and all, while the LiDAR sees the same walls.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.maps.grid import FREE_THRESH, OCCUPIED_THRESH, OccupancyGrid

# Drifting odometry, as an uncalibrated robot's (docs/sensors.md): wheel radii off by +1 % and
# -0.5 % (a 3 deg/m curve), track width off by 2 %, noisy 1 mm encoders. Over the office route
# (~36 m) odometry alone ends metres from the truth.
DRIFTING_ODOMETRY = {"wheel_noise_std": 0.005, "left_scale_error": 0.01,
                     "right_scale_error": -0.005, "track_width_error": 0.02,
                     "encoder_resolution": 0.001}
LIDAR = {"beams": 360, "max_range": 8.0, "noise_std": 0.01, "rate": 10.0}

OFFICE_ROUTE = [(4.8, 1.0), (4.8, 3.6), (8.8, 3.6), (8.8, 5.4), (7.0, 5.4), (7.0, 3.6),
                (2.6, 3.6), (2.6, 6.0), (5.3, 6.0), (5.3, 7.6), (1.5, 7.6), (1.5, 5.8),
                (2.6, 5.6), (2.6, 4.2), (1.0, 3.6), (1.0, 1.4)]  # ~36 m through every room


def office_scenario(seed: int = 0, odometry: dict | None = None, start=(1.0, 1.0, 0.0)) -> dict:
    """A 10 x 8 m office: two walls with doorways, desks, a pillar; LiDAR 360 beams, 1 cm noise."""
    return {
        "name": "office", "seed": seed, "world": {"size": [10.0, 8.0]},
        "obstacles": [
            {"type": "wall", "start": [6.0, 0.0], "end": [6.0, 3.0], "thickness": 0.1},
            {"type": "wall", "start": [6.0, 4.2], "end": [6.0, 8.0], "thickness": 0.1},
            {"type": "wall", "start": [0.0, 5.0], "end": [2.0, 5.0], "thickness": 0.1},
            {"type": "wall", "start": [3.2, 5.0], "end": [6.0, 5.0], "thickness": 0.1},
            {"type": "box", "center": [2.5, 2.3], "size": [1.2, 0.6]},
            {"type": "box", "center": [8.0, 6.6], "size": [1.0, 0.8]},
            {"type": "circle", "center": [8.6, 1.5], "radius": 0.3},
            {"type": "box", "center": [4.5, 6.8], "size": [0.8, 0.5]},
            {"type": "box", "center": [0.8, 7.2], "size": [0.6, 0.6]},
        ],
        "robots": [{"name": "r1", "pose": [float(v) for v in start], "lidar": dict(LIDAR),
                    "odometry": dict(DRIFTING_ODOMETRY if odometry is None else odometry)}],
    }


# ---------------------------------------------------------------------------- the ROS-style map
ROS_MAP_SIZE = (12.0, 10.0)  # [m] image extent
ROS_MAP_RESOLUTION = 0.05  # [m]
ROS_BUILDING = (1.0, 1.0, 11.0, 9.0)  # [m] outer wall box xmin, ymin, xmax, ymax
ROS_ROUTE = [(5.0, 2.0), (5.0, 5.0), (9.5, 5.0), (9.5, 7.4), (8.2, 7.4), (8.2, 5.0),
             (2.5, 5.0), (2.5, 8.4), (5.5, 8.4), (5.5, 6.85), (2.5, 6.85), (2.5, 5.0),
             (3.0, 2.0)]  # ~37 m through every room
ROS_START = (2.2, 2.2, 0.0)


def ros_map_image(seed: int = 0) -> np.ndarray:
    """A map_server-style image (rows top first): 0 occupied, 254 free, 205 unknown."""
    rng = np.random.default_rng([seed, 2011])
    res = ROS_MAP_RESOLUTION
    rows, cols = round(ROS_MAP_SIZE[1] / res), round(ROS_MAP_SIZE[0] / res)
    occ = np.zeros((rows, cols), dtype=bool)  # row 0 at the bottom while drawing
    known = np.zeros((rows, cols), dtype=bool)

    def cells(x0, y0, x1, y1):
        return slice(round(y0 / res), round(y1 / res)), slice(round(x0 / res), round(x1 / res))

    x0, y0, x1, y1 = ROS_BUILDING
    known[cells(x0 - 0.15, y0 - 0.15, x1 + 0.15, y1 + 0.15)] = True
    t = 0.15  # [m] wall thickness
    for box in [(x0 - t, y0 - t, x1 + t, y0), (x0 - t, y1, x1 + t, y1 + t),
                (x0 - t, y0, x0, y1), (x1, y0, x1 + t, y1),
                # interior walls with doorways
                (7.5, y0, 7.5 + t, 3.6), (7.5, 6.2, 7.5 + t, y1),
                (x0, 6.3, 1.9, 6.3 + t), (3.1, 6.3, 7.5, 6.3 + t),
                # furniture
                (3.5, 2.8, 4.5, 3.6), (8.6, 2.0, 10.4, 2.6), (8.3, 8.2, 9.8, 9.0),
                (3.6, 7.3, 4.4, 7.8), (1.0, 3.9, 1.5, 4.8)]:
        occ[cells(*box)] = True
    # a round table
    yy, xx = (np.mgrid[0:rows, 0:cols] + 0.5) * res
    occ |= (xx - 5.8) ** 2 + (yy - 3.2) ** 2 < 0.35 ** 2
    # ragged wall faces, as a real map's are: a few one-cell bumps on occupied edges
    edge = occ & ~np.roll(occ, 1, axis=0)
    bumps = edge & (rng.random(occ.shape) < 0.08)
    occ |= np.roll(bumps, -1, axis=0) & known
    image = np.where(occ, 0, np.where(known, 254, 205)).astype(np.uint8)
    return image[::-1]


def grid_from_image(image: np.ndarray, resolution: float, origin=(0.0, 0.0)) -> OccupancyGrid:
    """map_server's trinary reading: p = (255 - v) / 255; occupied > 0.65, free < 0.196."""
    p = (255.0 - image[::-1].astype(float)) / 255.0
    data = np.where(p > OCCUPIED_THRESH, 100, np.where(p < FREE_THRESH, 0, -1)).astype(np.int8)
    return OccupancyGrid(data, resolution, origin)


def occupied_boxes(grid: OccupancyGrid) -> list[dict]:
    """The occupied cells as few axis-aligned boxes (row runs merged upward while equal)."""
    occ = grid.occupied().copy()
    res = grid.resolution
    boxes = []
    for row in range(grid.rows):
        line = occ[row]
        col = 0
        while col < grid.cols:
            if not line[col]:
                col += 1
                continue
            end = col
            while end < grid.cols and line[end]:
                end += 1
            top = row + 1
            while top < grid.rows and occ[top, col:end].all() and (
                    end == grid.cols or not occ[top, end]) and (col == 0 or not occ[top, col - 1]):
                occ[top, col:end] = False
                top += 1
            cx = grid.origin[0] + 0.5 * (col + end) * res
            cy = grid.origin[1] + 0.5 * (row + top) * res
            boxes.append({"type": "box", "center": [cx, cy], "size": [(end - col) * res, (top - row) * res]})
            col = end
    return boxes


def ros_map_world(seed: int = 0, odometry: dict | None = None,
                  start=ROS_START) -> tuple[dict, OccupancyGrid]:
    """(scenario whose geometry is the map's occupied cells, the map as an OccupancyGrid)."""
    grid = grid_from_image(ros_map_image(seed), ROS_MAP_RESOLUTION)
    scenario = {
        "name": "ros_map", "seed": seed, "world": {"size": list(ROS_MAP_SIZE)},
        "obstacles": occupied_boxes(grid),
        "robots": [{"name": "r1", "pose": [float(v) for v in start], "lidar": dict(LIDAR),
                    "odometry": dict(DRIFTING_ODOMETRY if odometry is None else odometry)}],
    }
    return scenario, grid


def route_from(route: list, start_xy, index: int) -> tuple[tuple[float, float, float], list]:
    """Start at waypoint ``index`` of a closed tour (start_xy + route), facing the next one; the
    rest of the tour follows. Different seeds start at different places (global localization)."""
    home = (float(start_xy[0]), float(start_xy[1]))
    tour = [home] + [tuple(p) for p in route if np.hypot(p[0] - home[0], p[1] - home[1]) > 1e-6]
    i = index % len(tour)
    here, ahead = tour[i], tour[(i + 1) % len(tour)]
    heading = float(np.arctan2(ahead[1] - here[1], ahead[0] - here[0]))
    return (here[0], here[1], heading), tour[i + 1:] + tour[:i]  # not back to the start itself


# ---------------------------------------------------------------------------- people on the route
WALKER_RADIUS = 0.25  # [m] a pedestrian's default body disc
WALKER_CLEARANCE = 0.45  # [m] a walker's start and goals this far from the map's obstacles
WALKER_SPACING = 0.7  # [m] between walkers' starts
ROBOT_KEEP_OUT = 1.2  # [m] no walker starts this close to the robot
ON_ROUTE_SHARE = 0.5  # of the walkers pace the robot's route (ahead of it and towards it)
MAX_WALKER_DRAWS = 100_000  # bounded placement
# Route draws failing this many times in a row: the route is full (a short one in a small
# office holds 13 walkers 0.7 m apart), and the rest of its share walk between free points.
ROUTE_FULL_AFTER = 10_000
GRID_RESOLUTION = 0.1  # [m] of the clearance grid walkers are placed on


def with_walkers(data: dict, walkers: int, policy: str, seed: int) -> dict:
    """``data`` (a one-robot scenario with a goal) plus ``walkers`` pedestrians (``policy``:
    social_force or orca), from ``seed``: ON_ROUTE_SHARE of them walk back and forth along the
    robot's planned route (between two of its points: towards the robot and with it, pushing
    it now and then), the rest between random free points; every start and goal at least
    WALKER_CLEARANCE from obstacles, starts WALKER_SPACING apart and ROBOT_KEEP_OUT from the
    robot and its goal (when the route is full, ROUTE_FULL_AFTER failed draws in a row, the rest
    of its share walk between free points). Raises ValueError when they do not fit (bounded
    draws)."""
    from pymunk_bot.config import parse_scenario
    from pymunk_bot.planning.astar import astar
    from pymunk_bot.planning.grid import ClearanceGrid
    from pymunk_bot.planning.map import MapInfo

    rng = np.random.default_rng([seed, walkers, 36])
    config = parse_scenario(data, "localization people")
    robot = config.robots[0]
    grid = ClearanceGrid.from_map(MapInfo.from_scenario(config), GRID_RESOLUTION, cap=2.0)
    rows, cols = np.nonzero(grid.clearance >= WALKER_CLEARANCE)
    free = np.column_stack([grid.xs[cols], grid.ys[rows]])
    plan = astar(grid, robot.pose[:2], robot.goal.position, hard=robot.radius + 0.05,
                 soft=robot.radius + 0.3)
    route = np.asarray(plan.path if plan.path is not None else [robot.pose[:2]], dtype=float)
    if route.shape[0] > 1:  # the route's points where a walker fits
        r, c = np.asarray([grid.cell_of(x, y) for x, y in route]).T
        route = route[grid.clearance[r, c] >= WALKER_CLEARANCE]
    home = np.asarray(robot.pose[:2], dtype=float)
    goal = np.asarray(robot.goal.position, dtype=float)
    people: list[dict] = []
    starts: list[np.ndarray] = []
    route_failures = 0  # route draws failed in a row
    for _ in range(MAX_WALKER_DRAWS):
        if len(people) == walkers:
            break
        on_route = (len(people) < ON_ROUTE_SHARE * walkers and route.shape[0] >= 2
                    and route_failures < ROUTE_FULL_AFTER)
        pool = route if on_route else free
        a, b = pool[rng.integers(pool.shape[0], size=2)]
        if (np.hypot(*(a - home)) < ROBOT_KEEP_OUT or np.hypot(*(a - goal)) < ROBOT_KEEP_OUT
                or np.hypot(*(a - b)) < 2.0
                or any(np.hypot(*(a - s)) < WALKER_SPACING for s in starts)):
            route_failures += on_route
            continue
        route_failures = 0
        starts.append(a)
        people.append({"type": "pedestrian", "center": a.round(3).tolist(),
                       "goals": [b.round(3).tolist(), a.round(3).tolist()], "mode": "loop",
                       "policy": policy,
                       "speed": 1.0, "speed_std": 0.2, "radius": WALKER_RADIUS})
    if len(people) < walkers:
        raise ValueError(f"only {len(people)} of {walkers} walkers fit in {data.get('name')}")
    out = dict(data)
    out["obstacles"] = list(data.get("obstacles", [])) + people
    return out
