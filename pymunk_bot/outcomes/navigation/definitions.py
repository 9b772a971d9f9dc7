"""The thresholds the navigation metrics use and their signature; the metrics' names, units
and directions live in :mod:`pymunk_bot.config.metric_bounds` (pure data the scenario schema
bounds in ``expect``). Names follow Francis et al. 2023, "Principles and Guidelines for Evaluating Social Robot
Navigation Algorithms" (arXiv 2306.16740, Table 1), plus the physical contact metrics only a
simulator with real contacts can give. docs/benchmark.md gives every formula; keep them in step.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, fields


from pymunk_bot.config.metric_bounds import BY_NAME, METRIC_NAMES, METRICS, Metric

__all__ = ["BY_NAME", "FORMULA_VERSION", "METRICS", "METRIC_NAMES", "Metric", "Thresholds"]

# Bump when a formula changes: the signature then changes, so old rows are never mixed in.
FORMULA_VERSION = 2  # 2: success excludes collisions (reached keeps arrival), discomfort


@dataclass(frozen=True)
class Thresholds:
    """Every setting a metric depends on (documented defaults, tuned to no scenario)."""

    personal_space: float = 0.5  # [m] clearance that counts as an intrusion
    discomfort_distance: float = 0.2  # [m] clearance that counts as discomfort (CrowdNav's)
    stall_speed: float = 0.05  # [m/s] slower than this is stalled
    progress_window: float = 10.0  # [s] failure to progress: no gain over this long ...
    progress_distance: float = 0.1  # [m] ... of at least this toward the goal
    sample_period: float = 0.1  # [s] speed, acceleration and jerk are sampled this often
    spl_resolution: float = 0.05  # [m] grid of the shortest collision-free path

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"metric threshold {f.name} must be a finite number > 0 "
                                 f"(got {value!r})")
        if self.spl_resolution > 1.0:
            raise ValueError(f"spl_resolution must be <= 1 m (got {self.spl_resolution})")

    def signature(self) -> str:
        """A short hash of every threshold and the formula version: rows with different
        signatures measured different things and are never averaged together."""
        text = json.dumps({"version": FORMULA_VERSION, **asdict(self)}, sort_keys=True)
        return hashlib.sha256(text.encode("ascii")).hexdigest()[:12]
