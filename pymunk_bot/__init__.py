"""pymunk-bot: a fast, physically honest 2D mobile-robot simulator built on pymunk.

>>> import pymunk_bot as pb
>>> sim = pb.Simulation.from_file(None)   # the built-in default scenario
>>> sim.run(1.0)
>>> round(sim.time, 6)
1.0
"""
from .config import ScenarioConfig, load_scenario
from .errors import ScenarioError
from .robot import Robot
from .sim import Simulation

__all__ = ["Robot", "ScenarioConfig", "ScenarioError", "Simulation", "load_scenario"]
__version__ = "0.1.0"
