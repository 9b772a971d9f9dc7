"""`pymunk-bot bench`: the speed benchmarks, which live beside the package in a checkout.

The benchmarks (``bench/`` at the repository's root) drive this command line themselves (the
fuzz run, map building), so they run as a program of their own, not as an import of it; they
are not part of an installed package, and from one this command says where they are.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pymunk_bot

# The bench's sections, in the order they run (what `pymunk-bot bench --only` takes).
SECTION_NAMES = ("simulation", "lidar", "contacts", "fleet", "learning_loop", "irsim", "movers",
                 "crowds", "maps", "localization", "localization_robustness", "learning", "fuzz")


def checkout_root() -> Path | None:
    """The source checkout this package runs from (the folder holding ``bench/``), if any."""
    for root in (Path(pymunk_bot.__file__).resolve().parents[1], Path.cwd()):
        if (root / "bench" / "__main__.py").is_file():
            return root
    return None


def cmd_bench(args: argparse.Namespace) -> int:
    """Run the benchmarks of the checkout in a process of their own; 2 if there is none."""
    root = checkout_root()
    if root is None:
        print("error: the speed benchmarks live in the bench/ folder of a pymunk-bot checkout, "
              "not in the installed package: run `pymunk-bot bench` inside a clone of the "
              "repository (pip install -e . there)", file=sys.stderr)
        return 2
    argv = [sys.executable, "-m", "bench"] + (["--quick"] if args.quick else [])
    for name in args.only or []:
        argv += ["--only", name]
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), env.get("PYTHONPATH")]))
    return subprocess.run(argv, check=False, cwd=root, env=env).returncode
