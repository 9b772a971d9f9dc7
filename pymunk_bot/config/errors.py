"""The one error type users see for bad input: file, key path and problem on one line."""
from __future__ import annotations

from typing import Any


class ScenarioError(Exception):
    """Bad scenario input. ``str()`` is the one-line message the CLI prints (exit status 2)."""

    def __init__(self, source: str, path: str, problem: str, line: int | None = None) -> None:
        self.source = source
        self.path = path
        self.problem = problem
        self.line = line
        super().__init__(self.format())

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:  # pickles whole: crosses processes
        return (type(self), (self.source, self.path, self.problem, self.line))

    def format(self) -> str:
        """The one-line message: file, key path, problem and (when known) the line."""
        where = f"{self.source}: {self.path}: " if self.path else f"{self.source}: "
        line = f" (line {self.line})" if self.line is not None else ""
        # One line always, even when the problem quotes user text with line breaks in it.
        return f"{where}{self.problem}{line}".replace("\r", "\\r").replace("\n", "\\n")


class ScenarioWarning(UserWarning):
    """A doubtful but valid input (an angle that looks like degrees); the run goes on.
    The CLI prints it as one line: ``warning: file: key.path: problem``."""

    def __init__(self, source: str, path: str, problem: str, line: int | None = None) -> None:
        super().__init__(ScenarioError(source, path, problem, line).format())


class ControllerError(Exception):
    """A user's controller code raised (in its import, constructor or compute): a bug in that
    code, not bad scenario input. The CLI shows the traceback and exits 1."""

    def __init__(self, where: str, problem: str) -> None:
        self.where = where
        self.problem = problem
        super().__init__(f"{where}: {problem}")

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:  # a sweep's worker reports it whole
        return (type(self), (self.where, self.problem))


class SemanticError(Exception):
    """A problem at a key path (a tuple, as pydantic's locations are), found before the
    source is known: the loader turns it into a :class:`ScenarioError`."""

    def __init__(self, loc: tuple, problem: str) -> None:
        super().__init__(problem)
        self.loc = loc
        self.problem = problem
