"""The ``crowd_state`` sensor's section: the pedestrians' true states, as CrowdNav's agents see
them (``sensors/crowd_state.py``)."""
from __future__ import annotations

from typing import Annotated

from pydantic import Field

from pymunk_bot.config.types import PositiveFloat, PositiveInt, Section

MAX_HUMANS_SEEN = 500


class CrowdStateConfig(Section):
    """``crowd_state: {max_humans: 10, max_range: null}`` on a robot: its controller reads the
    nearest ``max_humans`` pedestrians within ``max_range`` [m] (None: any distance), exactly:
    positions, velocities and radii (``obs.extra["crowd_state"]``)."""

    max_humans: Annotated[PositiveInt, Field(le=MAX_HUMANS_SEEN)] = 10
    max_range: Annotated[PositiveFloat, Field(le=1e4)] | None = None  # [m] between centres
