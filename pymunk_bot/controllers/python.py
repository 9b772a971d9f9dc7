"""A user's own controller, imported from ``class_path: 'package.module:ClassName'``.

The class follows the :class:`~pymunk_bot.controllers.Controller` protocol: it is built as
``ClassName(robot_spec, **params)`` and its ``compute(observation)`` returns (left, right) wheel
speeds [m/s] (or a :class:`~pymunk_bot.command.Command`, for any drive); ``rate`` [Hz], ``status`` and ``message`` are optional attributes.

Where the module is looked for: next to the scenario file, then in the folders above it, then
the current folder, then ``sys.path``. Validation only *finds* the module and reads its source
(no user code runs); the simulation imports it, with the found folder on ``sys.path`` only
for the import. A bug in the user's code (an exception in its import, constructor or
``compute``) is a :class:`~pymunk_bot.errors.ControllerError` carrying its traceback, not
bad input.
"""
from __future__ import annotations

import ast
import importlib
import importlib.machinery
import importlib.util
import inspect
import math
import os
import sys
from pathlib import Path

from ..config.controllers import PythonControllerConfig
from ..errors import ControllerError
from .base import Command, Controller, Observation, RobotSpec


def search_dirs(base_dir: str | Path | None) -> list[Path]:
    """The scenario's folder and those above it, then the current folder."""
    dirs = []
    if base_dir is not None:
        base = Path(base_dir).resolve()
        dirs += [base, *base.parents]
    dirs.append(Path(os.getcwd()))
    return dirs


def module_home(module_name: str, base_dir: str | Path | None) -> Path | None:
    """The first search folder holding the module's top-level package (None: use sys.path)."""
    top = module_name.split(".")[0]
    if top in sys.modules or top == "pymunk_bot":
        return None
    for directory in search_dirs(base_dir):
        if importlib.machinery.PathFinder.find_spec(top, [str(directory)]) is not None:
            return directory
    return None


def check_class_path(class_path: str, base_dir: str | Path | None = None) -> None:
    """Find the module and check the class without running user code; ValueError if wrong.

    Our own package is imported (it is not user code); a user's module is found on disk and
    its source parsed, which catches a missing class or one with no ``compute`` of its own.
    """
    module_name, _, attr = class_path.partition(":")
    if module_name.split(".")[0] == "pymunk_bot":
        import_class(class_path)
        return
    home = module_home(module_name, base_dir)
    origin = _find_source(module_name, home)
    if origin is None:
        raise ValueError(f"cannot import module '{module_name}': not found next to the scenario, "
                         "in the folders above it, the current folder or sys.path")
    if origin.suffix != ".py" or "." in attr:
        return  # compiled or nested: checked when the simulation imports it
    try:
        tree = ast.parse(origin.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, SyntaxError, ValueError) as exc:
        raise ValueError(f"cannot read '{origin}': {type(exc).__name__}: {exc}") from None
    _check_source(tree, module_name, attr, class_path)


def _find_source(module_name: str, home: Path | None) -> Path | None:
    """The file of a (dotted) module, found without importing it; None if absent."""
    parts = module_name.split(".")
    if home is None:
        try:
            spec = importlib.util.find_spec(parts[0])
        except (ImportError, ValueError):
            return None
    else:
        spec = importlib.machinery.PathFinder.find_spec(parts[0], [str(home)])
    for part in parts[1:]:
        if spec is None or not spec.submodule_search_locations:
            return None
        spec = importlib.machinery.PathFinder.find_spec(part, list(spec.submodule_search_locations))
    if spec is None:
        return None
    return Path(spec.origin) if spec.origin else Path(os.devnull)


def _check_source(tree: ast.Module, module_name: str, attr: str, class_path: str) -> None:
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == attr:
            own = {n.name for n in node.body if isinstance(n, (ast.FunctionDef,
                                                               ast.AsyncFunctionDef))}
            bases = {ast.unparse(b).rsplit(".", 1)[-1] for b in node.bases}
            if "compute" not in own and bases <= {"Controller", "object"}:
                raise ValueError(f"'{class_path}' has no compute(observation) method of its own")
            return
    bound = {t.id for n in tree.body if isinstance(n, (ast.Assign, ast.AnnAssign))
             for t in (n.targets if isinstance(n, ast.Assign) else [n.target])
             if isinstance(t, ast.Name)}
    bound |= {(a.asname or a.name).split(".")[0] for n in tree.body
              if isinstance(n, (ast.Import, ast.ImportFrom)) for a in n.names}
    if attr not in bound and not any(isinstance(n, (ast.If, ast.Try)) for n in tree.body):
        raise ValueError(f"module '{module_name}' has no attribute '{attr}'")


