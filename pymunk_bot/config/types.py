"""Strict scalar and vector types shared by every scenario section.

Scalars are strict (a YAML string "1.0" or a bool is not a number) and finite (no NaN/inf).
"""
from __future__ import annotations

import math
from typing import Annotated

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, Strict

# Every number is finite and within +-1e9: beyond that, products of two values overflow and
# pymunk's arithmetic (its winding asserts) breaks down. Fields add tighter physical ranges.
MAX_ABS = 1e9
Float = Annotated[float, Strict(), Field(allow_inf_nan=False, ge=-MAX_ABS, le=MAX_ABS)]
PositiveFloat = Annotated[Float, Field(gt=0)]
NonNegativeFloat = Annotated[Float, Field(ge=0)]
Probability = Annotated[Float, Field(ge=0, lt=1)]
# Physical sizes and masses have sane bounds: pymunk turns a 1e-150 m radius into NaN poses.
Length = Annotated[Float, Field(ge=1e-3, le=1e4)]  # [m], 1 mm .. 10 km
Mass = Annotated[Float, Field(ge=1e-3, le=1e6)]  # [kg]
Coordinate = Annotated[Float, Field(ge=-1e6, le=1e6)]  # [m], a point in the world
Distance = Annotated[Float, Field(ge=0, le=1e4)]  # [m], a range, tolerance or margin
Speed = Annotated[Float, Field(gt=0, le=100)]  # [m/s]
Accel = Annotated[Float, Field(gt=0, le=1e3)]  # [m/s^2]
Rate = Annotated[Float, Field(gt=0, le=1e3)]  # [Hz]: a controller or sensor at most 1 kHz
Gain = Annotated[Float, Field(ge=0, le=1e3)]  # a dimensionless weight or a controller gain
Friction = Annotated[Float, Field(ge=0, le=100)]  # contact / floor friction coefficient
Duration = Annotated[Float, Field(gt=0, le=86_400)]  # [s], at most one simulated day
Short = Annotated[Float, Field(ge=0, le=100)]  # [m], a margin or radius at robot scale
PositiveShort = Annotated[Float, Field(gt=0, le=100)]  # a look-ahead [m] or [s], a cap [m]
Angle = Annotated[Float, Field(ge=-1e3, le=1e3)]  # [rad]; |angle| > 2 pi warns (degrees?)
Noise = Annotated[Float, Field(ge=0, le=1e3)]  # a noise std or random-walk rate, sensor's unit
Bias = Annotated[Float, Field(ge=-1e3, le=1e3)]  # a sensor bias, in the sensor's unit
Int = Annotated[int, Strict(), Field(ge=-(2**63), le=2**63 - 1)]
PositiveInt = Annotated[Int, Field(gt=0)]
Vec2 = tuple[Coordinate, Coordinate]
Pose = tuple[Coordinate, Coordinate, Angle]
# Counts that size memory or time.
MAX_OBSTACLES = 2000
MAX_ROBOTS = 20_000  # a swarm; memory and time grow linearly (checks as n log n)
MAX_POLYGON_POINTS = 2000
MAX_WAYPOINTS = 1000
MAX_BEAMS = 4096
Region = Annotated[list[Vec2], Field(min_length=3, max_length=MAX_POLYGON_POINTS)]  # a polygon
Name = Annotated[str, Strict(), Field(pattern=r"^[a-z0-9_-]+$", min_length=1, max_length=64)]


def _zero_or_at_least_a_nanometre(value: float) -> float:
    if 0 < value < 1e-9:
        raise ValueError(f"must be 0 or >= 1e-09 (got {value:g})")
    return value


# A resolution or step where 0 means "ideal": tiny positive values would overflow the counts.
Resolution = Annotated[Float, Field(ge=0, le=1.0), AfterValidator(_zero_or_at_least_a_nanometre)]


def _angle_within_full_circle(value: float) -> float:
    if not 0 < value <= 2 * math.pi + 1e-12:
        raise ValueError(f"must be in (0, 2*pi] (got {value})")
    return value


FieldOfView = Annotated[Float, AfterValidator(_angle_within_full_circle)]


class Section(BaseModel):
    """Base of every scenario section: frozen, unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True)
