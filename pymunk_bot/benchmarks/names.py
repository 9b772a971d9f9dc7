"""The bench's section names, in the order they run (what `pymunk-bot bench --only` takes).

A module of its own, importing nothing: the command line lists these without loading the
benchmarks, which exercise the command line themselves and so sit above it.
"""
from __future__ import annotations

SECTION_NAMES = ("simulation", "lidar", "contacts", "fleet", "learning_loop", "irsim", "movers",
                 "crowds", "maps", "localization", "localization_robustness", "learning", "fuzz")
