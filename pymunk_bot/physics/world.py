"""The physical world: one pymunk Space with the arena, obstacles and robot bodies, and the
contact bookkeeping (in large fleets, a second Space where robots nothing can reach step
apart: physics/apart.py). Build order is fixed (arena, obstacles, robots) for determinism."""
from __future__ import annotations

from typing import Any, Callable

import numpy as np
import pymunk

from pymunk_bot.physics import settings as physics
from pymunk_bot.config.schema import ScenarioConfig
from pymunk_bot.config.substeps import ARENA_WALL_THICKNESS, SubstepNeed, substep_need
from pymunk_bot.physics.obstacles import Obstacle
from pymunk_bot.plugins import obstacles as obstacle_kinds


# Scenarios with fewer robots step in one Space: below it, deciding which robots step apart
# and the second Space's step cost about what the substeps they save do (the swarm of
# bench/fleet.py, 6 s from 0.5 s, CPU time, one run: 1000 robots 12.42x real time apart
# against 12.45x in one Space, 2000 robots 5.97x against 4.54x, 5000 robots 2.05x against
# 1.21x; 100 robots, 3 s: 82x against 109x), and their casts would ask two Spaces.
SPLIT_FROM = 2000


class World:
    """Owns the Space. ``actors`` move things before every tick (moving obstacles, pedestrians):
    objects with ``before_step(time, dt)``.

    Copies of one scenario can share a Space (:mod:`pymunk_bot.engine.replicas`): :meth:`ground`
    builds the arena and the fixed obstacles once, and ``World(config, ground, replica)`` adds
    one copy's movable obstacles, kept apart from the other copies' moving shapes."""

    def __init__(self, config: ScenarioConfig, ground: "World | None" = None,
                 replica: int | None = None, *, movables: bool = True) -> None:
        self.config = config
        self.width, self.height = config.world.arena
        # (x0, y0, x1, y1) [m]: [0, width] x [0, height], or a map's extent in the map's frame
        self.extent: tuple[float, float, float, float] = config.world.extent
        self.replica = replica
        self._own: list[Obstacle] = []  # the movable obstacles this world added to the space
        if ground is None:
            self._space = physics.new_space(
                pushable=any(getattr(o, "movable", False) for o in config.obstacles))
            self.map = config.world.map_geometry()  # a MapGeometry, or None
            self.arena_shapes = self._build_arena() if self.map is None else self._build_map()
            named = config.world.substeps
            # What the substep count depends on (None: the scenario names the count).
            self.need: SubstepNeed | None = None
            if isinstance(named, int):
                self.substeps = named
            else:
                self.need = substep_need(config)
                self.substeps = self.need.full
            self._caster: Any = None
            self._on_contact: dict[pymunk.Shape, Callable[[], None]] = {}
            # Robot shapes whose contact impulses someone reads (navmetrics); empty: no cost.
            self._on_solved: dict[pymunk.Shape, list[Callable[[pymunk.Arbiter], None]]] = {}
            # Robots that nothing can reach within the coming ticks step there, once a tick,
            # their bodies and joints alone (physics/apart.py); anyone who asks for the
            # world's Space gets them back. Copies on a shared ground never step apart, nor
            # fleets under SPLIT_FROM robots.
            self.apart_space: pymunk.Space | None = None
            if replica is None and movables and len(config.robots) >= SPLIT_FROM:
                self.apart_space = physics.new_space()
                self.apart_space.iterations = self._space.iterations  # the joints solved alike
            for other in (physics.STATIC, physics.MOVABLE, physics.ROBOT):
                self._space.on_collision(physics.ROBOT, other, begin=self._begin)
            self._fixed: dict[int, Obstacle] = {}
        else:  # a copy on a shared ground: its space, fixed geometry, caster and contacts
            self._space, self.map = ground.contact_space, ground.map
            self.arena_shapes = ground.arena_shapes
            self.substeps, self.need = ground.substeps, ground.need
            self._on_contact, self._on_solved, self._fixed = ground.shared_tables()
            self._ground = ground
            self.apart_space = None
        self.obstacles: list[Obstacle] = []
        for index, o in enumerate(config.obstacles):  # in the file's order, for determinism
            fixed = self._fixed.get(index)
            if fixed is not None:  # a copy: the ground's
                self.obstacles.append(fixed)
                continue
            obstacle = obstacle_kinds.get(o.type)(self._space, o)
            if obstacle.movable:
                if not movables:  # the ground holds no moving body: each copy adds its own
                    self._space.remove(*obstacle.body.constraints, *obstacle.shapes, obstacle.body)
                    continue
                if replica is not None:
                    for shape in obstacle.shapes:
                        shape.filter = physics.replica_filter(replica)
                self._own.append(obstacle)
            elif not movables:
                self._fixed[index] = obstacle
            self.obstacles.append(obstacle)
        self.actors: list[Any] = []
        self.time = 0.0  # simulated time [s], kept by the simulation
        # Substeps taken only where a contact can start (world.substeps: adaptive).
        self.adaptive = config.world.substeps in (None, "adaptive")
        # [s] the pymunk step the bodies' velocities now move in (the next tick's first), kept
        # by the simulation: dt / substeps, unless the substeps are adaptive.
        self.substep = config.world.dt / self.substeps
        self._disturbed = False  # bodies were moved outside the physics (see disturb)
        self.dt = config.world.dt  # [s]
        # Robots (body, control body) stepping in apart_space now, in the order they went.
        self._apart: dict[pymunk.Body, pymunk.Body] = {}
        self.whole = False  # someone holds the world's Space: every robot stays in it
        # Counts the times someone was handed the Space (who may add or remove fixed shapes)
        # or disturbed the world: the substep gate's cells of the fixed world look again then.
        self.fixed_version = 0
        self.layout = 0  # counts the moves between the two Spaces (batch readers re-index)

    def shared_tables(self) -> tuple[dict, dict, dict]:
        """What copies on this ground share with it: the contact callbacks by shape, those of
        solved contacts, and the fixed obstacles by their index in the scenario."""
        return self._on_contact, self._on_solved, self._fixed

    @property
    def space(self) -> pymunk.Space:
        """The world's pymunk Space, with every body in it. Robots that nothing can reach
        within the coming ticks may step in a Space of their own (:mod:`pymunk_bot.physics.apart`)
        while nobody looks; asking for this brings them back, for the rest of the run (a
        crowd, a metric or a user's query sees the whole world; a LiDAR's caster reads both
        Spaces instead: :meth:`ray_caster`)."""
        self.whole = True
        self.gather()
        self.touched()
        return self._space

    @property
    def contact_space(self) -> pymunk.Space:
        """The Space where contacts happen: every body and shape but those of the robots
        stepping apart (the engine's own view, which leaves them apart)."""
        return self._space

    @property
    def can_split(self) -> bool:
        """Whether robots may step apart: a world of its own that nobody holds the Space of."""
        return self.apart_space is not None and not self.whole

    def move_apart(self, robots: list[tuple[pymunk.Body, pymunk.Body]]) -> None:
        """Move these robots (body, control body) and their joints to the apart Space, and
        take their shapes out of the contact Space."""
        if robots:
            assert self.apart_space is not None
            shapes = [shape for body, _ in robots for shape in body.shapes]
            # Nothing can touch them there, and the contact Space need not sort their shapes
            # each substep. Their shapes leave every Space (whoever queries the world gathers
            # first), or, where LiDARs look, go with them (the caster reads both Spaces).
            self._space.remove(*shapes)
            _move(self._space, self.apart_space, robots)
            if self._caster is not None:
                self.apart_space.add(*shapes)
            self._apart.update(robots)
            self.layout += 1

    def move_back(self, robots: list[tuple[pymunk.Body, pymunk.Body]]) -> None:
        """Move these robots from the apart Space back to the contact Space, shapes too."""
        if robots:
            assert self.apart_space is not None
            shapes = [shape for body, _ in robots for shape in body.shapes]
            if self._caster is not None:
                self.apart_space.remove(*shapes)
            _move(self.apart_space, self._space, robots)
            self._space.add(*shapes)
            for body, _ in robots:
                del self._apart[body]
            self.layout += 1

    def gather(self) -> None:
        """Every robot stepping apart back into the contact Space."""
        self.move_back(list(self._apart.items()))

    def substep_for(self, body: pymunk.Body) -> float:
        """[s] the pymunk step ``body``'s velocity now moves it in: a tick for a robot
        stepping apart, else :attr:`substep`."""
        return self.dt if body in self._apart else self.substep

    @classmethod
    def ground(cls, config: ScenarioConfig) -> "World":
        """The arena and fixed obstacles of ``config`` alone: what copies of it share."""
        return cls(config, movables=False)

    def shape_filter(self, group: int) -> pymunk.ShapeFilter:
        """The filter of a robot's shapes: its ``group`` keeps its LiDAR off its own body (and,
        in a copy on a shared ground, its category keeps it apart from the other copies)."""
        if self.replica is None:
            return pymunk.ShapeFilter(group=group)
        return physics.replica_filter(self.replica, group)

    def disturb(self) -> None:
        """Bodies were moved outside the physics (a teleport, or a fixed obstacle's body moved
        by hand): adaptive substeps look again before a tick may skip them (on a shared
        ground, for every copy)."""
        self._disturbed = True
        self.touched()
        ground = getattr(self, "_ground", None)
        if ground is not None:
            ground.disturb()

    def touched(self) -> None:
        """The fixed world may have changed (the Space was handed out, or bodies moved by
        hand): ``fixed_version`` counts it, on a shared ground for every copy."""
        self.fixed_version += 1
        ground = getattr(self, "_ground", None)
        if ground is not None:
            ground.touched()

    def random_point(self, rng: np.random.Generator, margin: float) -> tuple[float, float]:
        """A point [m] drawn uniformly from the arena's open area: a grid map's free cells,
        else the arena less ``margin`` [m] from its edges (what is there is the caller's to
        test: obstacles, a vector map's painted areas)."""
        if self.map is not None:
            point = self.map.random_free_point(rng)
            if point is not None:
                return point
        x0, y0, x1, y1 = self.extent
        return (float(rng.uniform(x0 + margin, x1 - margin)),
                float(rng.uniform(y0 + margin, y1 - margin)))

    def take_disturbed(self) -> bool:
        """Whether :meth:`disturb` was called since the last time this was asked."""
        disturbed, self._disturbed = self._disturbed, False
        return disturbed

    def retire(self, bodies: list[pymunk.Body]) -> None:
        """Take this copy's movable obstacles and the given bodies (its robots' bodies and
        control bodies), with their shapes and joints, out of the shared space."""
        gone: dict[Any, None] = {}  # ordered and unique: two bodies may share a joint
        for body in [o.body for o in self._own] + bodies:
            gone.update(dict.fromkeys(body.constraints))
            for shape in body.shapes:
                self._on_contact.pop(shape, None)
                self._on_solved.pop(shape, None)
                gone[shape] = None
            gone[body] = None
        self._space.remove(*gone)
        self._own.clear()
        # Chipmunk fills a removed joint's slot with its last one, which can swap two joints
        # of another copy; its solver applies joints in that order, so put every joint back
        # in the order it was added (each copy's own build order, as in a space of its own).
        kept = list(self._space.constraints)
        self._space.remove(*kept)
        self._space.add(*kept)

    def _build_arena(self) -> list[pymunk.Shape]:
        w, h, t = self.width, self.height, ARENA_WALL_THICKNESS
        boxes = [(-t, -t, 0, h + t), (w, -t, w + t, h + t), (0, -t, w, 0), (0, h, w, h + t)]
        shapes: list[pymunk.Shape] = []
        for x0, y0, x1, y1 in boxes:
            shape = pymunk.Poly(self._space.static_body, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
            shape.friction = self.config.world.wall_friction
            shape.collision_type = physics.STATIC
            shapes.append(shape)
        self._space.add(*shapes)
        return shapes

    def _build_map(self) -> list[pymunk.Shape]:
        """The map's static geometry instead of the four arena walls (its edge is closed)."""
        from pymunk_bot.maps.outlines import add_to_space
        return add_to_space(self._space, self.map, self.config.world.wall_friction, physics.STATIC)

    def ray_caster(self) -> Any:
        """The world's shared :class:`~pymunk_bot.sensors.raycast.RayCaster` (made on first use:
        only worlds with a LiDAR pay for its geometry tables; one per space). Where robots may
        step apart it casts against both Spaces, and from then on their shapes go with them."""
        ground = getattr(self, "_ground", None)
        if ground is not None:
            return ground.ray_caster()
        if self._caster is None:
            from pymunk_bot.sensors.raycast import RayCaster, Spaces
            self.gather()  # none apart while the shapes' rule changes
            self._caster = RayCaster(self._space if self.apart_space is None
                                     else Spaces((self._space, self.apart_space)))
        return self._caster

    def count_contacts(self, shape: pymunk.Shape, on_begin: Callable[[], None]) -> None:
        """Call ``on_begin`` whenever a contact episode of ``shape`` (a robot's) begins."""
        self._on_contact[shape] = on_begin

    def watch_contacts(self, shape: pymunk.Shape,
                       on_solved: Callable[[pymunk.Arbiter], None]) -> None:
        """Call ``on_solved(arbiter)`` after every pymunk step in which ``shape`` (a robot's)
        touches something, once its impulse is solved (``arbiter.total_impulse``). Worlds where
        nobody asks never pay for a post-solve callback."""
        if not self._on_solved:
            for other in (physics.STATIC, physics.MOVABLE, physics.ROBOT):
                self._space.on_collision(physics.ROBOT, other, begin=self._begin,
                                        post_solve=self._solved)
        self._on_solved.setdefault(shape, []).append(on_solved)

    def _solved(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        for shape in arbiter.shapes:
            for on_solved in self._on_solved.get(shape, ()):
                on_solved(arbiter)

    def _begin(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        """A contact episode starts: count it for every robot in it (both, robot on robot)."""
        for shape in arbiter.shapes:
            on_begin = self._on_contact.get(shape)
            if on_begin is not None:
                on_begin()


def _move(source: pymunk.Space, target: pymunk.Space,
          robots: list[tuple[pymunk.Body, pymunk.Body]]) -> None:
    """Robots (body, control body) with their joints from ``source`` to ``target``, in their
    order (joints after bodies, as when built)."""
    parts: list[pymunk.Body | pymunk.Constraint] = []
    for body, control in robots:
        parts += [body, control, *control.constraints]
    source.remove(*parts)
    target.add(*parts)