def import_class(class_path: str, base_dir: str | Path | None = None) -> type:
    """Import and return the class named by 'package.module:ClassName'.

    ValueError (bad input) when the module or class cannot be found or the class cannot be a
    controller; ControllerError when the user's module raises while importing.
    """
    obj = import_module_attr(class_path, base_dir)
    if not inspect.isclass(obj):
        raise ValueError(f"'{class_path}' is not a class")
    compute = getattr(obj, "compute", None)
    if not callable(compute) or compute is Controller.compute:
        raise ValueError(f"'{class_path}' has no compute(observation) method of its own")
    return obj


def import_module_attr(class_path: str, base_dir: str | Path | None = None) -> object:
    """The object named by 'package.module:Name', the module looked for as ``import_class``
    says; ValueError when it cannot be found, ControllerError when the module raises."""
    module_name, _, attr = class_path.partition(":")
    home = module_home(module_name, base_dir)
    if home is not None:
        sys.path.insert(0, str(home))  # for this import only: sys.path is left as it was
        importlib.invalidate_caches()
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name is not None and module_name.startswith(exc.name):
            raise ValueError(f"cannot import module '{module_name}': {exc}") from None
        raise ControllerError(class_path, f"importing '{module_name}' failed: "
                                          f"{type(exc).__name__}: {exc}") from exc
    except Exception as exc:  # the user's module raised while importing
        raise ControllerError(class_path, f"importing '{module_name}' failed: "
                                          f"{type(exc).__name__}: {exc}") from exc
    finally:
        if home is not None and str(home) in sys.path:
            sys.path.remove(str(home))
    obj = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"module '{module_name}' has no attribute '{attr}'")
        obj = getattr(obj, part)
    return obj


class PythonController(Controller):
    """Wraps a user's controller instance: checks what it returns, forwards status and message."""

    def __init__(self, config: PythonControllerConfig, robot: RobotSpec) -> None:
        super().__init__()
        self.class_path = config.class_path
        cls = import_class(config.class_path, config.base_dir)
        try:
            inspect.signature(cls).bind(robot, **config.params)
        except TypeError as exc:  # the scenario's params do not fit: bad input
            raise ValueError(f"cannot build {config.class_path}(robot, **params): {exc}") from None
        except ValueError:
            pass  # no signature to check (a builtin): let the call decide
        try:
            self.inner = cls(robot, **config.params)
        except Exception as exc:
            raise ControllerError(config.class_path, f"its constructor raised "
                                                     f"{type(exc).__name__}: {exc}") from exc
        self.rate = float(config.rate if config.rate is not None
                          else getattr(self.inner, "rate", Controller.rate))
        if not 0 < self.rate <= 1e3:
            raise ValueError(f"{config.class_path}.rate must be in (0, 1000] Hz (got {self.rate})")

    def compute(self, obs: Observation) -> Command | tuple[float, float]:
        """The user's command: a :class:`Command`, or (left, right) diff wheel speeds [m/s]."""
        try:
            command = self.inner.compute(obs)
            self.status = getattr(self.inner, "status", self.status)
            self.message = getattr(self.inner, "message", self.message)
            if isinstance(command, Command):
                return command
            left, right = command
            left, right = float(left), float(right)
        except Exception as exc:
            raise ControllerError(self.class_path, f"compute() raised {type(exc).__name__}: "
                                                   f"{exc}") from exc
        if not (math.isfinite(left) and math.isfinite(right)):
            raise ControllerError(self.class_path, f"compute() returned wheel speeds "
                                                   f"({left}, {right}): not finite")
        return left, right

    def debug_path(self):
        getter = getattr(self.inner, "debug_path", None)
        return getter() if callable(getter) else None
