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
of those ticks ends, at their top speeds (or faster, if they go faster now). The substep gate
answers that (``SubstepGate.unreachable``: the one planner of when bodies can touch, asked
here per robot and over a few ticks, there for the whole Space and the coming tick):

- two moving bodies: the distance between their origins less both reaches, over both speeds
  (a k-d tree finds the pairs that are near);
- a fixed shape: the distance to the nearest one (pymunk's point query, asked only where the
  gate's cells of the fixed world, physics/static_cells.py, cannot rule one out) less the
  robot's reach. The fixed world cannot change while robots step apart (below), so the cells
  stand; a robot that a teleport put inside a fixed shape (a negative distance) stays.

It plans only for fleets of ``SPLIT_FROM`` robots or more (physics/world.py: only their
worlds have a Space apart), in a world of its own
(copies of a scenario share one Space), and only while nobody holds the world's Space
(``World.space``): a crowd, a metric that queries the world, or a user's code that asks for
the Space bring every robot back for the rest of the run, so whatever looks at the world sees
all of it. LiDARs do not: the world's ray caster reads both Spaces, and where it does, a
robot's shapes go apart with it (``sensors/raycast/spaces.py``). A teleport brings them back
too, and the next tick plans anew.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
import pymunk

from pymunk_bot.physics.propulsion import Propulsion
from pymunk_bot.physics.substeps import SubstepGate
from pymunk_bot.physics.world import World

PLAN_TICKS = 4  # ticks between two decisions


class RobotsApart:
    """Which robots step apart (see the module docstring), from the contact Space to
    ``apart``. ``robots``: the fleet's bodies in Propulsion's order, the first movers of
    ``gate`` (the contact Space's substep gate, which tells who can be reached); ``dt``: the
    tick [s]."""

    def __init__(self, apart: pymunk.Space, robots: Sequence[pymunk.Body], gate: SubstepGate,
                 dt: float) -> None:
        self.dt = dt
        if all(b.center_of_gravity == (0, 0) for b in robots):
            # Each robot's joints pull through its centre of gravity (the pivot's anchor is
            # its origin): the pivot moves, the gear turns, neither disturbs the other, and
            # one solver iteration solves both (measured: 10,000 robots for 2.5 s, positions
            # within 4e-15 m of ten iterations'). Nothing else is in that Space.
            apart.iterations = 1
        self.n = len(robots)
        if [m.body for m in gate.movers[:self.n]] != list(robots):
            raise ValueError("the gate's first movers must be the fleet's robots, in order")
        self._gate = gate
        self.apart = np.zeros(self.n, dtype=bool)  # stepping apart in this tick
        self._ticks_left = 0  # ticks until the next decision
        self.layout = -1  # World.layout after this planner's last move (-1: none yet)

    @property
    def crowded(self) -> bool:
        """Whether the contact Space holds moving bodies besides robots (each tick: substeps)."""
        return len(self._gate.movers) > self.n

    def reset(self, disturbed: bool = False) -> None:
        """Every robot back in the contact Space: the next tick decides anew, with the fixed
        world looked at again (``disturbed``: bodies were moved outside the physics, a fixed
        one may be among them)."""
        self.apart = np.zeros(self.n, dtype=bool)
        self._ticks_left = 0
        fixed = self._gate.fixed
        if disturbed:
            fixed.forget()
        fixed.refresh()

    def next_apart(self) -> np.ndarray:
        """Which robots step apart in the next tick."""
        if self._ticks_left > 1:
            self._ticks_left -= 1
            return self.apart
        self._ticks_left = PLAN_TICKS
        return self._gate.unreachable((PLAN_TICKS + 1) * self.dt)[:self.n]

    def settle(self, world: World, propulsion: Propulsion, apart: np.ndarray) -> None:
        """After a tick: the robots that step apart in the next one (``apart``) move there,
        the others back."""
        went = np.flatnonzero(apart & ~self.apart).tolist()
        back = np.flatnonzero(self.apart & ~apart).tolist()
        if went or back:
            bodies, controls = propulsion.bodies, propulsion.controls
            world.move_back([(bodies[k], controls[k]) for k in back])
            world.move_apart([(bodies[k], controls[k]) for k in went])
        self.apart = apart
        self.layout = world.layout
