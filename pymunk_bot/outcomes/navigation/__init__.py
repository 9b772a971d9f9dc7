"""Navigation metrics of a run (Francis et al. 2023, Table 1, plus contact impulses).

A run measures them for every robot when the scenario has pedestrians or an ``expect`` block
bounds a metric; the result JSON then holds ``robots.<name>.metrics``. From Python, for any
run and with any thresholds::

    from pymunk_bot.outcomes.navigation import Thresholds, track
    metrics = track(sim, "r1", Thresholds(personal_space=0.3))   # before stepping
    sim.run(10.0)
    metrics.values()   # {"success": 1.0, "spl": 0.93, "min_distance_to_human": 0.41, ...}

The tracker follows the run through resets (it measures each episode from its start).
docs/benchmark.md lists every metric with its formula and unit.
"""
from __future__ import annotations

from typing import Any

from pymunk_bot.outcomes.navigation.definitions import BY_NAME, METRIC_NAMES, METRICS, Metric, Thresholds
from pymunk_bot.outcomes.navigation.recorder import NavMetrics


def of_simulation(sim: Any, robot: str, thresholds: Thresholds | None = None) -> NavMetrics:
    """A new recorder of ``robot``'s metrics in ``sim``, measuring from now (updated by
    whoever calls its ``update(time)`` after every tick: :func:`track` does)."""
    handle = sim.robots[robot]
    return NavMetrics(sim.world, handle, list(sim.robots.values()), sim.config, sim.built.maps,
                      thresholds)


class MetricsTracker:
    """An observer of a :class:`~pymunk_bot.engine.simulation.Simulation` that keeps one robot's metrics
    (see :func:`track`). Uses the run's own recorder when it has one with the same
    thresholds, so nothing is measured twice."""

    def __init__(self, robot: str, thresholds: Thresholds | None = None) -> None:
        self.robot = robot
        self.thresholds = thresholds or Thresholds()
        self.recorder: NavMetrics | None = None
        self._own = False  # the recorder is ours to update (the run does not)

    def on_reset(self, sim: Any) -> None:
        """Follow the rebuilt run: its own recorder when it keeps one with these thresholds,
        else one of this tracker's."""
        built = sim.robots[self.robot].metrics.navigation
        if built is not None and built.thresholds == self.thresholds:
            self.recorder, self._own = built, False
        else:
            self.recorder, self._own = of_simulation(sim, self.robot, self.thresholds), True

    def __call__(self, sim: Any) -> None:
        if self._own and self.recorder is not None:
            self.recorder.update(sim.time)

    def collided(self) -> bool:
        """Whether the robot has collided in this episode (``collision``'s test)."""
        if self.recorder is None:
            raise RuntimeError("attach the tracker to a simulation first (use track())")
        return self.recorder.collided

    def values(self) -> dict[str, float]:
        """The metrics of the episode so far (see ``METRIC_NAMES``)."""
        if self.recorder is None:
            raise RuntimeError("attach the tracker to a simulation first (use track())")
        return self.recorder.values()


def track(sim: Any, robot: str, thresholds: Thresholds | None = None) -> MetricsTracker:
    """Measure ``robot``'s navigation metrics in ``sim`` from now on, through resets."""
    tracker = MetricsTracker(robot, thresholds)
    sim.attach(tracker)
    return tracker


__all__ = ["BY_NAME", "METRICS", "METRIC_NAMES", "Metric", "MetricsTracker", "NavMetrics",
           "Thresholds", "of_simulation", "track"]
