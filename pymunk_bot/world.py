"""The physical world: one pymunk Space with the arena, obstacles and robots, and contact bookkeeping."""
from __future__ import annotations

import numpy as np
import pymunk

from . import physics
from .config.schema import ScenarioConfig
from .config.substeps import ARENA_WALL_THICKNESS, required_substeps
from .obstacles import Obstacle, build_obstacle
from .robot import Robot

class World:
    """Owns the Space. Build order is fixed (arena, obstacles, robots) for determinism."""

    def __init__(self, config: ScenarioConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.width, self.height = config.world.size
        self.space = physics.new_space()
        self.arena_shapes = self._build_arena()
        self.obstacles: list[Obstacle] = [build_obstacle(self.space, o) for o in config.obstacles]
        robot_rngs = rng.spawn(len(config.robots))
        # Group ids start at 1: group 0 means "no group" to pymunk.
        self.robots: dict[str, Robot] = {
            rc.name: Robot(rc, self.space, group=i + 1, rng=robot_rngs[i])
            for i, rc in enumerate(config.robots)
        }
        self._robot_of_shape = {r.shape: r for r in self.robots.values()}
        for other in (physics.STATIC, physics.MOVABLE, physics.ROBOT):
            self.space.on_collision(physics.ROBOT, other, begin=self._begin)
        self.substeps = config.world.substeps or required_substeps(config)

    def _build_arena(self) -> list[pymunk.Shape]:
        w, h, t = self.width, self.height, ARENA_WALL_THICKNESS
        boxes = [(-t, -t, 0, h + t), (w, -t, w + t, h + t), (0, -t, w, 0), (0, h, w, h + t)]
        shapes = []
        for x0, y0, x1, y1 in boxes:
            shape = pymunk.Poly(self.space.static_body, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
            shape.friction = self.config.world.wall_friction
            shape.collision_type = physics.STATIC
            shapes.append(shape)
        self.space.add(*shapes)
        return shapes

    # ------------------------------------------------------------------ contacts
    def _begin(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data) -> None:
        """A contact episode starts: count it for every robot in it (both, robot on robot)."""
        for shape in arbiter.shapes:
            robot = self._robot_of_shape.get(shape)
            if robot is not None:
                robot.collisions += 1
