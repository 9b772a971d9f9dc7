"""The scenario file as frozen pydantic models: every key, its unit and its default.

docs/scenario-format.md documents each key; keep the two in step.
"""
from __future__ import annotations

import math
from typing import Annotated, Any, Callable, ClassVar, Literal

from pydantic import Field, PrivateAttr

from pymunk_bot.config.events import EventList
from pymunk_bot.config.localization import MappingConfig
from pymunk_bot.config.footprint import FootprintConfig
from pymunk_bot.config.metric_bounds import MetricBounds
from pymunk_bot.config.motion import MotionConfig
from pymunk_bot.config.types import (
    MAX_BEAMS, MAX_OBSTACLES, MAX_ROBOTS, Accel, Angle, Bias, Distance, Duration, Float,
    FieldOfView, Friction, Int, Length, Mass, Name, Noise, Pose, PositiveFloat,
    PositiveInt, Probability, Rate, Region, Resolution, Section, Speed, Vec2,
)

# ---------------------------------------------------------------------------- world

MAX_SUBSTEPS = 100
MAX_SPEED = 20.0  # [m/s]: faster than any ground robot this simulator is for
MAX_ACCEL = 50.0  # [m/s^2]: 5 g, beyond what wheels on a floor can transmit


class WorldConfig(Section):
    """The arena: a ``size`` (walls around [0, w] x [0, h]) or a ``map`` file (its extent)."""

    # arena interior width, height [m]; with ``map`` left out (filled in from the map's extent)
    size: tuple[Length, Length] | None = None
    map: str | None = None  # ROS map YAML or SVG plan, relative to the scenario file
    map_scale: PositiveFloat | None = None  # SVG only: metres per SVG user unit (default 0.01)
    dt: Annotated[PositiveFloat, Field(le=0.1, ge=1e-4)] = 1.0 / 60.0  # physics step [s]
    # pymunk steps per dt: a count, taken in every tick; None or "adaptive" (the default): the
    # count computed so nothing tunnels, taken only in ticks where a contact can start (one
    # pymunk step in the others)
    substeps: Annotated[PositiveInt, Field(le=MAX_SUBSTEPS)] | Literal["adaptive"] | None = None
    duration: Duration = 30.0  # default run length [s]
    wall_friction: Friction = 0.5  # contact friction of the arena walls
    _map_path: str | None = PrivateAttr(default=None)  # ``map`` resolved (config.world_map)

    @property
    def map_path(self) -> str | None:
        """The absolute path ``map`` resolved to (None before it is, or without a map)."""
        return self._map_path

    def with_map_path(self, path: str, size: tuple[float, float]) -> "WorldConfig":
        """A copy of this world with ``map`` resolved to ``path`` and the map's ``size`` [m]."""
        sized = self.model_copy(update={"size": size})
        sized._map_path = path
        return sized

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) [m] of the arena: the map's extent, else (0, 0, width, height)."""
        geometry = self.map_geometry()
        if geometry is not None:
            return tuple(float(v) for v in geometry.extent)  # type: ignore[return-value]
        assert self.size is not None  # parse_scenario guarantees one of size and map
        return (0.0, 0.0, float(self.size[0]), float(self.size[1]))

    @property
    def arena(self) -> tuple[float, float]:
        """Width and height of the arena [m] (a map's extent when ``size`` was left out)."""
        if self.size is None:
            raise ValueError("world.size is not known before the map is loaded")
        return (float(self.size[0]), float(self.size[1]))

    def map_geometry(self) -> Any:
        """The :class:`~pymunk_bot.maps.outlines.MapGeometry` of ``map`` (loaded once), or None."""
        if self.map is None:
            return None
        from pymunk_bot.config.world_map import map_geometry
        return map_geometry(self)


# ---------------------------------------------------------------------------- obstacles


class _Solid(Section):
    friction: Friction = 0.5  # contact friction (pymunk multiplies the two shapes')
    movable: bool = False  # a dynamic body the robots can push
    mass: Mass = 1.0  # [kg], movable only
    ground_friction: Friction = 0.5  # floor friction coefficient mu, movable only
    motion: MotionConfig | None = None  # scripted path (a kinematic body); not with movable


class BoxObstacle(_Solid):
    type: Literal["box"]
    center: Vec2  # [m]
    size: tuple[Length, Length]  # width, height [m]
    angle: Angle = 0.0  # [rad]


class CircleObstacle(_Solid):
    type: Literal["circle"]
    center: Vec2  # [m]
    radius: Length  # [m]


class PolygonObstacle(_Solid):
    type: Literal["polygon"]
    points: Region  # outline [m], either winding, concave allowed


class WallObstacle(Section):
    type: Literal["wall"]
    start: Vec2  # [m]
    end: Vec2  # [m]
    thickness: Length = 0.05  # [m]
    friction: Friction = 0.5



# ---------------------------------------------------------------------------- sensors


class LidarConfig(Section):
    beams: Annotated[PositiveInt, Field(le=MAX_BEAMS)] = 360
    fov: FieldOfView = 2 * math.pi  # [rad], centred on the heading
    max_range: Annotated[PositiveFloat, Field(le=1e4)] = 8.0  # [m]
    min_range: Distance = 0.05  # [m]; closer returns read max_range (no return)
    noise_std: Annotated[Distance, Field(le=100)] = 0.0  # Gaussian range noise [m]
    rate: Rate = 10.0  # scans per second [Hz]
    offset: Pose = (0.0, 0.0, 0.0)  # mounting pose in the robot frame [m, m, rad]
    dropout: Probability = 0.0  # chance that a beam has no return (reads max_range)


