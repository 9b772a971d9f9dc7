"""The localizer seam: after the sensors read, a localizer turns odometry, scans and the map into
the pose estimate the controller sees (``robot.localizer.pose``, ``.covariance``).

Write your own by subclassing :class:`Localizer`; register it with
``localizers.register("name", ConfigModel)`` or name it from YAML with ``type: python``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.robots.readings import LaserScan, RobotSpec

if TYPE_CHECKING:
    from pymunk_bot.localization.likelihood import LikelihoodField

# When an estimate is trustworthy enough to drive on (docs/localization.md, "Localize before
# driving"): its position std (along its worst axis) and heading std within these bounds.
LOCALIZED_POSITION_STD = 0.2  # [m]
LOCALIZED_HEADING_STD = math.radians(10.0)  # [rad]


@dataclass(frozen=True)
class LocalizerContext:
    """What a localizer is built with."""

    robot: RobotSpec
    start_pose: np.ndarray  # [x, y, theta]: the true start pose (what ``initial: known`` means)
    rng: np.random.Generator  # the localizer's own random stream
    arena: tuple[float, float]  # interior width, height [m]; see ``origin``
    map: OccupancyGrid | None = None  # the prebuilt map, given when the class sets ``needs_map``
    lidar_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # LiDAR mount in the robot frame
    origin: tuple[float, float] = (0.0, 0.0)  # [m] the arena's lower-left corner (a ROS map's
    # origin): the arena spans [x0, x0 + width] x [y0, y0 + height]
    # The likelihood field of ``map`` capped at a distance [m], built once for every localizer
    # and every reset of the run on that map (None: build your own from ``map``).
    likelihood: "Callable[[float], LikelihoodField] | None" = None

    def likelihood_field(self, max_dist: float) -> "LikelihoodField":
        """The likelihood field of ``map`` capped at ``max_dist`` [m]: the run's shared one,
        else one of its own."""
        if self.likelihood is not None:
            return self.likelihood(max_dist)
        from pymunk_bot.localization.likelihood import LikelihoodField
        assert self.map is not None
        return LikelihoodField(self.map, max_dist)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) [m] of the arena in the world frame."""
        (x0, y0), (w, h) = self.origin, self.arena
        return (x0, y0, x0 + w, y0 + h)


@dataclass(frozen=True)
class LocalizerInputs:
    """What a localizer reads at one update (every physics tick)."""

    time: float  # [s]
    odometry: np.ndarray  # odometry pose estimate now [x, y, theta]
    scan: LaserScan | None  # the latest LiDAR scan (new when ``scan.time == time``), if any
    imu: Any = None  # the latest IMU reading, if the robot has one


class Localizer:
    """Base class: keep ``pose`` (x, y, theta) and ``covariance`` (3x3) current in :meth:`update`."""

    needs_map: bool = False  # True: the context carries the scenario's map (or world.map)
    needs_lidar: bool = False  # True: the scenario must give the robot a LiDAR
    # True: ``pose`` is the robot's odometry estimate (controllers' observations read the
    # odometry of many robots at once, and this one's pose with it)
    reports_odometry: bool = False

    def __init__(self, config: Any, context: LocalizerContext) -> None:
        self.config = config
        self.context = context
        self.pose = np.array(context.start_pose, dtype=float)
        self.covariance = np.zeros((3, 3))

    def update(self, inputs: LocalizerInputs) -> None:
        """Fold in this tick's inputs; called after the sensors read, before controllers run."""
        raise NotImplementedError

    def debug(self) -> dict[str, Any]:
        """Extra state for views and logs (e.g. ``particles``: (n, 3) array); empty by default."""
        return {}

    @property
    def localized(self) -> bool:
        """Whether a controller may drive on ``pose`` (else it waits or turns on the spot).
        True by default; the built-in filters answer :meth:`spread_within_bounds`."""
        return True

    def spread_within_bounds(self) -> bool:
        """``covariance`` within LOCALIZED_POSITION_STD and LOCALIZED_HEADING_STD."""
        cov = np.asarray(self.covariance, dtype=float)
        if not np.all(np.isfinite(cov)):
            return False
        position_var = float(np.linalg.eigvalsh(0.5 * (cov[:2, :2] + cov[:2, :2].T))[-1])
        return (position_var <= LOCALIZED_POSITION_STD ** 2
                and float(cov[2, 2]) <= LOCALIZED_HEADING_STD ** 2)



