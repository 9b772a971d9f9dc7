"""Scene entities for Foxglove's 3D panel: the arena, obstacles, robots and goals.

Entity ids are stable, so an update replaces what was drawn: ``arena``, ``obstacle/<i>``
(``i`` = index in the scenario's obstacle list), ``robot/<name>`` (frame-locked to the robot's
base_link, so it moves with the transforms) and ``goal/<name>``. Shapes are extruded to a
small height so the 3D view reads well; everything stands on the floor (z = 0).
"""
from __future__ import annotations

import math

import numpy as np
from foxglove.messages import (Color, CubePrimitive, CylinderPrimitive, LinePrimitive,
                               LinePrimitiveLineType, Point3, Pose, Quaternion, SceneEntity,
                               SceneEntityDeletion, SceneEntityDeletionType, TextPrimitive,
                               Timestamp, TriangleListPrimitive, Vector3)

from pymunk_bot.viewer import palette
from pymunk_bot.viewer.scene import ShapeGeometry
from pymunk_bot.foxglove.frames import NS_PER_S, WORLD_FRAME, base_frame, nanoseconds, yaw_quaternion

WALL_HEIGHT = 0.4  # [m]
OBSTACLE_HEIGHT = 0.3  # [m]
ROBOT_HEIGHT = 0.15  # [m]
GOAL_HEIGHT = 0.01  # [m], a disc on the floor


def timestamp(t: float) -> Timestamp:
    """A Foxglove timestamp for simulated time ``t`` [s]."""
    sec, nsec = divmod(nanoseconds(t), NS_PER_S)
    return Timestamp(sec=sec, nsec=nsec)


def pose_msg(x: float, y: float, theta: float, z: float = 0.0) -> Pose:
    """A planar pose as a Foxglove Pose."""
    qx, qy, qz, qw = yaw_quaternion(theta)
    return Pose(position=Vector3(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw))


def _color(rgb: tuple[int, int, int], alpha: float = 1.0) -> Color:
    return Color(r=rgb[0] / 255, g=rgb[1] / 255, b=rgb[2] / 255, a=alpha)


def shape_primitives(g: ShapeGeometry, pose: tuple[float, float, float], height: float,
                     rgb: tuple[int, int, int]) -> dict[str, list]:
    """Primitives of one shape whose body sits at ``pose``, by SceneEntity field name."""
    x, y, theta = pose
    color = _color(rgb)
    if g.kind == "circle":
        cx, cy = g.points[0]
        c, s = math.cos(theta), math.sin(theta)
        return {"cylinders": [CylinderPrimitive(
            pose=pose_msg(x + c * cx - s * cy, y + s * cx + c * cy, 0.0, height / 2),
            size=Vector3(x=2 * g.radius, y=2 * g.radius, z=height),
            bottom_scale=1.0, top_scale=1.0, color=color)]}
    if g.kind == "segment":
        (ax, ay), (bx, by) = g.points
        length = math.hypot(bx - ax, by - ay) + 2 * g.radius  # rounded ends, drawn square
        angle = math.atan2(by - ay, bx - ax)
        mx, my = (ax + bx) / 2, (ay + by) / 2
        c, s = math.cos(theta), math.sin(theta)
        return {"cubes": [CubePrimitive(
            pose=pose_msg(x + c * mx - s * my, y + s * mx + c * my, theta + angle, height / 2),
            size=Vector3(x=length, y=max(2 * g.radius, 0.01), z=height), color=color)]}
    return {"triangles": [TriangleListPrimitive(pose=pose_msg(x, y, theta),
                                                points=_prism(g.points, height), color=color)],
            "lines": [LinePrimitive(type=LinePrimitiveLineType.LineLoop,
                                    pose=pose_msg(x, y, theta, height + 1e-3), thickness=0.01,
                                    points=[Point3(x=float(px), y=float(py), z=0.0)
                                            for px, py in g.points],
                                    color=_color(palette.OUTLINE))]}


def _prism(points: np.ndarray, height: float) -> list[Point3]:
    """Triangles of a convex polygon extruded from the floor to ``height``."""
    pts = [(float(px), float(py)) for px, py in points]
    out: list[Point3] = []
    for i in range(1, len(pts) - 1):  # top, as a fan
        for px, py in (pts[0], pts[i], pts[i + 1]):
            out.append(Point3(x=px, y=py, z=height))
    for (ax, ay), (bx, by) in zip(pts, pts[1:] + pts[:1]):  # sides
        for px, py, pz in ((ax, ay, 0.0), (bx, by, 0.0), (bx, by, height),
                           (ax, ay, 0.0), (bx, by, height), (ax, ay, height)):
            out.append(Point3(x=px, y=py, z=pz))
    return out


_PRIMITIVE_KINDS = ("cubes", "cylinders", "lines", "triangles", "texts")  # the ones we draw


