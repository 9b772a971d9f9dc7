"""pymunk-bot: a fast, physically honest 2D mobile-robot simulator built on pymunk.

>>> import pymunk_bot as pb
>>> sim = pb.Simulation.from_file(None)   # the built-in default scenario
>>> sim.run(1.0)
>>> round(sim.time, 6)
1.0

The names below load on first use, so ``import pymunk_bot`` costs little more than its
dependencies (the scenario schema is built when the first scenario is read).
"""
from __future__ import annotations

TYPE_CHECKING = False  # as typing's (mypy knows the name), without importing typing at start-up
if TYPE_CHECKING:
    from .command import Command
    from .config import ScenarioConfig, load_scenario
    from .errors import ScenarioError
    from .robot import Robot
    from .sim import Simulation

_EXPORTS = {"Command": "command", "Robot": "robot", "ScenarioConfig": "config",
            "ScenarioError": "errors", "Simulation": "sim", "load_scenario": "config"}

__all__ = sorted(_EXPORTS)
__version__ = "0.2.0"


def __getattr__(name: str) -> object:
    if name in _EXPORTS:
        import importlib

        value = getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """The public names (and the submodules imported so far), not this file's helpers."""
    import types

    modules = [k for k, v in globals().items() if isinstance(v, types.ModuleType)]
    return sorted({*__all__, "__version__", "__doc__", *modules})


del TYPE_CHECKING, annotations  # helpers of this file, not part of the package's namespace
