"""Regression expectations (`expect:`) checked at the end of a run, and per-tick metrics."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pymunk_bot.config.metric_bounds import BOUND_KEYS, bounds_of
from pymunk_bot.geometry.plane import distance_to_polygon, point_in_polygon

# Metric bounds that depend on how the run ends: undecided while it is shorter than planned.
END_METRICS = frozenset({"success", "spl", "timeout", "time_to_goal", "mean_speed", "min_speed",
                         "failure_to_progress"})


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


def _fmt(value: object) -> object:
    return round(value, 4) if isinstance(value, float) else value


def evaluate(expectations: dict, robots: dict) -> list[Check]:
    """Compare each robot's run against its expectations."""
    checks: list[Check] = []
    for name, exp in expectations.items():
        robot = robots[name]

        def add(key: str, passed: bool, expected: Any, actual: Any, by: float | None = None,
                unit: str = "") -> None:
            miss = None if passed or by is None else round(float(by), 4)
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
        bounds = bounds_of(exp)
        if bounds:
            measured = robot.metrics.navigation.values()
            for key, metric, limit in bounds:
                value = measured[metric.name]
                unit = metric.unit
                if metric.higher_is_better:  # NaN (no goal, no human) never passes
                    add(key, bool(value >= limit), f">= {limit:g}{' ' + unit if unit else ''}",
                        value, limit - value, unit)
                else:
                    add(key, bool(value <= limit), f"<= {limit:g}{' ' + unit if unit else ''}",
                        value, value - limit, unit)
        if exp.end_in is not None:
            region = np.asarray(exp.end_in, dtype=float)
            inside = point_in_polygon(robot.pose[:2], region)
            add("end_in", inside, "inside", "inside" if inside else
                f"outside at ({robot.pose[0]:.2f}, {robot.pose[1]:.2f})",
                distance_to_polygon(robot.pose[:2], region), "m")
    return checks


@dataclass(frozen=True)
class Verdict:
    """What a run can honestly claim about its expectations and controllers.

    ``status``: "passed" (every expectation checked and held), "unchecked" (the scenario has no
    expectations), "undecided" (none failed, but the run was too short to decide some),
    "failed" (an expectation failed or a controller reported failure).
    """

    status: str
    checks: list[Check]  # decided
    undecided: list[Check]  # could change if the run went on to the scenario's duration
    controller_failures: list[tuple[str, str]]  # (robot, the controller's message)
    sim_time: float  # [s] how long the run was
    needed: float  # [s] how long it must run to decide everything

    @property
    def passed(self) -> bool:
        return self.status in ("passed", "unchecked")

    def lines(self) -> list[str]:
        """The summary's verdict lines, the last one the verdict itself."""
        out = [f"expect {c.describe()}" for c in self.checks]
        out += [f"expect {c.robot}.{c.key}: expected {c.expected}, got {c.actual} so far "
                f"[undecided]" for c in self.undecided]
        out += [f"{robot}: controller failed: {message or '(no message)'}"
                for robot, message in self.controller_failures]
        if self.status == "failed":
            out.append("FAILED")
        elif self.status == "undecided":
            keys = ", ".join(f"{c.robot}.{c.key}" for c in self.undecided)
            out.append(f"UNDECIDED: {keys} could not be decided in {self.sim_time:g} s "
                       f"(run at least {self.needed:g} s)")
        elif self.status == "unchecked":
            out.append("nothing checked: the scenario has no expectations (add an 'expect' "
                       "block)")
        else:
            out.append(f"PASSED ({len(self.checks)} expectation"
                       f"{'s' if len(self.checks) != 1 else ''} checked)")
        return out


def unexpected_failures(expectations: dict, controller_status: dict[str, tuple[str | None, str]]
                        ) -> list[tuple[str, str]]:
    """(robot, message) of controllers that reported ``failed`` when the scenario did not
    expect it: a scenario expecting ``goal_reached: false`` expects its controller to give up."""
    return [(name, message) for name, (status, message) in controller_status.items()
            if status == "failed" and not (name in expectations
                                           and expectations[name].goal_reached is False)]


def judge(expectations: dict, checks: list[Check], sim_time: float, planned: float,
          controller_status: dict[str, tuple[str | None, str]], dt: float) -> Verdict:
    """Sort checks into decided and undecided for a run of ``sim_time`` out of ``planned`` [s].

    Safety checks (collisions, clearance, path length, never_enter) are judged over the run
    that was asked for; what depends on the end state or a later time is undecided when the
    run stopped before the scenario's duration (or before a ``within`` deadline).
    """
    short = sim_time + 0.5 * dt < planned
    decided: list[Check] = []
    undecided: list[Check] = []
    for check in checks:
        exp = expectations[check.robot]
        if check.key == "within":
            open_ = not check.passed and sim_time + 0.5 * dt < exp.within
        elif check.key == "goal_reached":
            deadline = exp.within if exp.within is not None else planned
            open_ = (not check.passed and sim_time + 0.5 * dt < deadline) or (
                check.passed and exp.goal_reached is False and short)
        elif check.key == "end_in":
            open_ = short
        elif check.key in BOUND_KEYS and BOUND_KEYS[check.key].name in END_METRICS:
            open_ = short
        else:
            open_ = False
        (undecided if open_ else decided).append(check)
    failures = unexpected_failures(expectations, controller_status)
    needed = max([planned] + [expectations[c.robot].within or 0.0 for c in undecided])
    if failures or not all(c.passed for c in decided):
        status = "failed"
    elif undecided:
        status = "undecided"
    elif not checks:
        status = "unchecked"
    else:
        status = "passed"
    return Verdict(status, decided, undecided, failures, sim_time, needed)
