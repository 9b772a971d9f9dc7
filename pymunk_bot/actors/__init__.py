"""Things that move by themselves: scripted obstacles and pedestrians.

Each actor has ``before_step(time, dt)``, called by the simulation before the physics of every
tick (see ``World.actors``). :func:`make_actors` builds them in a fixed order (scripted
obstacles in file order, then the crowd), so runs are deterministic.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from pymunk_bot.actors.motion import PathScript, ScriptedMotion
from pymunk_bot.actors.pedestrians import Crowd, make_crowd

__all__ = ["Crowd", "PathScript", "ScriptedMotion", "make_actors"]


def make_actors(world: Any, robots: Sequence, rng: np.random.Generator) -> list[Any]:
    """Every actor of a built world; ``rng`` is the run's child generator for them."""
    actors: list[Any] = [ScriptedMotion(o) for o in world.obstacles
                         if getattr(o.config, "motion", None) is not None]
    crowd = make_crowd(world, robots, rng)
    if crowd is not None:
        actors.append(crowd)
    return actors
