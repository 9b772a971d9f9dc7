"""pymunk settings for SI units, collision types, and the substep count that prevents tunnelling."""
from __future__ import annotations

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


def new_space() -> pymunk.Space:
    """A top-down Space in SI units: no gravity, fixed solver settings, no threads."""
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    space.iterations = SOLVER_ITERATIONS
    space.collision_slop = COLLISION_SLOP
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
