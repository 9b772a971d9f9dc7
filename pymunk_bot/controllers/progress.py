"""How long a controller has gone without progress, so that it never stands still for ever.

Every goal-driving controller measures its own progress (along its path, or toward its goal)
and hands it to a :class:`ProgressWatch` at each tick; after ``give_up_after`` seconds without
``step`` of it the controller fails with a message that says where and for how long. Nothing
resets the clock but progress (a replan or a hand-over from a manual override does not), so a
robot left somewhere it cannot drive away from ends with a status instead of idling.
"""
from __future__ import annotations

import math

PROGRESS_STEP = 0.1  # [m] of progress that counts


class ProgressWatch:
    """Seconds since the watched measure (larger is better, in metres) last grew by ``step``."""

    def __init__(self, step: float = PROGRESS_STEP) -> None:
        self.step = step  # [m]
        self.best = -math.inf  # [m] the best measure since the last progress
        self.since: float | None = None  # [s] when it last grew by a step

    def update(self, time: float, measure: float) -> float:
        """Record ``measure`` [m] at ``time`` [s]; return the seconds without progress."""
        if self.since is None or measure > self.best + self.step:
            self.best, self.since = measure, time
        return self.stalled(time)

    def stalled(self, time: float) -> float:
        """Seconds without progress at ``time`` [s] (0 before the first measure)."""
        return 0.0 if self.since is None else time - self.since

    def rebase(self, measure: float) -> None:
        """A new yardstick (a new path): progress counts from ``measure`` [m] on, but the time
        without progress keeps running."""
        self.best = measure

    def mark(self, time: float, measure: float) -> None:
        """Progress made at ``time`` [s] (e.g. a path segment's end); ``measure`` [m] from now."""
        self.best, self.since = measure, time

    def restart(self) -> None:
        """A new task (a new goal): no time without progress yet."""
        self.best, self.since = -math.inf, None


def no_progress_message(stalled: float, pose) -> str:
    """The failure message of a robot at ``pose`` that made no progress for ``stalled`` [s]."""
    return (f"no progress toward the goal for {stalled:.0f} s; stopped at "
            f"({float(pose[0]):.2f}, {float(pose[1]):.2f})")
