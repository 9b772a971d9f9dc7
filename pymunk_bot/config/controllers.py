"""Controller sections (`controller: {type: ...}`), one model per controller type."""
from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import Field

from .types import Float, NonNegativeFloat, PositiveFloat, Section, Vec2


class WheelsControllerConfig(Section):
    """Constant wheel speeds."""

    type: Literal["wheels"]
    left: Float = 0.0  # [m/s]
    right: Float = 0.0  # [m/s]
    rate: PositiveFloat = 10.0  # [Hz]


class GoToGoalControllerConfig(Section):
    """Proportional steering toward a point: v = k_rho * distance, omega = k_alpha * bearing."""

    type: Literal["go_to_goal"]
    goal: Vec2 | None = None  # [m]; None = the robot's goal
    rate: PositiveFloat = 10.0  # [Hz]
    k_rho: PositiveFloat = 1.0  # [1/s]
    k_alpha: PositiveFloat = 3.0  # [1/s]
    max_speed: PositiveFloat | None = None  # [m/s]; None = the robot's max wheel speed
    tolerance: NonNegativeFloat | None = None  # [m] stop radius; None = the goal's tolerance


ControllerConfig = Annotated[
    Union[WheelsControllerConfig, GoToGoalControllerConfig],
    Field(discriminator="type"),
]
