"""Pedestrians walking between their goals with the social force model.

Helbing & Molnar, "Social force model for pedestrian dynamics", Phys. Rev. E 51, 4282 (1995).
Per unit mass, walker a feels
- a driving force (v0 e - v) / tau toward its current goal (e the unit direction, v0 its
  desired speed, tau the relaxation time);
- from every other walker and robot b a repulsion -grad V0 exp(-b / sigma), where b is the
  semi-minor axis of the ellipse through a with foci at b and at b's next step
  (2b = sqrt((|r| + |r - s|)^2 - |s|^2), r = r_a - r_b, s = v_b * STEP_TIME), b less the
  bodies' size beyond NOMINAL_RADIUS each (so a large robot is avoided from farther); forces
  from behind (outside a 200 deg field of view) count at SIGHT_WEIGHT;
- from walls, obstacles and robots' footprints a repulsion U0 exp(-d / R) away from the nearest surface (d from the
  centre, less the walker's size beyond NOMINAL_RADIUS);
- optionally a random fluctuation, from the run's seeded generator;
- a keep-right rule (not in the 1995 paper): KEEP_RIGHT of the social force that holds a
  walker back is turned to its right, so head-on encounters resolve the way people do.
A walker with ``policy: orca`` takes its velocity from ORCA instead (:mod:`.orca`), toward the
same wished velocity. One that does not ``react_to_robot`` leaves robots out of both. Walkers
of one ``group`` share its slowest pace, and each is pulled back toward the group's centre
when it strays farther than GROUP_SPACING per companion (Moussaid et al. 2010's cohesion).
All walkers are updated together as numpy arrays. Each walker is a dynamic disc: contacts push
it (and robots that bump it count a collision); its speed is capped at MAX_SPEED_FACTOR * v0.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
import pymunk

from .. import physics
from ..config.motion import MAX_SPEED_FACTOR
from ..obstacles import Obstacle
from .body_state import BodyStates
from .orca import Orca, nearest_surfaces

STEP_TIME = 2.0  # [s] Delta t of the elliptical potential (Helbing & Molnar 1995)
SIGHT_COS = math.cos(math.radians(100.0))  # half the field of view
SIGHT_WEIGHT = 0.5  # weight of forces from outside the field of view
# People facing each other head-on both step to their right: without this a walker and a robot
# on one line balance forever. Part of a repulsion from ahead is turned to the walker's right.
KEEP_RIGHT = 0.5
# The 1995 paper measures distances between centres, for people of about this radius [m]; a
# bigger body (a robot, a large walker) is felt from farther by its excess size.
NOMINAL_RADIUS = 0.25
WALL_REACH = 5.0  # wall forces are computed out to this many ranges R
PEDESTRIAN_FRICTION = 0.3
SOCIAL_CUTOFF = 3.0  # [m] beyond their step |s| plus this, others' forces are left out (< 1 %)
# Walkers carry their own category bit, so the wall queries can skip them in C.
WALKER_CATEGORY = 1 << 30
_NOT_WALKERS = pymunk.ShapeFilter(mask=pymunk.ShapeFilter.ALL_MASKS() ^ WALKER_CATEGORY)
BOX_TEST_LIMIT = 200_000  # walkers x shapes beyond which the bounding-box test is skipped
GROUP_SPACING = 0.8  # [m] a companion's share of the group's spread (two walk ~0.8 m apart)
GROUP_PULL = 1.0  # [1/s] wished speed toward the group's centre per metre strayed beyond it


def build_pedestrian(space: pymunk.Space, config: Any) -> Obstacle:
    """A walker's body: a dynamic disc that does not spin."""
    body = pymunk.Body(config.mass, math.inf)
    body.position = tuple(config.center)
    shape = pymunk.Circle(body, config.radius)
    shape.friction = PEDESTRIAN_FRICTION
    shape.collision_type = physics.MOVABLE
    shape.filter = pymunk.ShapeFilter(categories=WALKER_CATEGORY)
    space.add(body, shape)
    return Obstacle(config, body, [shape])


