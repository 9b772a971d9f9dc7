"""A run's file written as it goes and/or a live server (Foxglove, rosbridge): what both share."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass
class ServedOutputs:
    """A log written while the run goes (``save()``, ``abort()``, ``path``, ``steps``) and/or
    a live server (``stop()``), paced at real time x ``speed`` while it serves."""

    log: Any = None  # McapLogger, Ros2BagLogger, ...
    server: Any = None  # LiveServer, RosbridgeServer, ...
    speed: float = 1.0
    kind: str = ""  # how the log is named when it is written, e.g. "ROS 2 bag, "

    @property
    def live(self) -> bool:
        """A server is running."""
        return self.server is not None

    def run_headless(self, sim: Any, duration: float) -> None:
        """Run ``sim``; paced at real time x speed while serving."""
        if self.server is None:
            sim.run(duration)
            return
        from pymunk_bot.foxglove.live import run_paced

        run_paced(sim, duration, self.speed)

    def finish(self) -> None:
        """Complete the log and stop the server; a log that cannot be written (OSError naming
        it) is removed, and the server stopped all the same."""
        try:
            if self.log is not None:
                self.log.save()
                print(f"wrote {self.log.path} ({self.kind}{self.log.steps} steps)")
                self.log = None
        finally:
            self.close()

    def close(self) -> None:
        """Drop an unfinished log and stop the server (after an error or Ctrl-C too)."""
        if self.log is not None:
            self.log.abort()
            self.log = None
        if self.server is not None:
            self.server.stop()
            self.server = None
