"""The `pymunk-bot` command line: one package, a module per family of subcommands.

``main.py`` builds the parser and dispatches; ``arguments.py`` holds the argument types every
subcommand shares (one seed rule, one duration rule); the rest each own their subcommands or the
outputs of ``run``.
"""
from .main import build_parser, main

__all__ = ["build_parser", "main"]
