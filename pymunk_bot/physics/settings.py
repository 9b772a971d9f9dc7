"""pymunk settings for SI units, collision types, and the substep count that prevents tunnelling."""
from __future__ import annotations

import atexit
import gc
import math

import pymunk

# Collision types: counting contact episodes per pair needs specific pairs (a handler on
# (ROBOT, None) fires twice for robot-robot contacts).
ROBOT = 1
STATIC = 2
MOVABLE = 3

GRAVITY = 9.81  # [m/s^2], only for the floor friction of movable obstacles
COLLISION_SLOP = 0.005  # [m]; pymunk's default 0.1 is tuned for pixels
SOLVER_ITERATIONS = 10
# A light crate squeezed between a robot and a wall is a chain of contacts with a large mass
# ratio; the solver needs more iterations to keep it from sinking into the wall (measured at
# 5 g of drive force: 30 keep the squeeze under 1 cm where 10 let 2.3 cm through).
PUSHING_ITERATIONS = 30
# Share of an overlap removed per 1/60 s. pymunk's default (10 %) let a robot that keeps pushing
# sink deeper; 30 % holds every measured contact within 1 cm without visible jitter.
OVERLAP_CORRECTION = 0.3


# Copies of one scenario sharing a Space (pymunk_bot.engine.replicas) keep apart by category bits:
# copy r's moving shapes are in category 1 << r and collide with, and are seen by, no other copy's.
MAX_REPLICAS = 16
_REPLICA_BITS = (1 << MAX_REPLICAS) - 1


def replica_filter(replica: int, group: int = 0) -> pymunk.ShapeFilter:
    """The shape filter of a moving shape of copy ``replica`` (a robot's has its ``group``):
    it meets static shapes and its own copy's, and its queries see just those."""
    if not 0 <= replica < MAX_REPLICAS:
        raise ValueError(f"replica must be in [0, {MAX_REPLICAS}) (got {replica})")
    own = 1 << replica
    return pymunk.ShapeFilter(group=group, categories=own,
                              mask=pymunk.ShapeFilter.ALL_MASKS() ^ (_REPLICA_BITS ^ own))


# pymunk frees a Body or Space through Python callbacks (cffi ``extern "Python"``), which stop
# working while the interpreter shuts down. A run left in a reference cycle at exit (a module
# global after a server thread ran) was collected then, and the exit crashed with SIGSEGV or
# SIGBUS. At exit every object still tracked is frozen out of the last collections: the OS
# takes the memory back instead (tests/ros2/test_rosbridge.py has the script that crashed).
atexit.register(gc.freeze)


def new_space(pushable: bool = False) -> pymunk.Space:
    """A top-down Space in SI units: no gravity, fixed solver settings, no threads.

    ``pushable``: the world has bodies robots can push (more solver iterations)."""
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    space.iterations = PUSHING_ITERATIONS if pushable else SOLVER_ITERATIONS
    space.collision_slop = COLLISION_SLOP
    space.collision_bias = (1.0 - OVERLAP_CORRECTION) ** 60
    return space


def ground_friction(space: pymunk.Space, body: pymunk.Body, mu: float) -> None:
    """Coulomb floor friction for a top-down body: a velocity-only pivot and gear to the ground.

    With max_bias = 0 the joints only remove velocity, with at most mu*m*g of force (and the
    matching torque about the centre), so a pushed crate slides and then stops.
    """
    force = mu * body.mass * GRAVITY
    pivot = pymunk.PivotJoint(space.static_body, body, (0, 0), (0, 0))
    pivot.max_bias = 0.0
    pivot.max_force = force
    gear = pymunk.GearJoint(space.static_body, body, 0.0, 1.0)
    gear.max_bias = 0.0
    gear.max_force = force * math.sqrt(body.moment / body.mass)  # lever: radius of gyration
    space.add(pivot, gear)
