"""waypoints: follows the points in order, rounds corners inside, never overshoots them."""
import math

import numpy as np
import pytest

from pymunk_bot import Simulation
from pymunk_bot.geometry.plane import point_in_polygon

from helpers import scenario


def random_polygon(rng):
    """A star-shaped polygon of 4-6 corners around the middle of a 10 x 8 room."""
    n = int(rng.integers(4, 7))
    angles = np.sort(rng.uniform(0, 2 * np.pi, n))
    radii = rng.uniform(2.0, 3.5, n)
    return [(5.0 + r * math.cos(a), 4.0 + r * math.sin(a)) for r, a in zip(radii, angles)]


def trace(config, duration):
    sim = Simulation(config)
    poses = []
    for _ in range(round(duration / sim.dt)):
        sim.step()
        poses.append(sim.robots["r"].pose.copy())
    return sim, np.array(poses)


def outside_distance(point, polygon):
    """How far a point lies outside a polygon (0 inside)."""
    if point_in_polygon(point, polygon):
        return 0.0
    n = len(polygon)
    return min(_segment_distance(point, polygon[i], polygon[(i + 1) % n]) for i in range(n))


def _segment_distance(p, a, b):
    p, a, b = map(np.asarray, (p, a, b))
    t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0, 1)
    return float(np.hypot(*(p - a - t * (b - a))))


@pytest.mark.parametrize("seed", range(4))
def test_patrol_loops_stay_inside_the_waypoint_polygon(seed):
    polygon = np.array(random_polygon(np.random.default_rng(seed)))
    start = polygon[0]
    config = scenario((10.0, 8.0), [], [{
        "name": "r", "pose": [float(start[0]), float(start[1]), 0.0],
        "controller": {"type": "waypoints", "points": polygon.tolist(), "loop": True}}])
    sim, poses = trace(config, 40.0)
    # Corners are rounded inside the route: the robot never leaves the polygon by more than
    # a couple of centimetres (it starts on a corner facing an arbitrary way).
    overshoot = max(outside_distance(p[:2], polygon) for p in poses[120:])
    assert overshoot < 0.03
    # And it really goes round: it passes close to every corner, lap after lap.
    for corner in polygon:
        assert np.hypot(*(poses[:, :2] - corner).T).min() < 0.6
    assert sim.robots["r"].controller.follower.tracker.laps >= 1


def test_stops_at_the_last_point_and_reports_arrival():
    points = [[3.0, 1.0], [3.0, 4.0], [6.0, 4.0], [8.0, 2.0]]
    config = scenario((10.0, 6.0), [], [{
        "name": "r", "pose": [1.0, 1.0, 0.0],
        "controller": {"type": "waypoints", "points": points}}])
    sim, poses = trace(config, 30.0)
    robot = sim.robots["r"]
    assert robot.controller.status == "arrived"
    assert math.dist(robot.pose[:2], (8.0, 2.0)) < 0.12
    assert np.hypot(*robot.velocity) < 1e-3  # standing still, not circling the point
    for corner in points[:-1]:  # passed every waypoint on the way
        assert np.hypot(*(poses[:, :2] - corner).T).min() < 0.35
