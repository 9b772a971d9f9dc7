"""What a view draws: plain arrays in world units, taken from a live simulation or a run log.

Nothing here imports pygame, so the run log (which stores the same geometry) and the plots
can use it. A :class:`Scene` is a snapshot: drawing it cannot change the simulation.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pymunk


@dataclass(frozen=True)
class ShapeGeometry:
    """One collision shape in its body's frame.

    ``kind`` is "poly" (``points``: the convex outline), "circle" (``points``: the centre, one
    row; ``radius``) or "segment" (``points``: the two ends; ``radius``: half the thickness).
    """

    kind: str
    points: np.ndarray  # (N, 2) [m], body frame
    radius: float = 0.0  # [m]
    movable: bool = False
    wall: bool = False  # one of the arena walls
    group: int = -1  # index of the obstacle it belongs to (-1: arena wall)

    def placed(self, pose: tuple[float, float, float] | np.ndarray) -> "ShapeView":
        """This shape with its body at ``pose`` (x, y, angle) in the world."""
        x, y, angle = (float(v) for v in pose)
        c, s = math.cos(angle), math.sin(angle)
        local = self.points
        world = np.empty_like(local)
        world[:, 0] = x + c * local[:, 0] - s * local[:, 1]
        world[:, 1] = y + s * local[:, 0] + c * local[:, 1]
        return ShapeView(self.kind, world, self.radius, self.movable, self.wall, (x, y, angle),
                         self.group)


@dataclass(frozen=True)
class ShapeView:
    """A shape placed in the world (same fields as :class:`ShapeGeometry`, world frame)."""

    kind: str
    points: np.ndarray  # (N, 2) [m], world frame
    radius: float
    movable: bool
    wall: bool
    pose: tuple[float, float, float]  # the body's pose [m, m, rad]
    group: int = -1


@dataclass
class RobotView:
    """One robot as a view shows it."""

    name: str
    index: int  # fixed per scenario: picks the colour
    pose: np.ndarray  # ground truth [x, y, theta]
    radius: float  # [m]
    odometry: np.ndarray  # the odometry estimate [x, y, theta]
    velocity: tuple[float, float] = (0.0, 0.0)  # true (v [m/s], omega [rad/s])
    goal: tuple[float, float] | None = None  # the task goal: the run is judged on reaching it
    goal_tolerance: float = 0.2  # [m]
    goal_reached: bool = False  # the task goal
    nav_goal: tuple[float, float] | None = None  # where the controller drives instead (a click,
    # or its own block's goal), when it differs from the task goal, which still judges the run
    path: np.ndarray | None = None  # (N, 2) the controller's planned path
    trail: np.ndarray = field(default_factory=lambda: np.empty((0, 2)))  # (N, 2) true positions
    scan_origin: np.ndarray | None = None  # sensor position when the latest scan was taken
    scan_points: np.ndarray | None = None  # (N, 2) world end points of the beams
    scan_hit: np.ndarray | None = None  # (N,) bool: the beam returned (did not read max_range)
    collisions: int = 0
    status: str = ""  # the controller's status
    teleop: bool = False  # wheel speeds set by hand (or by the log's override flag)
    estimate: np.ndarray | None = None  # the localizer's pose [x, y, theta], if it has one
    covariance: np.ndarray | None = None  # (3, 3) the estimate's covariance
    particles: np.ndarray | None = None  # (N, 3) the particle cloud (MCL)
    built_map: Any = None  # OccupancyGrid the robot has built so far (mapping / slam)
    footprint: np.ndarray | None = None  # (N, 2) outline in the robot frame; None: the disc
    steering: float | None = None  # a car's steering angle [rad]
    wheelbase: float = 0.0  # [m], with ``steering``


@dataclass
class Scene:
    """Everything drawn in one frame."""

    width: float  # arena interior [m]
    height: float  # [m]
    time: float  # simulated [s]
    shapes: list[ShapeView]
    robots: list[RobotView]
    title: str = ""
    origin: tuple[float, float] = (0.0, 0.0)  # [m] the arena's lower-left corner (a map's origin)


# ---------------------------------------------------------------------------- geometry


def shape_geometry(shape: pymunk.Shape, movable: bool, wall: bool = False,
                   group: int = -1) -> ShapeGeometry:
    """The body-frame geometry of a pymunk shape."""
    if isinstance(shape, pymunk.Circle):
        off = shape.offset
        return ShapeGeometry("circle", np.array([[off.x, off.y]]), shape.radius, movable, wall,
                             group)
    if isinstance(shape, pymunk.Segment):
        a, b = shape.a, shape.b
        return ShapeGeometry("segment", np.array([[a.x, a.y], [b.x, b.y]]), shape.radius,
                             movable, wall, group)
    if isinstance(shape, pymunk.Poly):
        points = np.array([(v.x, v.y) for v in shape.get_vertices()])
        return ShapeGeometry("poly", points, shape.radius, movable, wall, group)
    raise TypeError(f"cannot draw a {type(shape).__name__}")


def body_pose(body: pymunk.Body) -> tuple[float, float, float]:
    """(x, y, angle) of a body: its local frame in the world."""
    p = body.position
    return (p.x, p.y, body.angle)


def world_geometry(world) -> tuple[list[ShapeGeometry], list[tuple[int, list[ShapeGeometry]]]]:
    """(fixed shapes, [(obstacle index, shapes) for each movable obstacle]) of a World.

    Fixed shapes live on the static body, whose frame is the world frame.
    """
    fixed = [shape_geometry(s, False, wall=True) for s in world.arena_shapes]
    movable = []
    for i, obstacle in enumerate(world.obstacles):
        if obstacle.movable:
            movable.append((i, [shape_geometry(s, True, group=i) for s in obstacle.shapes]))
        else:
            fixed.extend(shape_geometry(s, False, group=i) for s in obstacle.shapes)
    return fixed, movable


def scan_end_points(pose: np.ndarray, scan) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(sensor origin, (N, 2) beam end points, (N,) returned) of a LaserScan taken at ``pose``."""
    x, y, theta = (float(v) for v in pose)
    ox, oy, otheta = (float(v) for v in getattr(scan, "offset", (0.0, 0.0, 0.0)))
    c, s = math.cos(theta), math.sin(theta)
    origin = np.array([x + c * ox - s * oy, y + s * ox + c * oy])
    ranges = np.asarray(scan.ranges, dtype=float)
    angles = np.asarray(scan.angles, dtype=float) + theta + otheta
    ends = origin + ranges[:, None] * np.column_stack((np.cos(angles), np.sin(angles)))
    # A beam that read max_range (or beyond, with noise) returned nothing.
    returned = ranges < float(scan.max_range) - 1e-9
    return origin, ends, returned
