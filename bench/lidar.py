"""LiDAR ray casting: RayCaster against one segment_query_first per ray, in the same run.

    python -m bench.lidar

Each world gets 360-beam full-circle scans (10 m range, random headings) from free
poses: robots' own positions with their own shape filter when there are robots. The scans of
one round are one tick's: they share a view of the scene (``begin_frame``, timed), as every
LiDAR of a simulation tick does; the reference needs none. The two
methods are timed alternately, block by block, and each figure is the median over the
repeats of the CPU time of this thread (time.thread_time, garbage collection paused), so
time spent waiting for other processes on a shared machine is not counted. The last
column is the largest disagreement between the two over every ray cast.
"""
from __future__ import annotations

import gc
import math
import statistics
import time
from collections.abc import Callable

import numpy as np
import pymunk

from pymunk_bot.sensors.raycast import RayCaster, reference_cast

BEAMS = 360
MAX_RANGE = 10.0  # [m]
ROBOT_RADIUS = 0.2  # [m]
POSES = 50
TARGET = 5.0  # RayCaster / segment_query_first loop, at least, in every world
REPEATS = 7

# (description, width = height [m], boxes, robots)
WORLDS = [
    ("20x20 m, 10 boxes", 20.0, 10, 0),
    ("20x20 m, 100 boxes", 20.0, 100, 0),
    ("20x20 m, 1000 boxes", 20.0, 1000, 0),
    ("63x63 m, 1000 boxes", 63.0, 1000, 0),
    ("20x20 m, 1000 boxes + 50 robots", 20.0, 1000, 50),
]


def _box(body: pymunk.Body, x: float, y: float, w: float, h: float, angle: float) -> pymunk.Poly:
    c, s = math.cos(angle), math.sin(angle)
    corners = [(-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2)]
    return pymunk.Poly(body, corners, pymunk.Transform(a=c, b=s, c=-s, d=c, tx=x, ty=y))


def build_world(size: float, n_boxes: int, n_robots: int,
                rng: np.random.Generator) -> tuple[pymunk.Space, list[pymunk.Body]]:
    """Walls just outside [0, size]^2, random boxes (0.2-1 m sides, any heading), and robot
    discs on free spots, each with its own shape-filter group."""
    space = pymunk.Space()
    sb, t = space.static_body, 0.5
    space.add(_box(sb, size / 2, -t / 2, size + 2 * t, t, 0.0),
              _box(sb, size / 2, size + t / 2, size + 2 * t, t, 0.0),
              _box(sb, -t / 2, size / 2, t, size, 0.0),
              _box(sb, size + t / 2, size / 2, t, size, 0.0))
    for _ in range(n_boxes):
        x, y = rng.uniform(0.0, size, 2)
        w, h = rng.uniform(0.2, 1.0, 2)
        space.add(_box(sb, x, y, w, h, rng.uniform(0.0, math.pi)))
    robots = []
    for group in range(1, n_robots + 1):
        body = pymunk.Body(1.0, pymunk.moment_for_circle(1.0, 0.0, ROBOT_RADIUS))
        body.position = _free_spot(space, size, rng)
        disc = pymunk.Circle(body, ROBOT_RADIUS)
        disc.filter = pymunk.ShapeFilter(group=group)
        space.add(body, disc)
        robots.append(body)
    return space, robots


def _free_spot(space: pymunk.Space, size: float, rng: np.random.Generator) -> tuple[float, float]:
    """A point at least a robot radius away from every shape."""
    while True:
        x, y = rng.uniform(ROBOT_RADIUS, size - ROBOT_RADIUS, 2)
        if space.point_query_nearest((float(x), float(y)), ROBOT_RADIUS, pymunk.ShapeFilter()) is None:
            return float(x), float(y)


def _poses(space: pymunk.Space, robots: list[pymunk.Body], size: float,
           rng: np.random.Generator) -> list[tuple[tuple[float, float], float, pymunk.ShapeFilter]]:
    """(origin, heading, filter) per scan: robots scan with their own group, else free spots."""
    if robots:
        return [((b.position.x, b.position.y), float(rng.uniform(-math.pi, math.pi)),
                 pymunk.ShapeFilter(group=i + 1))
                for i, b in enumerate(robots[:POSES])]
    return [(_free_spot(space, size, rng), float(rng.uniform(-math.pi, math.pi)), pymunk.ShapeFilter())
            for _ in range(POSES)]


def _timed(scan: Callable[[tuple[float, float], np.ndarray, pymunk.ShapeFilter], np.ndarray],
           poses: list, beams: np.ndarray, frame: Callable[[], None] | None = None
           ) -> tuple[float, list[np.ndarray]]:
    """Microseconds per ray over all poses (one tick: ``frame`` first, if given), and the
    scans."""
    start = time.thread_time()
    if frame is not None:
        frame()
    scans = [scan(origin, heading + beams, shape_filter) for origin, heading, shape_filter in poses]
    return (time.thread_time() - start) / (len(poses) * len(beams)) * 1e6, scans


def measure(seed: int = 0) -> list[dict]:
    """One row per world: reference and RayCaster cost per ray, speedup, largest difference."""
    beams = (np.arange(BEAMS) - BEAMS // 2) * (2.0 * math.pi / BEAMS)
    rows = []
    for description, size, n_boxes, n_robots in WORLDS:
        rng = np.random.default_rng(seed)
        space, robots = build_world(size, n_boxes, n_robots, rng)
        poses = _poses(space, robots, size, rng)
        caster = RayCaster(space)

        def fast(origin, angles, shape_filter):
            return caster.cast(origin, angles, MAX_RANGE, shape_filter)

        def slow(origin, angles, shape_filter):
            return reference_cast(space, origin, angles, MAX_RANGE, shape_filter)

        fast(poses[0][0], beams, poses[0][2])  # builds the static cache: not timed
        fast_us, slow_us, worst = [], [], 0.0
        gc_was_enabled = gc.isenabled()
        gc.disable()
        try:
            for _ in range(REPEATS):  # alternate, so load changes hit both methods alike
                t_fast, got = _timed(fast, poses, beams, caster.begin_frame)
                t_slow, want = _timed(slow, poses, beams)
                fast_us.append(t_fast)
                slow_us.append(t_slow)
                worst = max(worst, max(float(np.max(np.abs(g - w))) for g, w in zip(got, want)))
        finally:
            if gc_was_enabled:
                gc.enable()
        ref, new = statistics.median(slow_us), statistics.median(fast_us)
        rows.append({"world": description, "n_obstacles": n_boxes, "n_robots": n_robots,
                     "reference_us_per_ray": ref, "fast_us_per_ray": new,
                     "speedup": ref / new, "max_abs_diff_m": worst})
    return rows


def main() -> list[dict]:
    """Print the table; returns its rows."""
    rows = measure()
    header = f"{'world':34s} {'obstacles':>9s} {'robots':>6s} {'reference':>10s} {'RayCaster':>10s} " \
             f"{'speedup':>8s} {'max |diff|':>11s}"
    print(header)
    print(f"{'':34s} {'':>9s} {'':>6s} {'[us/ray]':>10s} {'[us/ray]':>10s} {'':>8s} {'[m]':>11s}")
    for r in rows:
        print(f"{r['world']:34s} {r['n_obstacles']:9d} {r['n_robots']:6d} {r['reference_us_per_ray']:10.2f} "
              f"{r['fast_us_per_ray']:10.3f} {r['speedup']:7.1f}x {r['max_abs_diff_m']:11.1e}")
    return rows


if __name__ == "__main__":
    main()
