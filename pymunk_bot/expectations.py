"""Regression expectations (`expect:`) checked at the end of a run, and per-tick metrics."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geometry import distance_to_polygon, point_in_polygon


@dataclass(frozen=True)
class Check:
    """One expectation of one robot and how the run measured up."""

    robot: str
    key: str
    passed: bool
    expected: object
    actual: object
    by: float | None = None  # how far a failed check missed, in the key's unit (None: n/a)
    unit: str = ""

    def describe(self) -> str:
        verdict = "ok" if self.passed else "FAILED"
        return f"{self.robot}.{self.key}: expected {self.expected}, got {self.actual} [{verdict}]"

    def miss(self) -> str:
        """What failed and by how much, for tables: "min_clearance 0.031 m, 0.019 m short"."""
        text = f"{self.robot}.{self.key}: expected {self.expected}, got {self.actual}"
        if self.by is not None:
            text += f" (off by {self.by:.3g}{' ' + self.unit if self.unit else ''})"
        return text


def _fmt(value) -> object:
    return round(value, 4) if isinstance(value, float) else value


def evaluate(expectations: dict, robots: dict) -> list[Check]:
    """Compare each robot's run against its expectations."""
    checks: list[Check] = []
    for name, exp in expectations.items():
        robot = robots[name]

        def add(key, passed, expected, actual, by=None, unit=""):
            miss = None if passed or by is None else _fmt(float(by))
            checks.append(Check(name, key, bool(passed), expected, _fmt(actual), miss, unit))

        if exp.goal_reached is not None:
            add("goal_reached", robot.goal_reached == exp.goal_reached, exp.goal_reached,
                robot.goal_reached)
        if exp.within is not None:
            t = robot.time_to_goal
            add("within", t is not None and t <= exp.within, f"<= {exp.within:g} s",
                "never" if t is None else t, None if t is None else t - exp.within, "s")
        if exp.max_collisions is not None:
            add("max_collisions", robot.collisions <= exp.max_collisions,
                f"<= {exp.max_collisions}", robot.collisions,
                robot.collisions - exp.max_collisions)
        if exp.min_clearance is not None:
            add("min_clearance", robot.metrics.min_clearance >= exp.min_clearance,
                f">= {exp.min_clearance:g} m", robot.metrics.min_clearance,
                exp.min_clearance - robot.metrics.min_clearance, "m")
        if exp.max_path_length is not None:
            add("max_path_length", robot.distance <= exp.max_path_length,
                f"<= {exp.max_path_length:g} m", robot.distance,
                robot.distance - exp.max_path_length, "m")
        for i, _ in enumerate(exp.never_enter):
            entered = robot.metrics.entered[i]
            add(f"never_enter[{i}]", entered is None, "never",
                "never" if entered is None else f"entered at t={entered:.2f} s")
        for key, field in (("localization_rmse", "rmse"), ("localization_final_error", "final_error")):
            limit = getattr(exp, key)
            if limit is None:
                continue
            score = getattr(robot, "localization_score", None)
            value = score.block()[field] if score is not None else None
            add(key, value is not None and value <= limit, f"<= {limit:g} m",
                "not localized" if value is None else value,
                None if value is None else value - limit, "m")
        if exp.end_in is not None:
            region = np.asarray(exp.end_in, dtype=float)
            inside = point_in_polygon(robot.pose[:2], region)
            add("end_in", inside, "inside", "inside" if inside else
                f"outside at ({robot.pose[0]:.2f}, {robot.pose[1]:.2f})",
                distance_to_polygon(robot.pose[:2], region), "m")
    return checks
