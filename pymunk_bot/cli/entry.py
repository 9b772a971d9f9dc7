"""The `pymunk-bot` console script and `python -m pymunk_bot`.

The command line is imported inside a handler, so a Ctrl-C during start-up is one line, not a
traceback; this module, the package's ``__init__`` and cli/__init__.py import nothing else first.
"""
import sys


def main() -> int:
    """Run `pymunk-bot` with the process's arguments; returns the exit status."""
    try:
        from pymunk_bot.cli.main import main as run
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    return run()
