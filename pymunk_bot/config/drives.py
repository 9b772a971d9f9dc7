"""Robot sections of the car-like (``ackermann``) and omnidirectional (``omni``) drives.

docs/scenario-format.md and docs/physics.md document each key; keep them in step.
"""
from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field

from pymunk_bot.config.schema import RobotConfig
from pymunk_bot.config.types import Float, Length, NonNegativeFloat, PositiveFloat, Section

MAX_STEER = 1.4  # [rad] (80 deg): beyond this tan() makes the turning circle degenerate
_Fraction = Annotated[Float, Field(gt=-1.0, lt=1.0)]


class AckermannOdometryConfig(Section):
    """Rear-wheel encoders plus a steering-angle sensor, with the errors real ones have."""

    wheel_noise_std: NonNegativeFloat = 0.0  # [m per sqrt(m)]: rear-wheel travel error after 1 m
    left_scale_error: _Fraction = 0.0  # believed rear-left wheel radius = true * (1 + this)
    right_scale_error: _Fraction = 0.0  # believed rear-right wheel radius = true * (1 + this)
    encoder_resolution: NonNegativeFloat = 0.0  # wheel travel per encoder tick [m]; 0 = ideal
    steer_scale_error: _Fraction = 0.0  # measured steering angle = true * (1 + this) + offset
    steer_offset: Annotated[Float, Field(ge=-0.2, le=0.2)] = 0.0  # [rad] steering sensor bias
    steer_noise_std: NonNegativeFloat = 0.0  # [rad per sqrt(m)]: steering-angle error averaged
    # over each metre driven, so the heading error is a random walk in distance
    steer_resolution: NonNegativeFloat = 0.0  # [rad] per step of the steering sensor; 0 = ideal
    wheelbase_error: _Fraction = 0.0  # believed wheelbase = true * (1 + this)


class AckermannRobotConfig(RobotConfig):
    """A car: the bicycle model through the middle of the rear axle (the pose point)."""

    drive: Literal["ackermann"]
    wheelbase: Length = 0.33  # rear axle to front axle [m]
    track_width: Length = 0.25  # between the rear wheels [m] (their encoders)
    max_steer: Annotated[PositiveFloat, Field(le=MAX_STEER)] = 0.5  # |steering angle| [rad]
    max_steer_rate: PositiveFloat = 3.0  # steering slew rate [rad/s]
    max_speed: PositiveFloat = 2.0  # forward and reverse [m/s]
    max_accel: PositiveFloat = 3.0  # [m/s^2]
    odometry: AckermannOdometryConfig = AckermannOdometryConfig()

    def min_turn_radius(self) -> float:
        """Tightest circle the rear-axle middle can drive [m]."""
        return self.wheelbase / math.tan(self.max_steer)

    def top_speed(self) -> float:
        # Any point of the footprint: v + omega * reach, with omega <= v / R_min.
        from pymunk_bot.geometry.footprint import of_robot
        return self.max_speed * (1.0 + of_robot(self).bounding_radius / self.min_turn_radius())


class OmniOdometryConfig(Section):
    """Wheel encoders of a mecanum (4 wheels) or three-wheel omni base."""

    wheel_noise_std: NonNegativeFloat = 0.0  # [m per sqrt(m)]: wheel travel error after 1 m
    scale_errors: list[_Fraction] = Field(default=[], max_length=4)  # per wheel, fractional
    # believed wheel radius errors, in wheel order (see docs); missing wheels have none
    encoder_resolution: NonNegativeFloat = 0.0  # wheel travel per encoder tick [m]; 0 = ideal
    wheel_distance_error: _Fraction = 0.0  # believed wheel_distance = true * (1 + this)


class OmniRobotConfig(RobotConfig):
    """Moves in any direction: body velocity (vx, vy, omega) in the robot frame."""

    drive: Literal["omni"]
    max_speed: PositiveFloat = 1.0  # limit on the norm of (vx, vy) [m/s]
    max_angular_speed: PositiveFloat = 2.0  # [rad/s]
    max_accel: PositiveFloat = 3.0  # on the norm of (ax, ay) [m/s^2]
    max_angular_accel: PositiveFloat = 8.0  # [rad/s^2]
    wheels: Literal["mecanum", "omni3"] = "mecanum"  # wheel layout, for the encoders
    # mecanum: half length + half width of the wheel rectangle; omni3: centre-to-wheel [m]
    wheel_distance: Length = 0.25
    odometry: OmniOdometryConfig = OmniOdometryConfig()

    def top_speed(self) -> float:
        from pymunk_bot.geometry.footprint import of_robot
        return self.max_speed + self.max_angular_speed * of_robot(self).bounding_radius
