"""How many pymunk substeps per dt a scenario needs so that nothing tunnels (pure geometry)."""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from pymunk_bot.geometry import plane as geo
from pymunk_bot.config.outlines import is_round, obstacle_outline, polygon_of
from pymunk_bot.config.schema import ScenarioConfig

ARENA_WALL_THICKNESS = 1.0  # [m]; thick so that nothing can tunnel out of the arena


def substeps_against_tunnelling(dt: float, max_speed: float, robot_radius: float,
                                thinnest_half_width: float, safety: float = 2.0) -> int:
    """Smallest substep count so that nothing moves more than a fraction of a collision depth.

    A disc of radius r passes through a wall of half-width w once its centre crosses the wall's
    middle within one substep, i.e. when ``v * dt / k > r + w``. We keep a factor ``safety`` below.
    """
    depth = robot_radius + thinnest_half_width
    if not depth > 0:  # the checks refuse shapes without width; this guards other callers
        raise ValueError(f"collision depth must be > 0 (radius {robot_radius:g} m + half width "
                         f"{thinnest_half_width:g} m)")
    return max(1, math.ceil(max_speed * dt * safety / depth))


def half_width(obstacle) -> float:
    """Half the thinnest extent of an obstacle: what a fast robot must not skip over."""
    if is_round(obstacle):
        return obstacle.radius
    return geo.thinness(polygon_of(obstacle)) / 2.0


# [m] the most two bodies may move into each other in one substep: contact starts with at most
# this overlap, which the solver then removes (measured: every contact stays within 1 cm).
CONTACT_STEP = 0.008
# [m] the same where robots push bodies: a light crate squeezed against a wall sinks a little
# further while the solver settles (measured: 10.6 mm once in 1000 trials at 8 mm steps).
PUSHING_CONTACT_STEP = 0.006


def substeps_against_overlap(dt: float, closing_speed: float, step: float = CONTACT_STEP) -> int:
    """Smallest substep count so that bodies closing at ``closing_speed`` [m/s] first touch
    with at most ``step`` [m] of overlap."""
    return max(1, math.ceil(closing_speed * dt / step))


def shove_factor(mass_ratio: float) -> float:
    """How many times its substep's travel a light body shoved into a wall by one ``mass_ratio``
    times heavier sinks in. The solver's iterations pass the pusher's impulse through the light
    body a little at a time, so the squeeze grows with the ratio (measured with
    tests/trust/test_physics_inputs.py's crate trials: about sqrt(ratio) / 6 from 30:1 to 3000:1
    at 0.5 .. 3 m/s; 1 below 25:1)."""
    return max(1.0, math.sqrt(mass_ratio) / 5.0)


@dataclass(frozen=True)
class Shove:
    """The hardest push in a scenario: the lightest movable obstacle shoved by the heaviest body
    that can push it, and the substeps that keep it out of a wall."""

    obstacle: int  # index in ``scenario.obstacles``
    mass: float  # [kg] of that obstacle
    pusher_mass: float  # [kg]
    speed: float  # [m/s] the fastest it can be shoved
    substeps: int
    squeeze: float  # how many times its substep's travel it sinks into a wall (shove_factor)


def hardest_shove(scenario: ScenarioConfig) -> Shove | None:
    """The push that needs most substeps, or None without movable obstacles."""
    movable = [(i, o) for i, o in enumerate(scenario.obstacles) if getattr(o, "movable", False)]
    if not movable:
        return None
    walkers = [o for o in scenario.obstacles if getattr(o, "type", "") == "pedestrian"]
    heaviest = max([r.mass for r in scenario.robots] + [o.mass for _, o in movable]
                   + [o.mass for o in walkers])
    speed = max([r.top_speed() for r in scenario.robots] + [mover_speed(o) for o in walkers])
    index, lightest = min(movable, key=lambda item: item[1].mass)
    factor = shove_factor(heaviest / lightest.mass)
    needed = substeps_against_overlap(scenario.world.dt, speed * factor, PUSHING_CONTACT_STEP)
    return Shove(index, lightest.mass, heaviest, speed, needed, factor)


def map_half_widths(scenario: ScenarioConfig) -> list[float]:
    """Half widths of a ``world.map``'s shapes: a convex piece's thinnest extent, and a
    segment's radius (0 for the zero-width chains around free space: then only the robot's
    own radius keeps it from crossing, so the depth is the radius alone)."""
    geometry = scenario.world.map_geometry()
    if geometry is None:
        return []
    widths = (geo.thinnesses(geometry.polygons) / 2.0).tolist()
    if len(geometry.segment_radius):
        widths.append(float(geometry.segment_radius.min()))
    return widths