def _entity(entity_id: str, t: float, primitives: dict[str, list], frame: str = WORLD_FRAME,
            frame_locked: bool = False) -> SceneEntity:
    unknown = set(primitives) - set(_PRIMITIVE_KINDS)
    if unknown:
        raise ValueError(f"not a scene primitive kind: {sorted(unknown)}")
    return SceneEntity(timestamp=timestamp(t), frame_id=frame, id=entity_id,
                       frame_locked=frame_locked, cubes=primitives.get("cubes"),
                       cylinders=primitives.get("cylinders"), lines=primitives.get("lines"),
                       triangles=primitives.get("triangles"), texts=primitives.get("texts"))


def _merge(parts: list[dict[str, list]]) -> dict[str, list]:
    merged: dict[str, list] = {}
    for part in parts:
        for key, values in part.items():
            merged.setdefault(key, []).extend(values)
    return merged


def arena_entity(fixed: list[ShapeGeometry], t: float) -> SceneEntity:
    """The walls and fixed obstacles (one entity: they never move)."""
    parts = []
    for g in fixed:
        height, rgb = (WALL_HEIGHT, palette.WALL) if g.wall else (OBSTACLE_HEIGHT, palette.STATIC)
        parts.append(shape_primitives(g, (0.0, 0.0, 0.0), height, rgb))
    return _entity("arena", t, _merge(parts))


def obstacle_entity(index: int, shapes: list[ShapeGeometry], pose: tuple[float, float, float],
                    t: float) -> SceneEntity:
    """A movable obstacle at ``pose`` (its shapes are in its body frame)."""
    parts = [shape_primitives(g, pose, OBSTACLE_HEIGHT, palette.MOVABLE) for g in shapes]
    return _entity(f"obstacle/{index}", t, _merge(parts))


def robot_entity(name: str, index: int, radius: float, t: float,
                 outline: list | None = None) -> SceneEntity:
    """A robot's body (a cylinder, or its footprint ``outline`` [m] in the robot frame as a
    closed line), heading mark and name, locked to its base_link frame."""
    rgb = palette.robot_colour(index)
    reach = radius if outline is None else max(p[0] for p in outline)
    heading = LinePrimitive(type=LinePrimitiveLineType.LineStrip,
                            pose=pose_msg(0.0, 0.0, 0.0, ROBOT_HEIGHT + 1e-3), thickness=0.02,
                            points=[Point3(x=0.0, y=0.0, z=0.0), Point3(x=reach, y=0.0, z=0.0)],
                            color=_color(palette.HEADING))
    label = TextPrimitive(pose=pose_msg(0.0, 0.0, 0.0, ROBOT_HEIGHT + 0.15), billboard=True,
                          font_size=14.0, scale_invariant=True, color=_color(rgb), text=name)
    primitives: dict = {"lines": [heading], "texts": [label]}
    if outline is None:
        primitives["cylinders"] = [CylinderPrimitive(
            pose=pose_msg(0.0, 0.0, 0.0, ROBOT_HEIGHT / 2),
            size=Vector3(x=2 * radius, y=2 * radius, z=ROBOT_HEIGHT),
            bottom_scale=1.0, top_scale=1.0, color=_color(rgb))]
    else:
        primitives["lines"].append(LinePrimitive(
            type=LinePrimitiveLineType.LineLoop, pose=pose_msg(0.0, 0.0, 0.0, ROBOT_HEIGHT),
            thickness=0.03, points=[Point3(x=float(x), y=float(y), z=0.0) for x, y in outline],
            color=_color(rgb)))
    return _entity(f"robot/{name}", t, primitives, frame=base_frame(name), frame_locked=True)


def goal_entity(name: str, index: int, goal: tuple[float, float], tolerance: float,
                reached: bool, t: float) -> SceneEntity:
    """A robot's goal: a disc of the goal tolerance, solid once reached."""
    rgb = palette.robot_colour(index)
    disc = CylinderPrimitive(pose=pose_msg(goal[0], goal[1], 0.0, GOAL_HEIGHT / 2),
                             size=Vector3(x=2 * tolerance, y=2 * tolerance, z=GOAL_HEIGHT),
                             bottom_scale=1.0, top_scale=1.0,
                             color=_color(rgb, 0.9 if reached else 0.35))
    label = TextPrimitive(pose=pose_msg(goal[0], goal[1], 0.0, 0.1), billboard=True,
                          font_size=12.0, scale_invariant=True, color=_color(rgb),
                          text=f"{name} goal" + (" (reached)" if reached else ""))
    return _entity(f"goal/{name}", t, {"cylinders": [disc], "texts": [label]})


def deletion(entity_id: str, t: float) -> SceneEntityDeletion:
    """Remove one entity (e.g. a goal that was cleared)."""
    return SceneEntityDeletion(timestamp=timestamp(t), type=SceneEntityDeletionType.MatchingId,
                               id=entity_id)
