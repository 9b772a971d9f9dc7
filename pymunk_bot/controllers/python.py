"""A user's own controller, imported from ``class_path: 'package.module:ClassName'``.

The class follows the :class:`~pymunk_bot.controllers.Controller` protocol: it is built as
``ClassName(robot_spec, **params)`` and its ``compute(observation)`` returns (left, right) wheel
speeds [m/s]; ``rate`` [Hz], ``status`` and ``message`` are optional attributes. The module is
imported as Python would; if that fails, the current directory is tried as well, so a scenario
run from a project's root finds the project's own packages without installing them.
"""
from __future__ import annotations

import importlib
import inspect
import os
import sys

from ..config.controllers import PythonControllerConfig
from .base import Command, Controller, Observation, RobotSpec


def import_class(class_path: str) -> type:
    """The controller class named by 'package.module:ClassName'; ValueError with a one-line reason."""
    obj = import_module_attr(class_path)
    if not inspect.isclass(obj):
        raise ValueError(f"'{class_path}' is not a class")
    if not callable(getattr(obj, "compute", None)):
        raise ValueError(f"'{class_path}' has no compute(observation) method")
    return obj


def import_module_attr(class_path: str) -> object:
    """The object named by 'package.module:Name'; ValueError with a one-line reason."""
    module_name, _, attr = class_path.partition(":")
    try:
        module = _import(module_name)
    except ImportError as exc:
        raise ValueError(f"cannot import module '{module_name}': {exc}") from None
    except Exception as exc:  # the user's module raised while importing
        raise ValueError(f"importing '{module_name}' failed: {type(exc).__name__}: {exc}") from None
    obj = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"module '{module_name}' has no attribute '{attr}'")
        obj = getattr(obj, part)
    return obj


def _import(module_name: str):
    try:
        return importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        here = os.getcwd()
        top = module_name.split(".")[0]
        if exc.name != top or here in sys.path:
            raise
        sys.path.append(here)  # appended: never shadows installed packages
        return importlib.import_module(module_name)


class PythonController(Controller):
    """Wraps a user's controller instance: checks what it returns, forwards status and message."""

    def __init__(self, config: PythonControllerConfig, robot: RobotSpec) -> None:
        super().__init__()
        cls = import_class(config.class_path)
        try:
            self.inner = cls(robot, **config.params)
        except TypeError as exc:
            raise ValueError(f"cannot build {config.class_path}(robot, **params): {exc}") from None
        self.rate = float(config.rate if config.rate is not None
                          else getattr(self.inner, "rate", Controller.rate))
        if not self.rate > 0:
            raise ValueError(f"{config.class_path}.rate must be > 0 (got {self.rate})")

    def compute(self, obs: Observation) -> Command | tuple[float, float]:
        command = self.inner.compute(obs)
        self.status = getattr(self.inner, "status", self.status)
        self.message = getattr(self.inner, "message", self.message)
        if isinstance(command, Command):
            return command
        left, right = command  # the older form: wheel speeds of a diff robot [m/s]
        return float(left), float(right)

    def debug_path(self):
        getter = getattr(self.inner, "debug_path", None)
        return getter() if callable(getter) else None
