"""The ``footprint`` section of a robot: its outline in the robot frame (origin = the pose point).

docs/scenario-format.md documents each key; keep the two in step.
"""
from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import Field

from pymunk_bot.config.types import Length, Section, Vec2

MAX_FOOTPRINT_POINTS = 64


class CircleFootprint(Section):
    """A disc (the default footprint is one of the robot's ``radius`` about the pose point)."""

    type: Literal["circle"]
    radius: Length  # [m]
    center: Vec2 = (0.0, 0.0)  # [m], robot frame


class BoxFootprint(Section):
    """A rectangle aligned with the robot: ``size`` = (length along x, width along y)."""

    type: Literal["box"]
    size: tuple[Length, Length]  # [m]
    center: Vec2 = (0.0, 0.0)  # [m], robot frame


class PolygonFootprint(Section):
    """Any simple outline, convex or concave, either winding (split into convex pieces)."""

    type: Literal["polygon"]
    points: list[Vec2] = Field(min_length=3, max_length=MAX_FOOTPRINT_POINTS)  # [m], robot frame


FootprintConfig = Annotated[Union[CircleFootprint, BoxFootprint, PolygonFootprint],
                            Field(discriminator="type")]
