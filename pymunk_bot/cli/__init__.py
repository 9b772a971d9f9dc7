"""The `pymunk-bot` command line: one package, a module per family of subcommands.

``main.py`` builds the parser and dispatches; ``arguments.py`` holds the argument types every
subcommand shares (one seed rule, one duration rule); the rest each own their subcommands or the
outputs of ``run``.
"""
from __future__ import annotations

from typing import Any

__all__ = ["build_parser", "main"]


def __getattr__(name: str) -> Any:
    # Loaded on first use, so `python -m pymunk_bot` (cli/entry.py) can catch a Ctrl-C while
    # the command line's imports run. Importing the submodule binds ``main`` to it, so the
    # functions are bound after.
    if name in __all__:
        import importlib

        module = importlib.import_module("pymunk_bot.cli.main")
        functions = {"build_parser": module.build_parser, "main": module.main}
        globals().update(functions)
        return functions[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
