"""The scenario file as frozen pydantic models: every key, its unit and its default.

docs/scenario-format.md documents each key; keep the two in step.
"""
from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import Field

from .footprint import FootprintConfig
from .motion import MotionConfig
from .types import (
    Float, FieldOfView, Int, Length, Mass, Name, NonNegativeFloat, Pose, PositiveFloat, PositiveInt,
    Probability, Section, Vec2,
)

# ---------------------------------------------------------------------------- world

MAX_SUBSTEPS = 100


class WorldConfig(Section):
    size: tuple[Length, Length]  # arena interior width, height [m]
    dt: Annotated[PositiveFloat, Field(le=0.1, ge=1e-4)] = 1.0 / 60.0  # physics step [s]
    # pymunk steps per dt; None = computed so nothing tunnels
    substeps: Annotated[PositiveInt, Field(le=MAX_SUBSTEPS)] | None = None
    duration: PositiveFloat = 30.0  # default run length [s]
    wall_friction: NonNegativeFloat = 0.5  # contact friction of the arena walls


# ---------------------------------------------------------------------------- obstacles


class _Solid(Section):
    friction: NonNegativeFloat = 0.5  # contact friction (pymunk multiplies the two shapes')
    movable: bool = False  # a dynamic body the robots can push
    mass: Mass = 1.0  # [kg], movable only
    ground_friction: NonNegativeFloat = 0.5  # floor friction coefficient mu, movable only
    motion: MotionConfig | None = None  # scripted path (a kinematic body); not with movable


class BoxObstacle(_Solid):
    type: Literal["box"]
    center: Vec2  # [m]
    size: tuple[Length, Length]  # width, height [m]
    angle: Float = 0.0  # [rad]


class CircleObstacle(_Solid):
    type: Literal["circle"]
    center: Vec2  # [m]
    radius: Length  # [m]


class PolygonObstacle(_Solid):
    type: Literal["polygon"]
    points: list[Vec2] = Field(min_length=3)  # outline [m], either winding, concave allowed


class WallObstacle(Section):
    type: Literal["wall"]
    start: Vec2  # [m]
    end: Vec2  # [m]
    thickness: Length = 0.05  # [m]
    friction: NonNegativeFloat = 0.5



# ---------------------------------------------------------------------------- sensors


class LidarConfig(Section):
    beams: PositiveInt = 360
    fov: FieldOfView = 2 * math.pi  # [rad], centred on the heading
    max_range: PositiveFloat = 8.0  # [m]
    min_range: NonNegativeFloat = 0.05  # [m]; closer returns read max_range (no return)
    noise_std: NonNegativeFloat = 0.0  # Gaussian range noise [m]
    rate: PositiveFloat = 10.0  # scans per second [Hz]
    offset: Pose = (0.0, 0.0, 0.0)  # mounting pose in the robot frame [m, m, rad]
    dropout: Probability = 0.0  # chance that a beam has no return (reads max_range)


class OdometryConfig(Section):
    wheel_noise_std: NonNegativeFloat = 0.0  # [m per sqrt(m)]: travel error std after 1 m
    # Fractional errors: odometry believes a wheel radius (track width) of true * (1 + error).
    left_scale_error: Annotated[Float, Field(gt=-1.0)] = 0.0  # left wheel radius
    right_scale_error: Annotated[Float, Field(gt=-1.0)] = 0.0  # right wheel radius
    track_width_error: Annotated[Float, Field(gt=-1.0)] = 0.0  # track width
    encoder_resolution: NonNegativeFloat = 0.0  # wheel travel per encoder tick [m]; 0 = ideal


class ImuConfig(Section):
    rate: PositiveFloat | None = None  # [Hz]; None = every physics step
    gyro_noise_std: NonNegativeFloat = 0.0  # yaw-rate white noise [rad/s]
    gyro_bias: Float = 0.0  # constant yaw-rate bias [rad/s]
    accel_noise_std: NonNegativeFloat = 0.0  # white noise per axis [m/s^2]
    accel_bias: Vec2 = (0.0, 0.0)  # constant bias, robot frame [m/s^2]
    gyro_bias_walk: NonNegativeFloat = 0.0  # yaw-rate bias random walk [rad/s per sqrt(s)]
    accel_bias_walk: NonNegativeFloat = 0.0  # accel bias random walk per axis [m/s^2 per sqrt(s)]


# ---------------------------------------------------------------------------- robots


class GoalConfig(Section):
    position: Vec2  # [m]
    tolerance: PositiveFloat = 0.2  # [m]


class RobotConfig(Section):
    """Keys every robot has, whatever its drive; each drive's model adds its own (see drives)."""

    name: Name
    drive: str = "diff"  # a registered drive: diff (built in), or a plugin's
    pose: Pose  # x [m], y [m], theta [rad]
    radius: Length = 0.2  # [m] of the default disc footprint
    footprint: FootprintConfig | None = None  # robot frame; None: a disc of ``radius``
    mass: Mass = 5.0  # [kg]
    friction: NonNegativeFloat = 0.5  # contact friction of the robot's body
    # The pose estimate controllers see: a registered localizer's name or {type: name, ...}.
    localization: Any = "odometry"
    lidar: LidarConfig | None = None
    imu: ImuConfig | None = None
    controller: Any = None  # a registered controller's section; None: the robot stands still
    goal: GoalConfig | None = None

    def top_speed(self) -> float:
        """Fastest the robot's centre can move [m/s] (substeps are chosen from it)."""
        raise NotImplementedError


class DiffRobotConfig(RobotConfig):
    """A differential-drive robot: two wheels ``track_width`` apart."""

    drive: Literal["diff"] = "diff"
    track_width: Length = 0.3  # wheel separation [m]
    max_wheel_speed: PositiveFloat = 1.0  # [m/s]
    max_accel: PositiveFloat = 3.0  # per wheel [m/s^2]
    odometry: OdometryConfig = OdometryConfig()

    def top_speed(self) -> float:
        return self.max_wheel_speed


# ---------------------------------------------------------------------------- expectations


class RobotExpectation(Section):
    goal_reached: bool | None = None
    max_collisions: Annotated[Int, Field(ge=0)] | None = None
    within: PositiveFloat | None = None  # goal reached by this simulated time [s]
    min_clearance: NonNegativeFloat | None = None  # [m], closest approach to any obstacle
    max_path_length: PositiveFloat | None = None  # [m]
    never_enter: list[list[Vec2]] = []  # polygons the robot's centre must never enter
    end_in: list[Vec2] | None = None  # polygon the robot's centre must end inside


# ---------------------------------------------------------------------------- scenario


class ScenarioConfig(Section):
    """A whole scenario. Validate data with :func:`pymunk_bot.config.parse_scenario`: the model
    actually used is assembled from the registries (see ``config.assemble``), and the checks
    that span several keys run after it."""

    name: Name
    description: str = ""
    seed: Annotated[Int, Field(ge=0)] = 0
    world: WorldConfig
    obstacles: list[Any] = []  # each a registered obstacle kind's section
    robots: list[RobotConfig] = Field(min_length=1)
    expect: dict[str, RobotExpectation] = {}

    @classmethod
    def model_validate(cls, obj: Any, *args: Any, **kwargs: Any) -> "ScenarioConfig":  # type: ignore[override]
        """On this base class: the full validation a file gets (a ScenarioError on bad data)."""
        if cls is ScenarioConfig:
            from .loader import parse_scenario
            return parse_scenario(obj, "<data>")
        return super().model_validate(obj, *args, **kwargs)
