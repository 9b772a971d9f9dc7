"""`python -m bench [--quick] [--only NAME ...]`: every section's figures and
targets (what `pymunk-bot bench` runs, in a process of its own)."""
from __future__ import annotations

import argparse
import sys

from bench import run_all
from pymunk_bot.cli.bench import SECTION_NAMES


def main(argv: list[str] | None = None) -> int:
    """Run the sections asked for; 0 when they ran (a missed target is a figure, not an error)."""
    parser = argparse.ArgumentParser(prog="pymunk-bot bench", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    parser.add_argument("--only", action="append", choices=SECTION_NAMES, metavar="NAME",
                        help=f"run only this section (repeatable): {', '.join(SECTION_NAMES)}")
    args = parser.parse_args(argv)
    run_all(quick=args.quick, only=args.only)
    return 0


if __name__ == "__main__":
    sys.exit(main())
