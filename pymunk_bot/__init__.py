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
    from typing import Any

    from pymunk_bot.robots.command import Command
    from pymunk_bot.config import ScenarioConfig, load_scenario
    from pymunk_bot.config.errors import ScenarioError
    from pymunk_bot.robots.robot import Robot
    from pymunk_bot.engine.batch import Batch
    from pymunk_bot.engine.replicas import Replicas
    from pymunk_bot.engine.simulation import Simulation

_EXPORTS = {"Command": "robots.command", "Robot": "robots.robot", "ScenarioConfig": "config",
            "ScenarioError": "config.errors", "Simulation": "engine.simulation",
            "Replicas": "engine.replicas", "Batch": "engine.batch", "load_scenario": "config"}

# Modules that moved when the package took its layout by concept (docs/architecture.md): the
# old import paths keep working, with a DeprecationWarning naming the new one.
_MOVED = {
    'arcs': 'geometry.arcs',
    'batch': 'engine.batch',
    'build': 'engine.build',
    'command': 'robots.command',
    'drives': 'robots.drives',
    'entry': 'cli.entry',
    'errors': 'config.errors',
    'events': 'engine.events',
    'expectations': 'outcomes.expectations',
    'extras': 'config.extras',
    'fleet_rows': 'robots.progress',
    'footprint': 'geometry.footprint',
    'metrics': 'outcomes.metrics',
    'navmetrics': 'outcomes.navigation',
    'observation_rows': 'policy.observation_rows',
    'observing': 'engine.observing',
    'obstacles': 'physics.obstacles',
    'plots': 'viewer.plots',
    'plots_localization': 'viewer.plots_localization',
    'policy_file': 'policy.files',
    'policy_io': 'policy.io',
    'propulsion': 'physics.propulsion',
    'pytest_plugin': 'cli.pytest_plugin',
    'readings': 'robots.readings',
    'registry': 'config.registry',
    'replicas': 'engine.replicas',
    'results': 'outcomes.results',
    'robot': 'robots.robot',
    'runlog': 'outcomes.runlog',
    'scenario_tests': 'cli.scenario_tests',
    'sim': 'engine.simulation',
    'stacking': 'robots.stacking',
    'steering': 'physics.steering',
    'substep_gate': 'physics.substeps',
    'substep_split': 'physics.apart',
    'world': 'physics.world',
}

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


class _MovedModules:
    """Finds a module under its old name (``pymunk_bot.sim``) as the module it became
    (``pymunk_bot.engine.simulation``): one module object under both names."""

    @staticmethod
    def _new_name(fullname: str) -> str | None:
        prefix = __name__ + "."
        if not fullname.startswith(prefix):
            return None
        old = fullname[len(prefix):]
        head, _, rest = old.partition(".")
        new = _MOVED.get(old) or (_MOVED.get(head) and f"{_MOVED[head]}.{rest}")
        return f"{prefix}{new}" if new else None

    def find_spec(self, fullname: str, path: Any, target: Any = None) -> Any:
        """A spec loading the moved module, for an old name; None for any other."""
        if self._new_name(fullname) is None:
            return None
        import importlib.util

        return importlib.util.spec_from_loader(fullname, self)  # type: ignore[arg-type]

    def create_module(self, spec: Any) -> Any:
        """The module under its new name (imported now if it was not)."""
        import importlib
        import warnings

        new = self._new_name(spec.name)
        warnings.warn(f"{spec.name} is now {new}", DeprecationWarning, stacklevel=3)
        return importlib.import_module(str(new))

    def exec_module(self, module: Any) -> None:
        """The module ran under its new name already."""


def _install_moved_modules() -> None:
    import sys

    if not any(isinstance(f, _MovedModules) for f in sys.meta_path):
        sys.meta_path.append(_MovedModules())


_install_moved_modules()

del TYPE_CHECKING, annotations  # helpers of this file, not part of the package's namespace
