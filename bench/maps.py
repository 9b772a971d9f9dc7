"""Map worlds: build time of map geometry, and LiDAR on a map vs the same world as boxes.

    python -m bench.maps

Build: a TurtleBot3-size map (384 x 384 cells) and a 4000 x 4000 one (200 m square at 5 cm:
rooms 5 m apart with doors, 400 pillars, an unknown corner), from an ``OccupancyGrid`` to
``MapGeometry`` and then into a pymunk space; median wall time of repeats.
LiDAR: the same arena of boxes built twice, as pymunk boxes and as a map (rasterised at 5 cm,
written and read back as a ROS map); 360-beam scans from the same free poses with
``RayCaster``, median CPU time per ray (time.thread_time).
"""
from __future__ import annotations

import gc
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import pymunk

from pymunk_bot.maps.outlines import add_to_space, free_disc, geometry_from_grid
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.sensors.raycast import RayCaster

BEAMS = 360
MAX_RANGE = 10.0  # [m]
RESOLUTION = 0.05  # [m]


def turtlebot_grid(size: int = 384) -> OccupancyGrid:
    """Unknown outside a closed wall ring, nine round pillars inside (like TurtleBot3 world)."""
    data = np.full((size, size), -1, np.int8)
    a, b = size // 4, 3 * size // 4
    data[a:b, a:b] = 100
    data[a + 3:b - 3, a + 3:b - 3] = 0
    yy, xx = np.mgrid[:size, :size]
    for i in range(1, 4):
        for j in range(1, 4):
            data[(yy - a - i * (b - a) // 4) ** 2 + (xx - a - j * (b - a) // 4) ** 2 < 16] = 100
    return OccupancyGrid(data, RESOLUTION, (-size * RESOLUTION / 2, -size * RESOLUTION / 2))


def building_grid(size: int = 4000, seed: int = 0) -> OccupancyGrid:
    """A big floor: 2-cell walls every 100 cells with 1 m doors, 400 square pillars."""
    rng = np.random.default_rng(seed)
    data = np.zeros((size, size), np.int8)
    for k in range(2):
        data[:, k::100] = 100
        data[k::100, :] = 100
    for k in range(0, size, 100):
        for j in range(0, size, 100):
            data[k:k + 2, j + 40:j + 60] = 0
            data[j + 40:j + 60, k:k + 2] = 0
    for _ in range(400):
        cy, cx = rng.integers(0, size, 2)
        r = int(rng.integers(3, 10))
        data[max(0, cy - r):cy + r, max(0, cx - r):cx + r] = 100
    data[:200, :200] = -1
    return OccupancyGrid(data, RESOLUTION)


def time_build(grid: OccupancyGrid, repeats: int) -> tuple[float, int]:
    """Median seconds from grid to shapes in a space, and the number of shapes."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        shapes = add_to_space(pymunk.Space(), geometry_from_grid(grid))
        times.append(time.perf_counter() - start)
    return statistics.median(times), len(shapes)


def _box_world(rng: np.random.Generator, size: float, n_boxes: int) -> dict:
    obstacles = [{"type": "box", "center": [float(v) for v in rng.uniform(1.0, size - 1.0, 2)],
                  "size": [float(v) for v in rng.uniform(0.3, 1.0, 2)],
                  "angle": float(rng.uniform(0.0, math.pi))} for _ in range(n_boxes)]
    return {"name": "bench_boxes", "world": {"size": [size, size]}, "obstacles": obstacles,
            "robots": [{"name": "r1", "pose": [0.5, 0.5, 0.0]}]}


def lidar_ratio(n_boxes: int = 100, size: float = 20.0, poses: int = 30, repeats: int = 5,
                seed: int = 0) -> tuple[float, float, int, int]:
    """(us per ray on the boxes world, us per ray on its map, shapes in each)."""
    from pymunk_bot.cli import main as cli_main
    from pymunk_bot.config import parse_scenario
    from pymunk_bot.maps.files import load_world_map
    from pymunk_bot.engine.simulation import Simulation

    rng = np.random.default_rng(seed)
    data = _box_world(rng, size, n_boxes)
    sim = Simulation(parse_scenario(data, "bench"))
    boxes = pymunk.Space()  # the arena walls and boxes; robots (dynamic bodies) left out
    for shape in sim.world.space.shapes:
        if _body_of(shape).body_type == pymunk.Body.STATIC:
            boxes.add(_static_copy(shape, boxes))
    with tempfile.TemporaryDirectory() as tmp:
        import yaml

        scenario = Path(tmp) / "boxes.yaml"
        scenario.write_text(yaml.safe_dump(data))
        with _quiet():
            cli_main(["map", str(scenario), "-o", str(Path(tmp) / "boxes_map.yaml")])
        geometry = load_world_map(Path(tmp) / "boxes_map.yaml")
    mapped = pymunk.Space()
    add_to_space(mapped, geometry)
    origins: list[tuple[float, float]] = []
    while len(origins) < poses:
        x, y = rng.uniform(0.5, size - 0.5, 2)
        if free_disc(geometry, x, y, 0.3):
            origins.append((float(x), float(y)))
    angles = np.linspace(-math.pi, math.pi, BEAMS, endpoint=False)
    casters = {"boxes": RayCaster(boxes), "map": RayCaster(mapped)}
    samples: dict[str, list[float]] = {"boxes": [], "map": []}
    gc.disable()
    try:
        for _ in range(repeats):
            for name, caster in casters.items():
                start = time.thread_time()
                for origin in origins:
                    caster.cast(origin, angles, MAX_RANGE)
                samples[name].append((time.thread_time() - start) / (poses * BEAMS) * 1e6)
    finally:
        gc.enable()
    return (statistics.median(samples["boxes"]), statistics.median(samples["map"]),
            len(boxes.shapes), len(mapped.shapes))


def _static_copy(shape: pymunk.Shape, space: pymunk.Space) -> pymunk.Shape:
    """The same static shape on ``space``'s static body, in world coordinates."""
    body = space.static_body
    own = _body_of(shape)
    if isinstance(shape, pymunk.Poly):
        return pymunk.Poly(body, [own.local_to_world(v) for v in shape.get_vertices()],
                           radius=shape.radius)
    if isinstance(shape, pymunk.Circle):
        return pymunk.Circle(body, shape.radius, own.local_to_world(shape.offset))
    return pymunk.Segment(body, own.local_to_world(shape.a), own.local_to_world(shape.b),
                          shape.radius)


def _body_of(shape: pymunk.Shape) -> pymunk.Body:
    """The body a shape in a space is attached to (only a detached shape has none)."""
    if shape.body is None:
        raise ValueError(f"{shape!r} is not attached to a body")
    return shape.body


class _quiet:
    """Silence stdout (the map command's one-line report) inside the bench."""

    def __enter__(self):
        import contextlib
        import io

        self._redirect = contextlib.redirect_stdout(io.StringIO())
        self._redirect.__enter__()

    def __exit__(self, *exc):
        self._redirect.__exit__(*exc)


def main(quick: bool = False) -> dict:
    """Print and return the map figures."""
    repeats = 2 if quick else 5
    out = {}
    for name, grid in (("384x384 (TurtleBot3 size)", turtlebot_grid()),
                       ("4000x4000 (200 m building)", building_grid())):
        seconds, shapes = time_build(grid, 1 if grid.rows > 1000 else repeats)
        out[name] = seconds
        print(f"  build {name:<28} {seconds * 1000:8.1f} ms  ({shapes} shapes)")
    for n_boxes in (10, 100):
        boxes_us, map_us, n_box_shapes, n_map_shapes = lidar_ratio(n_boxes, repeats=repeats)
        ratio = map_us / boxes_us
        out[f"lidar ratio {n_boxes} boxes"] = ratio
        print(f"  LiDAR, 20x20 m, {n_boxes:>3} boxes: {boxes_us:5.2f} us/ray as boxes "
              f"({n_box_shapes} shapes), {map_us:5.2f} us/ray as a map ({n_map_shapes} shapes): "
              f"{ratio:.2f}x")
    return out


if __name__ == "__main__":
    main()
