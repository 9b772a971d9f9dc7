"""A controller that kills its own process when told to: a worker dying mid-sweep."""
from __future__ import annotations

import os


class DiesWhenTold:
    def __init__(self, robot, die: bool = False) -> None:
        self.die = die

    def compute(self, observation) -> tuple[float, float]:
        if self.die:
            os._exit(17)  # no exception, no cleanup: the worker process is simply gone
        return 0.3, 0.3
