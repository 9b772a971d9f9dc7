"""Robots that nothing can reach step apart: one pymunk step a tick, in a Space of their own.

The substep gate (physics/substeps.py) makes a Space take substeps whenever a contact can start
anywhere in it. In a crowd (10,000 robots) some pair is always about to touch, so every robot
took every substep, though most had nothing within reach. A robot that nothing can reach
within the coming ticks needs no substeps: it steps apart. Its body, control body and joints
move to a second pymunk Space (``World.apart_space``, the same settings) that takes one step
of the whole tick, while the others substep in the contact Space. Its shapes leave every
Space meanwhile (nothing can touch them; the contact Space need not sort them each substep),
and come back with it. Its joints pull it as they would in the contact Space; only the step
length differs, as in a tick the gate takes in one step. Where
the joints pull through the centre of gravity (discs), one solver iteration solves them, and
the apart Space takes one.

Every ``PLAN_TICKS`` ticks the planner decides which robots step apart until its next
decision: those that neither another moving body nor a fixed shape can reach before the last
of those ticks ends, at their top speeds (or faster, if they go faster now):

- two moving bodies: the distance between their origins less both reaches, over both speeds
  (a k-d tree finds the pairs that are near);
- a fixed shape: the distance to points sampled along the outlines of the world's fixed
  shapes (``SAMPLE_SPACING`` apart, so the true distance is at most half of that shorter;
  a k-d tree of them, built once) less the shapes' rounding radius.

It plans only for fleets of ``SPLIT_FROM`` robots or more, steered as rows
(``Propulsion.batched``), in a world of its own
(copies of a scenario share one Space), and only while nobody holds the world's Space
(``World.space``): a LiDAR, a crowd, a metric that queries the world, or a user's code that
asks for the Space bring every robot back for the rest of the run, so whatever looks at the
world sees all of it. A teleport brings them back too, and the next tick plans anew.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import pymunk
from scipy.spatial import cKDTree

from pymunk_bot.physics.propulsion import Propulsion
from pymunk_bot.physics.substeps import (MARGIN, Mover, SubstepGate, motions, origin_speeds,
                                         pair_gaps)
from pymunk_bot.physics.world import World

PLAN_TICKS = 4  # ticks between two decisions
# Fleets smaller than this step in one Space: below it, deciding and the second Space's step
# cost about what the substeps they save do (the swarm of benchmarks/fleet.py, 6 s from 0.5 s,
# CPU time, one run: 1000 robots 12.42x real time apart against 12.45x in one Space, 2000
# robots 5.97x against 4.54x, 5000 robots 2.05x against 1.21x; 100 robots, 3 s: 82x against
# 109x).
SPLIT_FROM = 2000
SAMPLE_SPACING = 0.05  # [m] between the points sampled along fixed outlines


class FixedOutlines:
    """Points along the outlines of a Space's fixed shapes, for lower bounds of the distance
    from any point to the nearest of them."""

    def __init__(self, space: pymunk.Space) -> None:
        points: list[np.ndarray] = []
        rounding = 0.0  # [m] the largest rounding radius (segments, rounded polygons)
        for shape in space.shapes:
            body = shape.body
            if body is None or not _fixed(shape) or shape.sensor:
                continue
            if isinstance(shape, pymunk.Circle):
                turns = max(8, math.ceil(2 * math.pi * shape.radius / SAMPLE_SPACING))
                angle = np.linspace(0.0, 2 * math.pi, turns, endpoint=False)
                local = np.array(shape.offset) + shape.radius * np.column_stack(
                    [np.cos(angle), np.sin(angle)])
                points.append(_to_world(body, local))
                continue
            if isinstance(shape, pymunk.Segment):
                corners = [tuple(shape.a), tuple(shape.b)]
            elif isinstance(shape, pymunk.Poly):
                corners = [tuple(v) for v in shape.get_vertices()]
                corners.append(corners[0])
            else:  # an unknown kind: its bounding box's outline (world frame: no transform)
                bb = shape.bb
                corners = [(bb.left, bb.bottom), (bb.right, bb.bottom), (bb.right, bb.top),
                           (bb.left, bb.top), (bb.left, bb.bottom)]
                body = None
            rounding = max(rounding, float(getattr(shape, "radius", 0.0)))
            for a, b in zip(corners, corners[1:]):
                samples = max(2, math.ceil(math.dist(a, b) / SAMPLE_SPACING) + 1)
                along = np.linspace(0.0, 1.0, samples)
                local = np.array(a) + np.outer(along, np.subtract(b, a))
                points.append(local if body is None else _to_world(body, local))
        cloud = np.concatenate(points) if points else np.empty((0, 2))
        self.tree = cKDTree(cloud) if cloud.shape[0] else None
        self.slack = 0.5 * SAMPLE_SPACING + rounding  # [m] sample distance - true distance, at most

    def gaps(self, xy: np.ndarray, look: float) -> np.ndarray:
        """At most the distance [m] from each of ``xy`` (n, 2) to the nearest fixed shape, or
        inf where none lies within ``look`` [m]."""
        if self.tree is None:
            return np.full(xy.shape[0], math.inf)
        distance, _ = self.tree.query(xy, distance_upper_bound=look + self.slack)
        return distance - self.slack


def _fixed(shape: pymunk.Shape | None) -> bool:
    """Whether ``shape`` is a fixed one (on a static body)."""
    return shape is not None and shape.body is not None and \
        shape.body.body_type == pymunk.Body.STATIC


def _to_world(body: pymunk.Body, local: np.ndarray) -> np.ndarray:
    """Body-frame points (n, 2) [m] in the world frame."""
    c, s = math.cos(body.angle), math.sin(body.angle)
    x, y = body.position
    return np.column_stack([c * local[:, 0] - s * local[:, 1] + x,
                            s * local[:, 0] + c * local[:, 1] + y])


class SplitPlanner:
    """Which robots step apart (see the module docstring), from the contact Space ``space``
    to ``apart``. ``robots``: the fleet's bodies in Propulsion's order; ``movers``: every
    moving body (the gate's); ``dt``: the tick [s]."""

    def __init__(self, space: pymunk.Space, apart: pymunk.Space, robots: Sequence[pymunk.Body],
                 movers: Sequence[Mover], dt: float) -> None:
        self.dt = dt
        if all(b.center_of_gravity == (0, 0) for b in robots):
            # Each robot's joints pull through its centre of gravity (the pivot's anchor is
            # its origin): the pivot moves, the gear turns, neither disturbs the other, and
            # one solver iteration solves both (measured: 10,000 robots for 2.5 s, positions
            # within 4e-15 m of ten iterations'). Nothing else is in that Space.
            apart.iterations = 1
        self.n = len(robots)
        of = {id(m.body): m for m in movers}
        own = {id(b) for b in robots}
        # Rows: the robots in Propulsion's order, then the other moving bodies.
        self._others = [m for m in movers if id(m.body) not in own]
        rows = [of[id(b)] for b in robots] + self._others
        self._reach = np.array([m.reach for m in rows])  # [m]
        self._top = np.array([m.speed or 0.0 for m in rows])  # [m/s] (0: only its speed now)
        self._offset = np.array([abs(m.body.center_of_gravity) for m in rows])  # [m] cog to origin
        self._outlines = FixedOutlines(space)
        self._space = space
        self._inside_unknown = False  # a teleport may have put an origin inside a fixed shape
        self.apart = np.zeros(self.n, dtype=bool)  # stepping apart in this tick
        self._ticks_left = 0  # ticks until the next decision
        self.layout = -1  # World.layout after this planner's last move (-1: none yet)

    @property
    def crowded(self) -> bool:
        """Whether the contact Space holds moving bodies besides robots (each tick: substeps)."""
        return bool(self._others)

    def reset(self, teleported: bool = False) -> None:
        """Every robot back in the contact Space: the next tick decides anew. ``teleported``:
        after a teleport, which may have put a robot's origin inside a fixed shape (the
        outlines tell no inside from outside; the next decision asks pymunk, robot by robot)."""
        self.apart = np.zeros(self.n, dtype=bool)
        self._ticks_left = 0
        self._inside_unknown = self._inside_unknown or teleported

    def next_apart(self, propulsion: Propulsion) -> np.ndarray:
        """Which robots step apart in the next tick (``propulsion``: the fleet's, which reads
        the robots' motion when a decision is due)."""
        if self._ticks_left > 1:
            self._ticks_left -= 1
            return self.apart
        self._ticks_left = PLAN_TICKS
        return self._clear((PLAN_TICKS + 1) * self.dt, propulsion.motion_array(),
                           propulsion.position_array())

    def settle(self, world: World, propulsion: Propulsion, gate: SubstepGate,
               apart: np.ndarray) -> None:
        """After a tick: the robots that step apart in the next one (``apart``) move there,
        the others back; ``propulsion`` and ``gate`` look their rows up again."""
        went = np.flatnonzero(apart & ~self.apart).tolist()
        back = np.flatnonzero(self.apart & ~apart).tolist()
        if went or back:
            bodies, controls = propulsion.bodies, propulsion.controls
            world.move_back([(bodies[k], controls[k]) for k in back])
            world.move_apart([(bodies[k], controls[k]) for k in went])
            propulsion.relocated()
            gate.relocated()
        self.apart = apart
        self.layout = world.layout

    def _clear(self, horizon: float, motion: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """The robots that nothing can reach within ``horizon`` [s]."""
        n = self.n
        origins = np.empty((self._reach.shape[0], 2))
        origins[:n] = xy
        others = [mover.body for mover in self._others]  # few: crates, moving obstacles
        for k, body in enumerate(others, start=n):
            origins[k] = tuple(body.position)
        moving = np.concatenate([motion[:, 1:4], motions(others)])  # (vx, vy, omega) each
        now = origin_speeds(moving[:, 0], moving[:, 1], moving[:, 2], self._offset)
        speeds = np.maximum(self._top, now)
        if not (np.isfinite(origins).all() and np.isfinite(speeds).all()):
            return np.zeros(n, dtype=bool)  # a body thrown out of the world: no telling
        reach = self._reach
        travel = speeds * horizon  # [m] the most each origin moves
        clear = np.ones(reach.shape[0], dtype=bool)
        pairs = cKDTree(origins).query_pairs(2.0 * float(reach.max() + travel.max()) + MARGIN,
                                             output_type="ndarray")
        if pairs.size:
            i, j = np.ascontiguousarray(pairs[:, 0]), np.ascontiguousarray(pairs[:, 1])
            gap = pair_gaps(np.ascontiguousarray(origins), reach, i, j)  # one layout: one compile
            meet = gap <= travel[i] + travel[j]
            clear[i[meet]] = False
            clear[j[meet]] = False
        look = float(reach[:n].max() + travel[:n].max()) + MARGIN
        fixed = self._outlines.gaps(origins[:n], look) - reach[:n] - MARGIN  # [m]
        out = clear[:n] & (fixed > travel[:n])
        if self._inside_unknown:  # a robot inside a fixed shape stays where contacts push it out
            self._inside_unknown = False
            every = pymunk.ShapeFilter()
            for k in np.flatnonzero(out).tolist():
                out[k] = not any(_fixed(hit.shape) for hit in
                                 self._space.point_query(tuple(origins[k]), 0.0, every))
        return out