class Crowd:
    """Every pedestrian of a world (an actor: ``before_step`` each tick)."""

    def __init__(self, walkers: Sequence[Obstacle], robots: Sequence, space: pymunk.Space,
                 rng: np.random.Generator) -> None:
        self.walkers = list(walkers)
        self.robots = list(robots)
        self.space = space
        self.rng = rng
        cfg: list[Any] = [w.config for w in self.walkers]
        n = len(cfg)
        self.radius = np.array([c.radius for c in cfg])  # [m]
        base = np.array([c.speed for c in cfg])
        spread = np.array([c.speed_std for c in cfg])
        draws = rng.standard_normal(n)
        # Desired speeds [m/s]: at least 10 % of the nominal one, whatever the draw.
        self.desired = np.maximum(base + spread * draws, 0.1 * base)
        self.tau = np.array([c.relaxation_time for c in cfg])  # [s]
        self.v0 = np.array([c.social_strength for c in cfg])  # [m^2/s^2]
        self.sigma = np.array([c.social_range for c in cfg])  # [m]
        self.u0 = np.array([c.wall_strength for c in cfg])  # [m^2/s^2]
        self.wall_range = np.array([c.wall_range for c in cfg])  # [m]
        self.fluctuation = np.array([c.fluctuation for c in cfg])  # [m/s^2]
        self.reacts = np.array([c.react_to_robot for c in cfg], dtype=bool)
        self._robot_bodies = {r.body for r in self.robots}
        self._states = BodyStates(space, [w.body for w in self.walkers])
        # What the wall forces can come from, by bounding box: a walker whose reach meets no box
        # skips its queries (exact: a shape within reach has its box within reach too).
        mine = {shape for w in self.walkers for shape in w.shapes}
        others = [s for s in space.shapes if s not in mine and s.body is not None]
        static = [s for s in others if s.body is not None
                  and s.body.body_type == pymunk.Body.STATIC]
        self._static_boxes = np.array([(s.bb.left, s.bb.bottom, s.bb.right, s.bb.top)
                                       for s in static], dtype=float).reshape(-1, 4)
        fixed = set(static)
        self._moving_shapes = [s for s in others if s not in fixed]
        names = sorted({c.group for c in cfg if c.group is not None})
        self.groups = [np.array([i for i, c in enumerate(cfg) if c.group == g]) for g in names]
        self.groups = [g for g in self.groups if len(g) > 1]
        for members in self.groups:  # a group walks at its slowest member's pace
            self.desired[members] = self.desired[members].min()
        orca = np.array([c.policy == "orca" for c in cfg], dtype=bool)
        self.social = ~orca
        self.orca = Orca(np.flatnonzero(orca), cfg) if orca.any() else None
        self.goals = [np.asarray(c.goals, dtype=float) for c in cfg]
        self.target = [0] * n  # index of the current goal
        self.direction = [1] * n  # +1 forward through the goals, -1 back (pingpong)
        self.done = np.zeros(n, dtype=bool)  # a "once" walker at its last goal
        self._tolerance = np.array([c.goal_tolerance for c in cfg])  # [m]
        self._robot_radius = np.array([r.spec.radius for r in self.robots])
        # Walkers feel each other through the elliptical potential only (the wall queries skip
        # them by category); robots also repel like walls, from their real footprint.

    # ------------------------------------------------------------------ state
    def positions(self) -> np.ndarray:
        """Every walker's position [m], shape (n, 2)."""
        return self._states.read()[:, :2]

    def velocities(self) -> np.ndarray:
        """Every walker's velocity [m/s], shape (n, 2)."""
        return self._states.read()[:, 2:]

    def goal_points(self) -> np.ndarray:
        return np.array([g[k] for g, k in zip(self.goals, self.target)]).reshape(-1, 2)

    # ------------------------------------------------------------------ the tick
    def before_step(self, time: float, dt: float) -> None:
        state = self._states.read()
        pos, vel = state[:, :2], state[:, 2:]
        self._advance_goals(pos)
        to_goal = self.goal_points() - pos
        dist = np.hypot(to_goal[:, 0], to_goal[:, 1])
        e = to_goal / np.maximum(dist, 1e-9)[:, None]
        wish = np.where(self.done, 0.0, self.desired)
        pref = wish[:, None] * e + self._cohesion(pos)  # the wished velocity [m/s]
        cap = MAX_SPEED_FACTOR * self.desired
        new = vel.copy()
        if self.social.any():
            new[self.social] = self._social_force(pos, vel, e, pref, dt)[self.social]
        if self.orca is not None:
            new[self.orca.agents] = self._orca(pos, vel, pref, cap, dt)
        speed = np.hypot(new[:, 0], new[:, 1])
        new *= np.minimum(1.0, cap / np.maximum(speed, 1e-12))[:, None]
        for walker, (vx, vy) in zip(self.walkers, new.tolist()):
            walker.body.velocity = (vx, vy)

    def _cohesion(self, pos: np.ndarray) -> np.ndarray:
        """Wished velocity [m/s] back toward each walker's group centre, beyond its spread."""
        pull = np.zeros_like(pos)
        for members in self.groups:
            off = pos[members].mean(axis=0) - pos[members]
            dist = np.maximum(np.hypot(off[:, 0], off[:, 1]), 1e-9)
            stray = np.maximum(dist - 0.5 * GROUP_SPACING * (len(members) - 1), 0.0)
            pull[members] = (GROUP_PULL * stray / dist)[:, None] * off
        return pull

    def _social_force(self, pos: np.ndarray, vel: np.ndarray, e: np.ndarray, pref: np.ndarray,
                      dt: float) -> np.ndarray:
        """Velocities after one step of the social force model (every walker)."""
        force = (pref - vel) / self.tau[:, None]
        social = self._social(pos, vel, e)
        against = np.maximum(-(social * e).sum(axis=1), 0.0)  # the part that holds us back
        social += KEEP_RIGHT * against[:, None] * np.column_stack([e[:, 1], -e[:, 0]])
        force += social
        force += self._walls(pos)
        if self.fluctuation.any():
            force += self.fluctuation[:, None] * self.rng.standard_normal(pos.shape)
        return vel + force * dt

    def _orca(self, pos: np.ndarray, vel: np.ndarray, pref: np.ndarray, cap: np.ndarray,
              dt: float) -> np.ndarray:
        """Velocities of the ORCA walkers."""
        assert self.orca is not None
        agents = self.orca.agents
        opos, ovel, orad = self._others(pos, vel)
        n, m = len(pos), len(opos)
        visible = np.ones((len(agents), m), dtype=bool)
        visible[np.arange(len(agents)), agents] = False
        visible[:, n:] &= self.reacts[agents][:, None]
        walls: list[list[tuple[float, float, float]]] = []
        # farther surfaces than this never bind: (d - r) / tau_obst exceeds the speed cap
        reach = self.radius[agents] + cap[agents] * self.orca.wall_horizon
        near = self._near_boxes(pos[agents], reach)
        for k, a in enumerate(agents.tolist()):
            if not near[k]:
                walls.append([])
                continue
            skip = self._robot_bodies  # robots are neighbours (or ignored), not walls
            walls.append(nearest_surfaces(self.space, (float(pos[a, 0]), float(pos[a, 1])),
                                          float(reach[k]), _NOT_WALKERS, skip))
        return self.orca.velocities(pos[agents], vel[agents], self.radius[agents],
                                    (opos, ovel, orad), n,
                                    visible, pref[agents], cap[agents], dt, walls)

    def _advance_goals(self, pos: np.ndarray) -> None:
        off = self.goal_points() - pos
        arrived = (np.hypot(off[:, 0], off[:, 1]) <= self._tolerance) & ~self.done
        for i in np.flatnonzero(arrived).tolist():  # most ticks: nobody
            walker = self.walkers[i]
            goals, k = self.goals[i], self.target[i]
            config: Any = walker.config
            mode, last = config.mode, len(goals) - 1
            if mode == "loop":
                self.target[i] = (k + 1) % len(goals)
            elif mode == "once":
                if k == last:
                    self.done[i] = True
                else:
                    self.target[i] = k + 1
            else:  # pingpong
                if last == 0:
                    continue
                if not 0 <= k + self.direction[i] <= last:
                    self.direction[i] = -self.direction[i]
                self.target[i] = k + self.direction[i]

    def _others(self, pos: np.ndarray, vel: np.ndarray) -> tuple[np.ndarray, ...]:
        """Positions, velocities and radii of everything a walker avoids: walkers, robots."""
        if not self.robots:
            return pos, vel, self.radius
        bodies = [r.body for r in self.robots]
        rpos = np.array([tuple(b.local_to_world(b.center_of_gravity)) for b in bodies])
        rvel = np.array([tuple(b.velocity) for b in bodies])
        return (np.vstack([pos, rpos]), np.vstack([vel, rvel]),
                np.concatenate([self.radius, self._robot_radius]))

    def _social(self, pos: np.ndarray, vel: np.ndarray, e: np.ndarray) -> np.ndarray:
        """Sum of the elliptical repulsions (per unit mass) on every walker, shape (n, 2).

        Only pairs closer than the other's step plus SOCIAL_CUTOFF are evaluated: farther ones
        contribute less than exp(-SOCIAL_CUTOFF / sigma) of the force at contact."""
        opos, ovel, orad = self._others(pos, vel)
        n = len(pos)
        step = ovel * STEP_TIME
        d = pos[:, None, :] - opos[None, :, :]
        reach = np.hypot(step[:, 0], step[:, 1]) + SOCIAL_CUTOFF + orad
        near = (d[..., 0] ** 2 + d[..., 1] ** 2) < reach[None, :] ** 2
        near[np.arange(n), np.arange(n)] = False  # no force on oneself
        near[:, n:] &= self.reacts[:, None]  # robots, for walkers that react to them
        a, b = np.nonzero(near)
        force = np.zeros_like(pos)
        if not len(a):
            return force
        r = d[a, b]  # from the other to the walker
        s = step[b]
        q = r - s
        rn = np.maximum(np.hypot(r[:, 0], r[:, 1]), 1e-9)
        qn = np.maximum(np.hypot(q[:, 0], q[:, 1]), 1e-9)
        two_b = np.sqrt(np.maximum((rn + qn) ** 2 - (s[:, 0] ** 2 + s[:, 1] ** 2), 1e-12))
        grad_b = ((rn + qn) / (2.0 * two_b))[:, None] * (r / rn[:, None] + q / qn[:, None])
        gap = np.maximum(0.5 * two_b - (self.radius[a] + orad[b] - 2 * NOMINAL_RADIUS), 0.0)
        sigma = self.sigma[a]
        magnitude = self.v0[a] / sigma * np.exp(-gap / sigma)
        seen = (-(r * e[a]).sum(axis=1) / rn) >= SIGHT_COS
        magnitude *= np.where(seen, 1.0, SIGHT_WEIGHT)
        pair = magnitude[:, None] * grad_b
        force[:, 0] = np.bincount(a, pair[:, 0], minlength=n)
        force[:, 1] = np.bincount(a, pair[:, 1], minlength=n)
        return force

    def _near_boxes(self, pos: np.ndarray, reach: np.ndarray) -> np.ndarray:
        """Whether each point's square of half-side ``reach`` [m] meets the bounding box of
        any non-walker shape (static boxes from the build, moving ones as they are now)."""
        boxes = self._static_boxes
        if self._moving_shapes:
            boxes = np.vstack([boxes, [(s.bb.left, s.bb.bottom, s.bb.right, s.bb.top)
                                       for s in self._moving_shapes]])
        if len(pos) * len(boxes) > BOX_TEST_LIMIT:  # a huge map: let the queries sort it out
            return np.ones(len(pos), dtype=bool)
        x, y, r = pos[:, :1], pos[:, 1:], reach[:, None]
        return ((boxes[:, 0] <= x + r) & (boxes[:, 2] >= x - r)
                & (boxes[:, 1] <= y + r) & (boxes[:, 3] >= y - r)).any(axis=1)

    def _walls(self, pos: np.ndarray) -> np.ndarray:
        """Repulsion from the nearest surface of each wall, obstacle, robot and arena side."""
        force = np.zeros_like(pos)
        near = self._near_boxes(pos, WALL_REACH * self.wall_range + self.radius)
        for i, (x, y) in enumerate(pos.tolist()):
            if not near[i]:
                continue
            reach = WALL_REACH * self.wall_range[i] + self.radius[i]
            # One C call says whether anything is in reach at all (most walkers, most ticks:
            # nothing), before the query that reports every shape through a Python callback.
            if self.space.point_query_nearest((x, y), reach, _NOT_WALKERS) is None:
                continue
            for hit in self.space.point_query((x, y), reach, _NOT_WALKERS):
                if not self.reacts[i] and hit.shape.body in self._robot_bodies:
                    continue
                gap = max(hit.distance - (self.radius[i] - NOMINAL_RADIUS), 0.0)
                push = self.u0[i] / self.wall_range[i] * math.exp(-gap / self.wall_range[i])
                gx, gy = hit.gradient
                force[i, 0] += push * gx
                force[i, 1] += push * gy
        return force


def make_crowd(world: Any, robots: Sequence[Any], rng: np.random.Generator) -> Crowd | None:
    """The crowd of a world's pedestrians (None when it has none)."""
    walkers = [o for o in world.obstacles if getattr(o.config, "type", "") == "pedestrian"]
    if not walkers:
        return None
    return Crowd(walkers, robots, world.space, rng)
