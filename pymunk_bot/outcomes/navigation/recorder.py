"""One robot's navigation metrics, measured after every tick of a run.

Per tick (only in runs that ask: a crowd, an ``expect`` bound on a metric, or :func:`track`):
clearances and times to collision to every pedestrian (one compiled call over the crowd,
folded into running minima and sums: :func:`.formulas.encounters`), stalled time, and the
clearing distance; every ``sample_period`` the velocity for speed, acceleration and
jerk. Contact impulses come from pymunk's post-solve of the robot's contacts. Everything else
(success, SPL, ...) is read once, at :meth:`NavMetrics.values`.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
import pymunk

from pymunk_bot.actors.body_state import BodyStates
from pymunk_bot.actors.pedestrians import WALKER_CATEGORIES
from pymunk_bot.outcomes.metrics import RobotMetrics
from pymunk_bot.outcomes.navigation import formulas
from pymunk_bot.outcomes.navigation.definitions import METRIC_NAMES, Thresholds
from pymunk_bot.outcomes.navigation.shortest import shortest_path_length, world_key

CONTACT_KINDS = ("wall", "robot", "human", "object")


class ContactTally:
    """Contact episodes, summed impulse [N s] and peak force [N] per kind of thing touched."""

    def __init__(self) -> None:
        self.episodes = dict.fromkeys(CONTACT_KINDS, 0)
        self.impulse = dict.fromkeys(CONTACT_KINDS, 0.0)  # [N s]
        self.peak_force = dict.fromkeys(CONTACT_KINDS, 0.0)  # [N]

    def any(self) -> bool:
        """Whether any contact episode began."""
        return sum(self.episodes.values()) > 0

    def add(self, kind: str, first: bool, impulse: float, step: float) -> None:
        """One solved contact: ``impulse`` [N s] over a pymunk step of ``step`` [s]."""
        self.episodes[kind] += int(first)
        self.impulse[kind] += impulse
        if step > 0:
            self.peak_force[kind] = max(self.peak_force[kind], impulse / step)


class NavMetrics:
    """The metrics of robot ``robot`` (a :class:`~pymunk_bot.robots.robot.Robot`) in ``world``.

    ``robots``: every robot of the run (contacts with them count as robot contacts);
    ``config``: the scenario (duration, static map for SPL); ``maps``: its
    :class:`~pymunk_bot.engine.build.MapSource`. Measures from the world's time at construction."""

    def __init__(self, world: Any, robot: Any, robots: list[Any], config: Any, maps: Any,
                 thresholds: Thresholds | None = None) -> None:
        self.thresholds = thresholds or Thresholds()
        self.signature = self.thresholds.signature()
        self._world, self._robot, self._config, self._maps = world, robot, config, maps
        self._body: pymunk.Body = robot.body
        self._radius = float(robot.spec.radius)  # [m] bounding radius (time to collision)
        self._shapes = list(robot.shapes)
        self._disc = getattr(robot.config, "footprint", None) is None
        walkers = [o for o in world.obstacles if getattr(o.config, "type", "") == "pedestrian"]
        self._humans = [o.body for o in walkers]
        self._human_radius = np.array([o.config.radius for o in walkers], dtype=float)  # [m]
        self._human_set = set(self._humans)
        self._human_states = BodyStates(self._humans)
        self._robot_set = {r.body for r in robots if r is not robot}
        # Clearing distance: RobotMetrics' clearance, with pedestrians left out of the query.
        f = robot.shape.filter
        self._clearing = RobotMetrics(world.space, robot, [], shape_filter=pymunk.ShapeFilter(
            group=f.group, categories=f.categories, mask=f.mask & ~WALKER_CATEGORIES))
        self.contacts = ContactTally()
        for shape in self._shapes:
            world.watch_contacts(shape, self._on_contact)
        self.start = self._last = float(world.time)  # [s]
        self.min_distance_to_human = math.inf  # [m]
        self.min_time_to_collision = math.inf  # [s]
        self.personal_space_intrusions = 0
        self.personal_space_time = 0.0  # [s]
        self.stalled_time = 0.0  # [s]
        self.discomfort_time = 0.0  # [s] before the goal with a pedestrian within discomfort
        self.first_collision: float | None = None  # [s] the tick of the first collision
        self.human_overlap = False  # a pedestrian overlapped the robot at some tick
        self._inside = np.zeros(len(self._humans), dtype=bool)
        self._clear = np.zeros(len(self._humans))  # [m] to each human, this tick
        self._samples: list[tuple[float, float, float, float]] = []  # t, vx, vy, best [s, m/s, m]
        self._best = math.inf  # [m] closest approach to the goal so far
        self._next_sample = self.start
        self._sample(self.start, *self._body.velocity)

    # ------------------------------------------------------------------ per tick
    def update(self, now: float) -> None:
        """Measure the tick that ended at ``now`` [s]."""
        step, self._last = now - self._last, now
        vx, vy = self._body.velocity
        reached = self._robot.goal_reached
        if not reached and math.hypot(vx, vy) < self.thresholds.stall_speed:
            self.stalled_time += step
        closest = self._measure_humans(step, vx, vy) if self._humans else math.inf
        if not reached and closest < self.thresholds.discomfort_distance:
            self.discomfort_time += step
        self.human_overlap = self.human_overlap or closest < 0.0
        if self.first_collision is None and (closest < 0.0 or self.contacts.any()):
            self.first_collision = now
        self._clearing.update(now)
        if not reached and now >= self._next_sample - 1e-9:
            self._sample(now, vx, vy)

    def _sample(self, now: float, vx: float, vy: float) -> None:
        goal = self._robot.goal
        if goal is not None:
            x, y = self._body.position
            self._best = min(self._best, math.hypot(goal[0] - x, goal[1] - y))
        self._samples.append((now, vx, vy, self._best))
        self._next_sample += self.thresholds.sample_period

    @property
    def collided(self) -> bool:
        """Whether the robot has collided (a contact, or a pedestrian overlapping it at a
        tick) since the episode began."""
        return self.first_collision is not None

    def _measure_humans(self, step: float, vx: float, vy: float) -> float:
        """Fold this tick into the human metrics; the least clearance [m] now."""
        state = self._human_states.read()
        # contiguous: one array layout for the kernel (numba compiles it once)
        hxy, hv = np.ascontiguousarray(state[:, :2]), np.ascontiguousarray(state[:, 2:])
        x, y = self._body.position
        clear = self._clear
        if not self._disc:  # exact distance to the footprint's pieces, less the pedestrian's
            clear[:] = [min(s.point_query(tuple(p)).distance for s in self._shapes)
                        for p in hxy.tolist()]
            clear -= self._human_radius
        closest, entries, inside, ttc = formulas.encounters(
            hxy, hv, self._human_radius, x, y, vx, vy, self._radius, clear, self._disc,
            self.thresholds.personal_space, self._inside)
        self.min_distance_to_human = min(self.min_distance_to_human, closest)
        self.personal_space_intrusions += entries
        if inside:
            self.personal_space_time += step
        self.min_time_to_collision = min(self.min_time_to_collision, ttc)
        return float(closest)

    def _on_contact(self, arbiter: pymunk.Arbiter) -> None:
        a, b = arbiter.bodies
        other = b if a is self._body else a
        if other is self._body:
            return
        if other.body_type == pymunk.Body.STATIC:
            kind = "wall"
        elif other in self._human_set:
            kind = "human"
        elif other in self._robot_set:
            kind = "robot"
        else:
            kind = "object"
        self.contacts.add(kind, arbiter.is_first_contact, float(arbiter.total_impulse.length),
                          self._world.space.current_time_step)

    # ------------------------------------------------------------------ the metrics
    def shortest_path(self) -> float:
        """L* [m]: the shortest collision-free path from the start pose to the goal (NaN
        without a goal)."""
        goal = self._robot.goal
        if goal is None:
            return math.nan
        x, y = self._robot.config.pose[:2]
        start = (float(x), float(y))
        return shortest_path_length(self._maps.info(), start, (float(goal[0]), float(goal[1])),
                                    self._radius, self.thresholds.spl_resolution,
                                    key=world_key(self._config))

    def values(self) -> dict[str, float]:
        """Every metric (docs/benchmark.md), by the names of ``METRIC_NAMES``, as floats."""
        robot, t = self._robot, self.thresholds
        now = float(self._world.time)
        has_goal = robot.goal is not None
        reached = bool(robot.goal_reached)
        ttg = robot.time_to_goal
        duration = self._config.world.duration
        ended = now >= duration - 0.5 * self._config.world.dt
        samples = np.array(self._samples, dtype=float).reshape(-1, 4)
        c = self.contacts
        if reached and ttg is not None:  # up to the goal: not diluted by what came after
            path = float(robot.distance_to_goal or 0.0)
            speed = formulas.mean_speed(path, ttg - self.start)
        else:
            path = float(robot.distance)
            speed = formulas.mean_speed(path, now - self.start)
        nan = math.nan
        first = self.first_collision
        clean = first is None or (ttg is not None and first > ttg)  # none before the goal
        elapsed = (ttg if reached and ttg is not None else now) - self.start
        out: dict[str, float] = {
            "success": float(reached and clean) if has_goal else nan,
            "reached": float(reached) if has_goal else nan,
            "collision": float(first is not None),
            "collision_wall": float(c.episodes["wall"] + c.episodes["object"] > 0),
            "collision_robot": float(c.episodes["robot"] > 0),
            "collision_human": float(c.episodes["human"] > 0 or self.human_overlap),
            "timeout": float(not reached and ended) if has_goal else nan,
            "failure_to_progress": float(formulas.failed_to_progress(
                samples[:, 0], samples[:, 3], t.progress_window, t.progress_distance))
            if has_goal else nan,
            "stalled_time": self.stalled_time,
            "time_to_goal": float(ttg) if ttg is not None else nan,
            "path_length": path,
            "spl": formulas.spl(reached, self.shortest_path(), path) if has_goal else nan,
            "min_distance_to_human": self.min_distance_to_human,
            "personal_space_intrusions": float(self.personal_space_intrusions),
            "personal_space_time": self.personal_space_time,
            "discomfort": self.discomfort_time / elapsed if elapsed > 0 else 0.0,
            "min_time_to_collision": self.min_time_to_collision,
            "clearing_distance": float(self._clearing.min_clearance or 0.0),
            "mean_speed": speed,
            "human_impulse": c.impulse["human"],
            "peak_human_force": c.peak_force["human"],
            "robot_impulse": c.impulse["robot"],
            "peak_robot_force": c.peak_force["robot"],
            "object_impulse": c.impulse["object"],
            "peak_object_force": c.peak_force["object"],
        }
        out.update(formulas.sample_kinematics(samples[:, 1:3], t.sample_period))
        return {name: float(out[name]) for name in METRIC_NAMES}
