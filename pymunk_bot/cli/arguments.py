"""Argument types and the parser class shared by every subcommand: one rule per kind of value."""
from __future__ import annotations

import argparse
import math
import re
from pathlib import Path
from typing import Callable

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.outcomes.results import writable_problem

# 0 ran and every expectation held; 1 an expectation failed, could not be decided, or a
# controller failed (or raised); 2 bad input; 3 an internal error (a bug: traceback shown).
EXIT_OK, EXIT_EXPECTATION_FAILED, EXIT_BAD_INPUT, EXIT_INTERNAL_ERROR = 0, 1, 2, 3
MAX_DURATION = 86_400.0  # [s] simulated, as the scenario's own world.duration
MAX_JOBS = 256  # parallel processes
_NEGATIVE = re.compile(r"-[\d.]")  # a negative number, range or list: a value, not an option


class Parser(argparse.ArgumentParser):
    """argparse that exits with status 2 and one line on bad arguments (its default too)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"error: {message} (see `{self.prog} --help`)\n")

    def parse_known_args(self, args=None, namespace=None):
        """As argparse, but a value that starts with '-' and a digit (``--seeds -3:2``,
        ``--duration -1``) is the option's value, so its own check can say what is wrong
        (argparse would take it for an option and say "expected one argument")."""
        if args is not None:
            args = list(args)
            for k in range(len(args) - 1, 0, -1):
                action = self._option_string_actions.get(args[k - 1])
                if action is not None and action.nargs is None \
                        and _NEGATIVE.match(args[k]) and args[k] not in self._option_string_actions:
                    args[k - 1:k + 1] = [f"{args[k - 1]}={args[k]}"]
        return super().parse_known_args(args, namespace)


def seed_number(text: str) -> int:
    """argparse type: one seed, a whole number in [0, 2**63 - 1] (the API's rule, check_seed)."""
    try:
        value = int(text, 10)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 0 (got '{text}')") from None
    from pymunk_bot.config.checks import check_seed  # here: `import pymunk_bot.cli` stays light

    try:
        seed = check_seed(value)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("seed ")) from None
    assert seed is not None
    return seed


def duration_seconds(text: str) -> float:
    """argparse type: simulated seconds, finite, in (0, MAX_DURATION]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number of seconds (got '{text}')") from None
    if not (math.isfinite(value) and 0 < value <= MAX_DURATION):
        raise argparse.ArgumentTypeError(f"must be > 0 and <= {MAX_DURATION:g} s (got '{text}')")
    return value


def count_up_to(most: int) -> Callable[[str], int]:
    """argparse type: a whole number in 1..``most``."""
    def count(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number (got '{text}')") from None
        if not 1 <= value <= most:
            raise argparse.ArgumentTypeError(f"must be in 1..{most} (got {value})")
        return value
    return count


jobs_count = count_up_to(MAX_JOBS)  # processes


def check_output(option: str, path: Path, formats: tuple[str, ...]) -> Path:
    """``path`` if it can be written as one of ``formats``; else a one-line ScenarioError."""
    if path.suffix.lower() not in formats:
        got = f"'{path.suffix}'" if path.suffix else "no extension"
        raise ScenarioError(option, "", f"{path}: unsupported file type ({got}); use "
                                        f"{' or '.join(formats)}")
    problem = writable_problem(path)
    if problem is not None:
        raise ScenarioError(option, "", problem)
    return path
