"""Offscreen frames show what the simulation holds: robots where their poses say, rays, ghosts."""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.viewer import palette as pal
from viewer_helpers import Harness, build, near, wheels

ROBOT = pal.robot_colour(0)


def _colours_around(surface, centre, radius):
    x, y = int(round(centre[0])), int(round(centre[1]))
    return [tuple(surface.get_at((i, j)))[:3]
            for i in range(x - radius, x + radius + 1) for j in range(y - radius, y + radius + 1)]


def test_robot_is_drawn_at_its_pose_and_follows_it():
    sim = build([{"name": "r", "pose": [1.0, 1.5, math.pi / 2], "radius": 0.25,
                  "controller": wheels(0.5, 0.5)}])
    h = Harness(sim)
    h.viewer.layers.grid = False
    h.draw()
    x, y, _ = sim.robots["r"].pose
    # Inside the disc beside the heading line: the robot's colour.
    assert near(h.pixel((x - 0.15, y)), ROBOT, 2)
    assert near(h.pixel((x + 0.15, y)), ROBOT, 2)
    # The heading line points up (theta = pi/2): white above the centre, not below.
    assert near(h.pixel((x, y + 0.15)), pal.HEADING, 30)
    assert near(h.pixel((x, y - 0.15)), ROBOT, 2)
    for _ in range(60):  # 1 s at 0.5 m/s, minus the acceleration ramp
        h.source.step()
    h.draw()
    nx, ny, _ = sim.robots["r"].pose
    assert ny - y > 0.4
    assert near(h.pixel((nx - 0.15, ny)), ROBOT, 2)
    assert not near(h.pixel((x - 0.15, y)), ROBOT, 30)  # the old place is empty now


def test_obstacles_fixed_movable_and_concave():
    sim = build([{"name": "r", "pose": [0.4, 0.4, 0.0]}],
                obstacles=[{"type": "box", "center": [1.0, 2.2], "size": [0.6, 0.6]},
                           {"type": "box", "center": [2.0, 2.2], "size": [0.6, 0.6],
                            "movable": True},
                           {"type": "polygon",
                            "points": [[2.6, 0.5], [3.6, 0.5], [3.6, 1.5], [3.1, 1.0],
                                       [2.6, 1.5]]}])
    h = Harness(sim)
    h.viewer.layers.grid = False
    h.draw()
    assert near(h.pixel((1.15, 2.2)), pal.STATIC, 2)
    assert near(h.pixel((2.15, 2.2)), pal.MOVABLE, 2)  # beside the crate's cross
    assert near(h.pixel((2.1, 2.3)), pal.MOVABLE_EDGE, 60)  # on the cross
    assert near(h.pixel((3.1, 0.8)), pal.STATIC, 2)  # inside the concave polygon
    assert near(h.pixel((3.1, 1.35)), pal.FLOOR, 2)  # in its notch: floor
    assert near(h.pixel((1.0, 1.0)), pal.FLOOR, 2)


def _ray_pixels(h, scan_robot, fraction=0.5):
    origin, ends, hit = scan_robot.scan_origin, scan_robot.scan_points, scan_robot.scan_hit
    mids = origin + fraction * (ends - origin)
    return [h.viewer.camera.to_screen(*m) for m in mids[hit]]