def mover_speed(obstacle) -> float:
    """Fastest a scripted obstacle or a pedestrian moves [m/s] (0 for the others)."""
    if getattr(obstacle, "type", "") == "pedestrian":
        from pymunk_bot.config.motion import MAX_SPEED_FACTOR
        return MAX_SPEED_FACTOR * (obstacle.speed + 3.0 * obstacle.speed_std)
    motion = getattr(obstacle, "motion", None)
    if motion is None:
        return 0.0
    reach = 0.0
    if motion.angular_speed:
        outline = obstacle_outline(obstacle)
        if outline is not None:
            reach = float(np.hypot(*(outline - outline.mean(axis=0)).T).max())
    return motion.speed + abs(motion.angular_speed) * reach


@dataclass(frozen=True)
class SubstepNeed:
    """What a scenario's substep count depends on, but for how fast its robots go: the count
    for any speed bound, so that ticks whose robots go slower than their drives allow can
    take fewer (:mod:`pymunk_bot.physics.substeps`). See :func:`required_substeps`."""

    dt: float  # [s] the tick
    top_speed: float  # [m/s] the fastest robot's top speed
    several: bool  # more than one robot: two can close on each other head-on
    smallest: float  # [m] half the thinnest extent of anything that moves
    thinnest: float  # [m] half the thinnest extent of anything fixed
    # (speed [m/s], half width [m]) of every scripted obstacle and pedestrian that moves
    scripted: tuple[tuple[float, float], ...]
    step: float  # [m] the deepest a contact may start (less where robots push bodies)
    walker_speed: float  # [m/s] the fastest pedestrian: it pushes crates too (0: none)
    shove: Shove | None  # the hardest push (None: nothing to push)

    @property
    def full(self) -> int:
        """Substeps with every robot at its top speed: the scenario's count."""
        return self.count(self.top_speed)

    @functools.cached_property
    def limits(self) -> tuple[float, ...]:
        """The highest robot speeds [m/s] that 1, 2, ... ``full - 1`` substeps hold (each found
        by bisection, from below): a table for ticks that cannot afford :meth:`count` (found
        once: copies of a scenario rebuilt among others share it)."""
        found = []
        for k in range(1, self.full):
            low, high = 0.0, self.top_speed
            if self.count(low) > k:
                found.append(-math.inf)  # not even at rest (scripted movers need more)
                continue
            for _ in range(60):
                middle = 0.5 * (low + high)
                low, high = (middle, high) if self.count(middle) <= k else (low, middle)
            found.append(low)
        return tuple(found)

    def count(self, fastest: float) -> int:
        """Substeps while no robot goes faster than ``fastest`` [m/s] (any footprint point)."""
        dt, smallest = self.dt, self.smallest
        closing = 2 * fastest if self.several else fastest  # two robots head-on
        closing = max([closing] + [fastest + speed for speed, _ in self.scripted])
        substeps = max(substeps_against_tunnelling(dt, fastest, smallest, self.thinnest),
                       substeps_against_tunnelling(dt, closing, smallest, smallest),
                       substeps_against_overlap(dt, closing, self.step))
        if self.shove is not None:
            pushed = max(fastest, self.walker_speed) * self.shove.squeeze
            substeps = max(substeps, substeps_against_overlap(dt, pushed, PUSHING_CONTACT_STEP))
        for speed, width in self.scripted:
            substeps = max(substeps, substeps_against_tunnelling(dt, fastest + speed, smallest,
                                                                 width))
        return substeps


def substep_need(scenario: ScenarioConfig) -> SubstepNeed:
    """The scenario's :class:`SubstepNeed`."""
    from pymunk_bot.geometry.footprint import of_robot
    robots, obstacles = scenario.robots, scenario.obstacles
    movable = [o for o in obstacles if getattr(o, "movable", False)]
    smallest = min([of_robot(r).half_thickness for r in robots] + [half_width(o) for o in movable])
    thinnest = min([ARENA_WALL_THICKNESS / 2] + [half_width(o) for o in obstacles
                                                 if not getattr(o, "movable", False)]
                   + map_half_widths(scenario))
    scripted = tuple((speed, half_width(o)) for o in obstacles
                     if (speed := mover_speed(o)) > 0)
    walkers = [mover_speed(o) for o in obstacles if getattr(o, "type", "") == "pedestrian"]
    return SubstepNeed(scenario.world.dt, max(r.top_speed() for r in robots), len(robots) > 1,
                       smallest, thinnest, scripted,
                       PUSHING_CONTACT_STEP if movable else CONTACT_STEP,
                       max(walkers, default=0.0), hardest_shove(scenario))


def required_substeps(scenario: ScenarioConfig) -> int:
    """Substeps so that nothing tunnels and no contact starts deeper than CONTACT_STEP.

    Everything that moves counts: robots (by their footprint's thinnest extent), the bodies they
    push (a pushed body moves no faster than its pusher, so the fastest robot bounds it; the
    smallest movable obstacle is what must not skip through the thinnest wall, and the lightest
    must not be squeezed into it by the heaviest pusher: :func:`hardest_shove`), and scripted
    movers and pedestrians closing on a robot."""
    return substep_need(scenario).full
