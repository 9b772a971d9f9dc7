"""The ``plan_guidance`` settings of the ``policy`` controller, the envs and policy files: its
own module, since the policy files (``pymunk_bot.policy.files``) read it and the controller
sections (``config.controllers``) read the policy files."""
from __future__ import annotations

from typing import Annotated, Any

from pydantic import Field, ValidationError

from pymunk_bot.config.types import Distance, Duration, PositiveShort, Section


class PlanGuidanceConfig(Section):
    """Plan-guided goal features (``plan_guidance`` of the ``policy`` controller and of the
    envs; docs/learning.md): the goal a policy sees is a point ``lookahead`` metres along an
    A* path on the map the robot knows instead of the final goal."""

    lookahead: Annotated[PositiveShort, Field(le=20)] = 1.5  # [m] along the path
    replan_period: Annotated[Duration, Field(le=60)] = 1.0  # [s] between checks for a replan
    off_path: Annotated[PositiveShort, Field(le=20)] = 1.0  # [m] farther than this: replan
    resolution: Annotated[Distance, Field(ge=0.02, le=1)] = 0.1  # [m] planning grid cell

    def as_array(self) -> list[float]:
        """The settings as numbers, in field order (what a policy file records)."""
        return [float(getattr(self, name)) for name in type(self).model_fields]

    @classmethod
    def from_array(cls, values: Any) -> "PlanGuidanceConfig":
        """Settings from :meth:`as_array`'s numbers; ValueError if they are not."""
        numbers = [float(v) for v in values]
        names = list(cls.model_fields)
        if len(numbers) != len(names):
            raise ValueError(f"plan_guidance holds {len(numbers)} numbers, not "
                             f"{len(names)} ({', '.join(names)})")
        settings = cls.of(dict(zip(names, numbers)))
        assert settings is not None  # a mapping gives settings
        return settings

    @classmethod
    def of(cls, value: Any) -> "PlanGuidanceConfig | None":
        """Settings from what a user passes: None or False (off), True (the defaults), a
        mapping of some keys, or settings; ValueError in one line naming the key if bad."""
        if value is None or value is False:
            return None
        if value is True:
            return cls()
        if isinstance(value, cls):
            return value
        if not isinstance(value, dict):
            raise ValueError(f"plan_guidance must be true, false or a mapping of "
                             f"{', '.join(cls.model_fields)} (got {value!r:.80})")
        try:
            return cls(**value)
        except ValidationError as exc:
            error = exc.errors()[0]
            key = ".".join(str(part) for part in error["loc"])
            raise ValueError(f"plan_guidance.{key}: {error['msg']} "
                             f"(got {error.get('input')!r:.40})") from None
