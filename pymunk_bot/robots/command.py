"""What a controller (or a user) asks of a robot: a body-frame velocity."""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Command:
    """Body-frame velocity: forward ``v`` [m/s], yaw rate ``omega`` [rad/s], lateral ``vy`` [m/s].

    Every drive takes one; a drive limits it to what it can do (an ackermann robot turns no
    tighter than its steering allows, only an omni robot moves sideways).
    """

    v: float = 0.0
    omega: float = 0.0
    vy: float = 0.0

    def __post_init__(self) -> None:
        v, omega, vy = self.v, self.omega, self.vy
        if (type(v) is float and type(omega) is float and type(vy) is float and  # the usual case
                math.isfinite(v) and math.isfinite(omega) and math.isfinite(vy)):
            return
        for name in ("v", "omega", "vy"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise ValueError(f"command {name} must be a finite number (got {value!r})")


STOP = Command()