def test_lidar_rays_and_hits_are_drawn_only_when_enabled():
    sim = build([{"name": "r", "pose": [2.0, 1.5, 0.3], "lidar": {"beams": 12, "max_range": 5.0}}],
                obstacles=[{"type": "box", "center": [3.4, 1.5], "size": [0.3, 2.5]}])
    h = Harness(sim, size=(600, 450))
    h.viewer.layers.grid = False
    h.viewer.layers.trails = False
    h.draw()
    robot = h.viewer.scene().robots[0]
    assert robot.scan_hit.sum() == 12  # a closed arena: every beam returns
    ray = pal.mix(ROBOT, pal.FLOOR, 0.78)
    # Halfway along a beam that starts outside the robot's disc.
    mids = [p for p in _ray_pixels(h, robot, 0.7)]
    assert all(any(near(c, ray, 25) for c in _colours_around(h.surface, p, 1)) for p in mids)
    # Hit points sit where the beams end.
    ends = [h.viewer.camera.to_screen(*e) for e in robot.scan_points]
    dot = pal.mix(ROBOT, (0, 0, 0), 0.25)
    assert all(any(near(c, dot, 30) for c in _colours_around(h.surface, p, 1)) for p in ends)
    h.key(__import__("pygame").K_l, "l")
    h.draw()
    assert not h.viewer.layers.rays
    for p in mids:
        assert all(near(c, pal.FLOOR, 3) for c in _colours_around(h.surface, p, 1))


def test_odometry_ghost_is_drawn_where_odometry_believes_the_robot_is():
    # A 10 % wheel-radius error on one side makes odometry turn while the robot drives straight.
    sim = build([{"name": "r", "pose": [0.5, 1.5, 0.0], "odometry": {"right_scale_error": 0.1},
                  "controller": wheels(0.6, 0.6)}], size=(6.0, 3.0))
    h = Harness(sim, size=(900, 450))
    h.viewer.layers.grid = False
    h.viewer.layers.trails = False
    for _ in range(240):
        h.source.step()
    h.draw()
    robot = sim.robots["r"]
    ox, oy, _ = robot.odometry.pose
    assert math.hypot(ox - robot.pose[0], oy - robot.pose[1]) > 0.5
    ghost = pal.mix(ROBOT, pal.FLOOR, 0.35)
    cam = h.viewer.camera

    def ring_hits():
        hits = 0
        for a in np.linspace(0, 2 * math.pi, 48, endpoint=False):
            p = cam.to_screen(ox + robot.radius * math.cos(a), oy + robot.radius * math.sin(a))
            hits += any(near(c, ghost, 40) for c in _colours_around(h.surface, p, 1))
        return hits

    assert ring_hits() >= 12  # a dashed ring: about half of it is drawn
    h.viewer.layers.ghost = False
    h.draw()
    assert ring_hits() == 0


def test_goal_marker_and_deep_zoom():
    sim = build([{"name": "r", "pose": [1.0, 1.0, 0.0], "goal": {"position": [3.0, 2.0]}}])
    h = Harness(sim)
    h.viewer.layers.grid = False
    h.draw()
    assert near(h.pixel((3.0, 2.0)), ROBOT, 40)  # the crosshair's centre
    # Zoomed in as far as it goes on the robot, the frame still draws and shows the robot.
    h.viewer.camera.zoom(1e6, h.viewer.camera.to_screen(1.0, 1.0))
    h.viewer.camera.centre = (1.0, 1.0)
    h.draw()
    assert near(h.pixel((1.0 - 0.01, 1.0 - 0.02)), ROBOT, 2)
    assert near(h.pixel((1.0 + 0.01, 1.0)), pal.HEADING, 2)  # on the heading line


def test_drawing_never_changes_the_simulation():
    def make():
        return build([{"name": "r", "pose": [1.0, 1.5, 0.0], "lidar": {"beams": 30,
                       "noise_std": 0.02}, "odometry": {"wheel_noise_std": 0.01},
                       "controller": {"type": "go_to_goal"}, "goal": {"position": [3.5, 2.5]}}])

    drawn, plain = make(), make()
    h = Harness(drawn)
    for _ in range(90):
        h.source.step()
        h.draw()
        h.viewer.scene()
        plain.step()
    for a, b in zip(drawn.robots.values(), plain.robots.values()):
        assert np.array_equal(a.pose, b.pose)
        assert np.array_equal(a.odometry.pose, b.odometry.pose)
        assert np.array_equal(a.lidar.ranges, b.lidar.ranges)
    assert drawn.steps == plain.steps
