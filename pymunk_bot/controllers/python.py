"""A user's own controller, imported from ``class_path: 'package.module:ClassName'``.

The class follows the :class:`~pymunk_bot.controllers.Controller` protocol: it is built as
``ClassName(robot_spec, **params)`` and its ``compute(observation)`` returns (left, right) wheel
speeds [m/s] (or a :class:`~pymunk_bot.robots.command.Command`, for any drive); ``rate`` [Hz], ``status`` and ``message`` are optional attributes.

Where the module is looked for: next to the scenario file, then in the folders above it, then
the current folder, then ``sys.path``. Validation only *finds* the module and reads its source
(no user code runs); the simulation imports it, with the found folder on ``sys.path`` only
for the import. A bug in the user's code (an exception in its import, constructor or
``compute``, ``sys.exit()`` included) is a :class:`~pymunk_bot.config.errors.ControllerError` carrying
its traceback, not bad input.

Time budget: when the environment variable ``PYMUNK_BOT_CALL_BUDGET`` holds a number of seconds,
each call into user code (the import, the constructor, every ``compute``) may take at most that
long; a call that overruns is stopped and fails the run with a ``ControllerError`` naming the
controller. ``pymunk-bot test`` and ``pymunk-bot sweep`` set it to ``BATCH_CALL_BUDGET`` (10 s)
unless it is set already (``0`` turns it off); interactive runs and the Python API have no
budget unless the variable is set. A call stuck in C code that ignores signals (and, in threads
other than the main one, a blocking call) is only stopped when it returns to Python.
"""
from __future__ import annotations

import importlib
import contextlib
import ctypes
import inspect
import math
import os
import signal
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

from pymunk_bot.config.class_path import module_home
from pymunk_bot.config.controllers import PythonControllerConfig
from pymunk_bot.config.errors import ControllerError
from pymunk_bot.controllers.base import Command, Controller, Observation, RobotSpec


CALL_BUDGET_ENV = "PYMUNK_BOT_CALL_BUDGET"
BATCH_CALL_BUDGET = 10.0  # [s] per call into user code in `test` and `sweep` runs


class _Overran(BaseException):
    """Raised into user code that ran past its budget (a BaseException: a user's ``except
    Exception`` must not swallow it)."""

    def __init__(self) -> None:
        super().__init__("stopped here: the call ran past its time budget")


def call_budget() -> float | None:
    """Seconds one call into user code may take (``PYMUNK_BOT_CALL_BUDGET``); None: no limit."""
    text = os.environ.get(CALL_BUDGET_ENV, "").strip()
    if not text:
        return None
    try:
        budget = float(text)
    except ValueError:
        raise ValueError(f"{CALL_BUDGET_ENV} must be a number of seconds (got {text[:40]!r})") \
            from None
    if not (math.isfinite(budget) and budget >= 0):
        raise ValueError(f"{CALL_BUDGET_ENV} must be >= 0 s (got {text[:40]!r})")
    return budget or None


@contextlib.contextmanager
def batch_budget() -> Iterator[None]:
    """For the block (a `test` or `sweep` command, its worker processes included): user code
    gets ``BATCH_CALL_BUDGET`` per call unless ``PYMUNK_BOT_CALL_BUDGET`` is set already."""
    if CALL_BUDGET_ENV in os.environ:
        yield
        return
    os.environ[CALL_BUDGET_ENV] = f"{BATCH_CALL_BUDGET:g}"
    try:
        yield
    finally:
        os.environ.pop(CALL_BUDGET_ENV, None)


@contextlib.contextmanager
def budgeted(class_path: str, what: str) -> Iterator[None]:
    """Run the block (one call into user code) within :func:`call_budget`; a ControllerError
    naming ``class_path`` and ``what`` when it overruns."""
    budget = call_budget()
    if budget is None:
        yield
        return
    overran = ControllerError(class_path, f"{what} took longer than {budget:g} s (the per-call "
                                          f"time budget, {CALL_BUDGET_ENV})")
    if threading.current_thread() is threading.main_thread() and hasattr(signal, "setitimer"):
        def alarm(signum, frame) -> None:
            raise _Overran

        previous = signal.signal(signal.SIGALRM, alarm)
        signal.setitimer(signal.ITIMER_REAL, budget)
        try:
            yield
        except _Overran as stop:  # its traceback shows where the user's code was
            raise overran from stop
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)
        return
    # Other threads get no signals: a timer raises into this thread when it next runs Python.
    target, lock, state = threading.get_ident(), threading.Lock(), {"done": False, "fired": False}

    def fire() -> None:
        with lock:
            if not state["done"]:
                state["fired"] = True
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(target),
                                                           ctypes.py_object(_Overran))

    timer = threading.Timer(budget, fire)
    timer.daemon = True
    timer.start()
    try:
        yield
    except _Overran as stop:
        raise overran from stop
    finally:
        with lock:
            state["done"] = True
        timer.cancel()
    if state["fired"]:  # it fired as the call returned: the run still overran
        raise overran


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
        with budgeted(class_path, f"importing '{module_name}'"):
            module = importlib.import_module(module_name)
    except ControllerError:
        raise
    except ModuleNotFoundError as exc:
        if exc.name is not None and module_name.startswith(exc.name):
            raise ValueError(f"cannot import module '{module_name}': {exc}") from None
        raise ControllerError(class_path, f"importing '{module_name}' failed: "
                                          f"{type(exc).__name__}: {exc}") from exc
    except (Exception, SystemExit) as exc:  # the user's module raised (or exited) importing
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
        call_budget()  # a bad PYMUNK_BOT_CALL_BUDGET is bad input, told before user code runs
        cls = import_class(config.class_path, config.base_dir)
        try:
            inspect.signature(cls).bind(robot, **config.params)
        except TypeError as exc:  # the scenario's params do not fit: bad input
            raise ValueError(f"cannot build {config.class_path}(robot, **params): {exc}") from None
        except ValueError:
            pass  # no signature to check (a builtin): let the call decide
        try:
            with budgeted(config.class_path, "its constructor"):
                self.inner = cls(robot, **config.params)
        except ControllerError:
            raise
        except (Exception, SystemExit) as exc:
            raise ControllerError(config.class_path, f"its constructor raised "
                                                     f"{type(exc).__name__}: {exc}") from exc
        self.rate = float(config.rate if config.rate is not None
                          else getattr(self.inner, "rate", Controller.rate))
        if not 0 < self.rate <= 1e3:
            raise ValueError(f"{config.class_path}.rate must be in (0, 1000] Hz (got {self.rate})")

    def compute(self, obs: Observation) -> Command | tuple[float, float]:
        """The user's command: a :class:`Command`, or (left, right) diff wheel speeds [m/s]."""
        try:
            with budgeted(self.class_path, "compute()"):
                command = self.inner.compute(obs)
            self.status = getattr(self.inner, "status", self.status)
            self.message = getattr(self.inner, "message", self.message)
            if isinstance(command, Command):
                return command
            left, right = command
            left, right = float(left), float(right)
        except ControllerError:
            raise
        except (Exception, SystemExit) as exc:
            raise ControllerError(self.class_path, f"compute() raised {type(exc).__name__}: "
                                                   f"{exc}") from exc
        if not (math.isfinite(left) and math.isfinite(right)):
            raise ControllerError(self.class_path, f"compute() returned wheel speeds "
                                                   f"({left}, {right}): not finite")
        return left, right

    def debug_path(self):
        getter = getattr(self.inner, "debug_path", None)
        return getter() if callable(getter) else None
