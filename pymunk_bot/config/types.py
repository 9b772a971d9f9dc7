"""Strict scalar and vector types shared by every scenario section.

Scalars are strict (a YAML string "1.0" or a bool is not a number) and finite (no NaN/inf).
"""
from __future__ import annotations

import math
from typing import Annotated

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, Strict

Float = Annotated[float, Strict(), Field(allow_inf_nan=False)]
PositiveFloat = Annotated[Float, Field(gt=0)]
NonNegativeFloat = Annotated[Float, Field(ge=0)]
Probability = Annotated[Float, Field(ge=0, lt=1)]
# Physical sizes and masses have sane bounds: pymunk turns a 1e-150 m radius into NaN poses.
Length = Annotated[Float, Field(ge=1e-3, le=1e4)]  # [m], 1 mm .. 10 km
Mass = Annotated[Float, Field(ge=1e-3, le=1e6)]  # [kg]
Int = Annotated[int, Strict()]
PositiveInt = Annotated[Int, Field(gt=0)]
Vec2 = tuple[Float, Float]
Pose = tuple[Float, Float, Float]
Name = Annotated[str, Strict(), Field(pattern=r"^[a-z0-9_-]+$", min_length=1, max_length=64)]


def _angle_within_full_circle(value: float) -> float:
    if not 0 < value <= 2 * math.pi + 1e-12:
        raise ValueError(f"must be in (0, 2*pi] (got {value})")
    return value


FieldOfView = Annotated[Float, AfterValidator(_angle_within_full_circle)]


class Section(BaseModel):
    """Base of every scenario section: frozen, unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True)
