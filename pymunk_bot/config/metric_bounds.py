"""The navigation metrics' names, units and directions, and the ``expect`` keys that bound them.

Pure data (the scenario schema reads it; :mod:`pymunk_bot.outcomes.navigation` measures them). An
``expect`` block bounds a metric where larger is better by its own name (at least:
``spl: 0.7``, ``min_distance_to_human: 0.3``) and one where smaller is better by ``max_`` and
its name (at most: ``max_human_impulse: 0.0``, ``max_personal_space_time: 2.0``; a name
that starts with ``max_`` is its own key: ``max_jerk: 50``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pymunk_bot.config.types import Float, Section


@dataclass(frozen=True)
class Metric:
    """One metric: its column name, unit, and whether larger values are better."""

    name: str
    unit: str  # SI; "" for rates and counts
    higher_is_better: bool
    doc: str


# Column order of benchmark rows and of ``robots.<name>.metrics`` in the result JSON.
METRICS: tuple[Metric, ...] = (
    Metric("success", "", True, "1 if the goal was reached with no collision before it "
                                "(CrowdNav's success), else 0; implies reached"),
    Metric("reached", "", True, "1 if the goal was reached at all (after a collision too)"),
    Metric("collision", "", False, "1 if the robot collided with anything (wall, robot or "
                                   "human): a contact, or a pedestrian's disc overlapping its "
                                   "footprint at a tick; the collision_* columns split it"),
    Metric("collision_wall", "", False, "1 if it touched static geometry or a non-human obstacle"),
    Metric("collision_robot", "", False, "1 if it touched another robot"),
    Metric("collision_human", "", False, "1 if it touched a pedestrian (any contact, at any "
                                         "distance threshold)"),
    Metric("timeout", "", False, "1 if the run reached its duration without the goal"),
    Metric("failure_to_progress", "", False, "1 if the closest approach to the goal did not "
                                             "improve by progress_distance within any "
                                             "progress_window before the goal"),
    Metric("stalled_time", "s", False, "time spent slower than stall_speed before the goal"),
    Metric("time_to_goal", "s", False, "time the goal was reached (NaN if never)"),
    Metric("path_length", "m", False, "distance travelled by the robot's centre, up to "
                                      "the goal when reached"),
    Metric("spl", "", True, "reached x L* / max(L*, L), L* the shortest collision-free path "
                            "of the static world, L the path length"),
    Metric("min_distance_to_human", "m", True, "smallest clearance between the robot's "
                                               "footprint and a pedestrian's disc (inf: none)"),
    Metric("personal_space_intrusions", "", False, "entries of pedestrians into a clearance "
                                                   "of personal_space"),
    Metric("personal_space_time", "s", False, "time with some pedestrian within personal_space"),
    Metric("discomfort", "", False, "fraction of the time before the goal (or the end) with "
                                    "some pedestrian within discomfort_distance (CrowdNav's "
                                    "danger frequency, per episode)"),
    Metric("min_time_to_collision", "s", True, "smallest constant-velocity time to contact "
                                               "with a pedestrian (inf: never on course)"),
    Metric("clearing_distance", "m", True, "smallest clearance to static geometry and "
                                           "obstacles (not pedestrians)"),
    Metric("mean_speed", "m/s", True, "path length / time, up to the goal when reached"),
    Metric("min_speed", "m/s", True, "smallest sampled speed before the goal"),
    Metric("max_speed", "m/s", False, "largest sampled speed before the goal"),
    Metric("mean_acceleration", "m/s^2", False, "mean |dv/dt| over the samples"),
    Metric("max_acceleration", "m/s^2", False, "largest |dv/dt| over the samples"),
    Metric("mean_jerk", "m/s^3", False, "mean |da/dt| over the samples"),
    Metric("max_jerk", "m/s^3", False, "largest |da/dt| over the samples"),
    Metric("human_impulse", "N s", False, "sum of contact impulses between robot and "
                                          "pedestrians"),
    Metric("peak_human_force", "N", False, "largest contact force on a pedestrian"),
    Metric("robot_impulse", "N s", False, "sum of contact impulses with other robots"),
    Metric("peak_robot_force", "N", False, "largest contact force with another robot"),
    Metric("object_impulse", "N s", False, "sum of contact impulses with movable or "
                                           "scripted obstacles"),
    Metric("peak_object_force", "N", False, "largest contact force on such an obstacle"),
)
METRIC_NAMES: tuple[str, ...] = tuple(m.name for m in METRICS)
BY_NAME: dict[str, Metric] = {m.name: m for m in METRICS}


# Keys already in ``expect`` with the same meaning (max_path_length): not generated twice.
_EXISTING = {"max_path_length"}


def bound_key(metric: Metric) -> str:
    """The ``expect`` key that bounds ``metric``: its name (at least, or at most for a name
    that already starts with ``max_``) or ``max_<name>`` (at most)."""
    if metric.higher_is_better or metric.name.startswith("max_"):
        return metric.name
    return f"max_{metric.name}"


BOUND_KEYS: dict[str, Metric] = {bound_key(m): m for m in METRICS
                                 if bound_key(m) not in _EXISTING}


class MetricBounds(Section):
    """Bounds on navigation metrics in a robot's ``expect`` block (None: not checked); the
    keys are ``BOUND_KEYS``'s (a test keeps the two in step)."""

    success: Float | None = None  # at least
    reached: Float | None = None  # at least
    max_collision: Float | None = None  # at most
    max_collision_wall: Float | None = None  # at most
    max_collision_robot: Float | None = None  # at most
    max_collision_human: Float | None = None  # at most
    max_timeout: Float | None = None  # at most
    max_failure_to_progress: Float | None = None  # at most
    max_stalled_time: Float | None = None  # at most [s]
    max_time_to_goal: Float | None = None  # at most [s]
    spl: Float | None = None  # at least
    min_distance_to_human: Float | None = None  # at least [m]
    max_personal_space_intrusions: Float | None = None  # at most
    max_personal_space_time: Float | None = None  # at most [s]
    max_discomfort: Float | None = None  # at most
    min_time_to_collision: Float | None = None  # at least [s]
    clearing_distance: Float | None = None  # at least [m]
    mean_speed: Float | None = None  # at least [m/s]
    min_speed: Float | None = None  # at least [m/s]
    max_speed: Float | None = None  # at most [m/s]
    max_mean_acceleration: Float | None = None  # at most [m/s^2]
    max_acceleration: Float | None = None  # at most [m/s^2]
    max_mean_jerk: Float | None = None  # at most [m/s^3]
    max_jerk: Float | None = None  # at most [m/s^3]
    max_human_impulse: Float | None = None  # at most [N s]
    max_peak_human_force: Float | None = None  # at most [N]
    max_robot_impulse: Float | None = None  # at most [N s]
    max_peak_robot_force: Float | None = None  # at most [N]
    max_object_impulse: Float | None = None  # at most [N s]
    max_peak_object_force: Float | None = None  # at most [N]


def bounds_of(expectation: Any) -> list[tuple[str, Metric, float]]:
    """(key, metric, limit) of every metric bound an expectation sets."""
    return [(key, metric, getattr(expectation, key)) for key, metric in BOUND_KEYS.items()
            if getattr(expectation, key, None) is not None]