class OdometryConfig(Section):
    wheel_noise_std: Noise = 0.0  # [m per sqrt(m)]: travel error std after 1 m
    # Fractional errors: odometry believes a wheel radius (track width) of true * (1 + error).
    left_scale_error: Annotated[Float, Field(gt=-1.0, le=10.0)] = 0.0  # left wheel radius
    right_scale_error: Annotated[Float, Field(gt=-1.0, le=10.0)] = 0.0  # right wheel radius
    track_width_error: Annotated[Float, Field(gt=-1.0, le=10.0)] = 0.0  # track width
    encoder_resolution: Resolution = 0.0  # wheel travel per encoder tick [m]; 0 = ideal


class ImuConfig(Section):
    rate: Rate | None = None  # [Hz]; None = every physics step
    gyro_noise_std: Noise = 0.0  # yaw-rate white noise [rad/s]
    gyro_bias: Bias = 0.0  # constant yaw-rate bias [rad/s]
    accel_noise_std: Noise = 0.0  # white noise per axis [m/s^2]
    accel_bias: tuple[Bias, Bias] = (0.0, 0.0)  # constant bias, robot frame [m/s^2]
    gyro_bias_walk: Noise = 0.0  # yaw-rate bias random walk [rad/s per sqrt(s)]
    accel_bias_walk: Noise = 0.0  # accel bias random walk per axis [m/s^2 per sqrt(s)]


# ---------------------------------------------------------------------------- robots


class GoalConfig(Section):
    position: Vec2  # [m]
    tolerance: Annotated[PositiveFloat, Field(le=1e4)] = 0.2  # [m]


class RobotConfig(Section):
    """Keys every robot has, whatever its drive; each drive's model adds its own (see drives)."""

    name: Name
    drive: str = "diff"  # a registered drive: diff (built in), or a plugin's
    pose: Pose  # x [m], y [m], theta [rad]
    radius: Length = 0.2  # [m] of the default disc footprint
    footprint: FootprintConfig | None = None  # robot frame; None: a disc of ``radius``
    mass: Mass = 5.0  # [kg]
    friction: Friction = 0.5  # contact friction of the robot's body
    # The pose estimate controllers see: a registered localizer's name or {type: name, ...}.
    localization: Any = "odometry"
    lidar: LidarConfig | None = None
    imu: ImuConfig | None = None
    controller: Any = None  # a registered controller's section; None: the robot stands still
    goal: GoalConfig | None = None
    # Build an occupancy grid from this robot's LiDAR (known poses; slam builds its own).
    mapping: MappingConfig | None = None

    def top_speed(self) -> float:
        """Fastest the robot's centre can move [m/s] (substeps are chosen from it)."""
        raise NotImplementedError


class DiffRobotConfig(RobotConfig):
    """A differential-drive robot: two wheels ``track_width`` apart."""

    drive: Literal["diff"] = "diff"
    track_width: Length = 0.3  # wheel separation [m]
    max_wheel_speed: Annotated[PositiveFloat, Field(le=MAX_SPEED)] = 1.0  # [m/s]
    max_accel: Annotated[PositiveFloat, Field(le=MAX_ACCEL)] = 3.0  # per wheel [m/s^2]
    odometry: OdometryConfig = OdometryConfig()

    def top_speed(self) -> float:
        return self.max_wheel_speed


# ---------------------------------------------------------------------------- expectations


class RobotExpectation(MetricBounds):  # + bounds on navigation metrics (metric_bounds.py)
    goal_reached: bool | None = None
    max_collisions: Annotated[Int, Field(ge=0, le=10**9)] | None = None
    within: Duration | None = None  # goal reached by this simulated time [s]
    min_clearance: Distance | None = None  # [m], closest approach to any obstacle
    max_path_length: Annotated[PositiveFloat, Field(le=1e7)] | None = None  # [m]
    never_enter: Annotated[list[Region], Field(max_length=100)] = []  # polygons the centre avoids
    end_in: Region | None = None  # polygon the robot's centre must end inside
    # [m] the localizer's position RMSE against the truth (needs a `localization` on the robot)
    localization_rmse: Annotated[PositiveFloat, Field(le=1e3)] | None = None
    localization_final_error: Annotated[PositiveFloat, Field(le=1e3)] | None = None  # [m] at the end


# ---------------------------------------------------------------------------- scenario


class ScenarioConfig(Section):
    """A whole scenario. Validate data with :func:`pymunk_bot.config.parse_scenario`: the model
    actually used is assembled from the registries (see ``config.assemble``), and the checks
    that span several keys run after it."""

    name: Name
    description: Annotated[str, Field(max_length=10_000)] = ""
    seed: Annotated[Int, Field(ge=0)] = 0
    world: WorldConfig
    obstacles: Annotated[list[Any], Field(max_length=MAX_OBSTACLES)] = []  # registered kinds' sections
    robots: list[RobotConfig] = Field(min_length=1, max_length=MAX_ROBOTS)
    expect: dict[str, RobotExpectation] = {}
    events: EventList = []  # things that happen at a simulated time (config/events.py)

    # The full validation (the schema assembled from the registries, then the checks across
    # keys) lives above this module; config/loader.py installs it here when it is imported.
    full_validation: ClassVar[Callable[[Any, str], "ScenarioConfig"] | None] = None

    @classmethod
    def model_validate(cls, obj: Any, *args: Any, **kwargs: Any) -> "ScenarioConfig":
        """On this base class: the full validation a file gets (a ScenarioError on bad data)."""
        if cls is ScenarioConfig and ScenarioConfig.full_validation is not None:
            return ScenarioConfig.full_validation(obj, "<data>")
        return super().model_validate(obj, *args, **kwargs)
