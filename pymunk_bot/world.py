"""The physical world: one pymunk Space with the arena, obstacles and robot bodies, and the
contact bookkeeping. Build order is fixed (arena, obstacles, robots) for determinism."""
from __future__ import annotations

from typing import Any, Callable

import pymunk

from . import physics
from .config.schema import ScenarioConfig
from .config.substeps import ARENA_WALL_THICKNESS, required_substeps
from .obstacles import Obstacle
from .plugins import obstacles as obstacle_kinds


class World:
    """Owns the Space. ``actors`` move things before every tick (moving obstacles, pedestrians):
    objects with ``before_step(time, dt)``."""

    def __init__(self, config: ScenarioConfig) -> None:
        self.config = config
        self.width, self.height = config.world.arena
        # (x0, y0, x1, y1) [m]: [0, width] x [0, height], or a map's extent in the map's frame
        self.extent: tuple[float, float, float, float] = config.world.extent
        self.space = physics.new_space(
            pushable=any(getattr(o, "movable", False) for o in config.obstacles))
        self.map = config.world.map_geometry()  # a MapGeometry, or None
        self.arena_shapes = self._build_arena() if self.map is None else self._build_map()
        self.obstacles: list[Obstacle] = [
            obstacle_kinds.get(o.type)(self.space, o) for o in config.obstacles]
        self.actors: list[Any] = []
        self.time = 0.0  # simulated time [s], kept by the simulation
        self.substeps = config.world.substeps or required_substeps(config)
        self._caster: Any = None
        self._on_contact: dict[pymunk.Shape, Callable[[], None]] = {}
        for other in (physics.STATIC, physics.MOVABLE, physics.ROBOT):
            self.space.on_collision(physics.ROBOT, other, begin=self._begin)

    def _build_arena(self) -> list[pymunk.Shape]:
        w, h, t = self.width, self.height, ARENA_WALL_THICKNESS
        boxes = [(-t, -t, 0, h + t), (w, -t, w + t, h + t), (0, -t, w, 0), (0, h, w, h + t)]
        shapes: list[pymunk.Shape] = []
        for x0, y0, x1, y1 in boxes:
            shape = pymunk.Poly(self.space.static_body, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
            shape.friction = self.config.world.wall_friction
            shape.collision_type = physics.STATIC
            shapes.append(shape)
        self.space.add(*shapes)
        return shapes

    def _build_map(self) -> list[pymunk.Shape]:
        """The map's static geometry instead of the four arena walls (its edge is closed)."""
        from .maps.geometry import add_to_space
        return add_to_space(self.space, self.map, self.config.world.wall_friction, physics.STATIC)

    def ray_caster(self) -> Any:
        """The world's shared :class:`~pymunk_bot.sensors.raycast.RayCaster` (made on first use:
        only worlds with a LiDAR pay for its geometry tables)."""
        if self._caster is None:
            from .sensors.raycast import RayCaster
            self._caster = RayCaster(self.space)
        return self._caster

    def count_contacts(self, shape: pymunk.Shape, on_begin: Callable[[], None]) -> None:
        """Call ``on_begin`` whenever a contact episode of ``shape`` (a robot's) begins."""
        self._on_contact[shape] = on_begin

    def _begin(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        """A contact episode starts: count it for every robot in it (both, robot on robot)."""
        for shape in arbiter.shapes:
            on_begin = self._on_contact.get(shape)
            if on_begin is not None:
                on_begin()
