"""The navigation benchmark: controllers x suites x seeds, one row of metrics per episode.

    from pymunk_bot.benchmark import (controller_choices, load_suite, markdown,
                                      run_benchmark, summarize)
    rows = run_benchmark(load_suite("crowds"), controller_choices(["navigate", "avoid"]),
                         seeds=range(5), backend="process", out="episodes.csv")
    print(markdown(summarize(rows)))

See docs/benchmark.md (the metrics are :mod:`pymunk_bot.outcomes.navigation`).
"""
from __future__ import annotations

from pymunk_bot.benchmark.controllers import ControllerChoice, controller_choice, controller_choices
from pymunk_bot.benchmark.layouts import LAYOUTS, draw_layout
from pymunk_bot.benchmark.runner import ROW_KEYS, run_benchmark, run_episode
from pymunk_bot.benchmark.suite import Entry, episode_data, load_suite, shipped_suites
from pymunk_bot.benchmark.summary import MixedSignatures, markdown, summarize, to_json

__all__ = ["ControllerChoice", "Entry", "LAYOUTS", "MixedSignatures", "ROW_KEYS",
           "controller_choice", "controller_choices", "draw_layout", "episode_data",
           "load_suite", "markdown", "run_benchmark", "run_episode", "shipped_suites",
           "summarize", "to_json"]
