"""What a controller sees and what it returns.

A controller is called at its own ``rate`` with an :class:`Observation` (the robot's sensor
readings and its pose estimate, never ground truth unless the scenario asks for it) and returns
a :class:`~pymunk_bot.robots.command.Command` (body velocity), which every drive takes. A controller
written for the diff drive may still return (left, right) wheel speeds [m/s]; new code should
return a Command, so it works on every drive. Write your own by subclassing :class:`Controller`.
"""
from __future__ import annotations

from pymunk_bot.robots.command import STOP, Command
from pymunk_bot.robots.drives.diff import wheel_speeds
from pymunk_bot.plugins import controllers
from pymunk_bot.robots.readings import LaserScan, Observation, RobotSpec
from pymunk_bot.controllers.localizing import LOCALIZING, localizing_command
from pymunk_bot.controllers.progress import ProgressWatch, no_progress_message

__all__ = ["STOP", "Command", "Controller", "LaserScan", "Observation", "RobotSpec", "controllers",
           "wheel_speeds"]


class Controller:
    """Base class for controllers: override :meth:`compute`.

    ``status`` is "running", "arrived" (goal reached as far as the controller knows) or
    "failed" (it gave up, e.g. no path); ``message`` says why.
    """

    rate: float = 10.0  # [Hz]
    needs_map: bool = False  # True: the simulation calls set_map() before the first compute()
    observes: bool = True  # False: compute() reads nothing and is called with None (none built)
    # True (with observes False): compute(None) gives one command for ever, and is asked once
    # each time the robot is given back to it (a fleet's constant controllers cost nothing).
    constant: bool = False
    _localizing_since: float | None = None  # [s] when the estimate last became untrustworthy
    _watched_goal: tuple[float, float] | None = None  # the goal the progress watch is for
    _given_up = False  # the watch ran out for this goal

    def __init__(self, config=None, robot: RobotSpec | None = None) -> None:
        """Built-in controllers pass their config and robot: that sets ``config``, ``rate`` and
        ``max_speed`` (the config's, capped by the robot's max wheel speed)."""
        self.status = "running"
        self.message = ""
        self.watch = ProgressWatch()  # progress toward the goal (controllers/progress.py)
        if config is not None:
            self.config = config
            self.rate = getattr(config, "rate", None) or self.rate
        if robot is not None:
            wanted = getattr(config, "max_speed", None) or robot.max_speed
            self.max_speed = min(wanted, robot.max_speed)

    def compute(self, obs: Observation) -> Command | tuple[float, float]:
        """The body velocity for the next control period (or diff wheel speeds, left and right)."""
        raise NotImplementedError

    def hold_until_localized(self, obs: Observation) -> Command | None:
        """Localize before driving: while the estimate is not trustworthy (``obs.localized``
        False: a global start, a kidnapping, a spread above the localizer's bounds) the robot
        turns on the spot through what its LiDAR does not see, then explores towards the
        localizer's ``obs.explore_heading`` or on its LiDAR alone (controllers/localizing.py),
        or stands still if it cannot turn in place without sweeping its outline over
        something. Returns that command, or None once it may drive."""
        if getattr(obs, "localized", True):
            if self.message == LOCALIZING:
                self.message = ""
            self._localizing_since = None
            return None
        if self._localizing_since is None:
            self._localizing_since = obs.time
        self.watch.restart()  # localizing is not standing still
        self.message = LOCALIZING
        return localizing_command(obs, obs.time - self._localizing_since)

    def gave_up(self, obs: Observation, measure: float) -> bool:
        """Feed ``measure`` [m] of progress (larger is better) to the progress watch; once
        ``give_up_after`` [s] of the config pass without progress, set status "failed" with a
        message saying where and for how long, and return True from then on, until the
        goal changes (a new goal is a new task: the watch starts again)."""
        goal = None if obs.goal is None else (float(obs.goal[0]), float(obs.goal[1]))
        if goal != self._watched_goal:
            self._watched_goal, self._given_up = goal, False
            self.watch.restart()
        if self._given_up:
            return True
        stalled = self.watch.update(obs.time, measure)
        if stalled <= self.config.give_up_after:
            return False
        self.status, self.message = "failed", no_progress_message(stalled, obs.pose)
        self._given_up = True
        return True

    def set_map(self, world_map) -> None:
        """Receive the scenario's map (a :class:`pymunk_bot.planning.MapInfo`) if ``needs_map``."""
        self.map = world_map

    def debug_path(self) -> list[tuple[float, float]] | None:
        """A path the controller is following, for views (None if it has none)."""
        return None
