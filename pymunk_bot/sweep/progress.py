"""Progress of a sweep or a benchmark on stderr, wherever stderr goes.

On a terminal, tqdm's bar. Elsewhere (a CI log, a notebook, a file) a bar's carriage returns
would pile up or vanish, so a plain line is printed each time another twentieth of the work is
done (at most 20 lines, whatever the total), with the time left estimated from this run's pace.
"""
from __future__ import annotations

import math
import sys
import time
from typing import IO, Any

LINES = 20  # plain lines at most over a whole run (one per 5 %)


def duration_text(seconds: float) -> str:
    """``3725.0`` -> ``1 h 2 min``; ``190.0`` -> ``3 min 10 s``; ``4.2`` -> ``4 s``."""
    seconds = max(0.0, seconds)
    if seconds < 1.0:
        return "under 1 s"
    whole = round(seconds)
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    if hours:
        return f"{hours} h {minutes} min"
    return f"{minutes} min {secs} s" if minutes else f"{secs} s"


class Progress:
    """Counts finished items (``update``) out of ``total``; ``enabled=False`` shows nothing.
    ``initial`` items were done before (a resumed sweep): they do not count towards the pace.
    """

    def __init__(self, total: int, desc: str, unit: str, enabled: bool = True,
                 initial: int = 0, stream: IO[str] | None = None) -> None:
        self.total, self.done, self.desc, self.unit = total, initial, desc, unit
        self._stream = sys.stderr if stream is None else stream
        self._initial = initial
        self._started = time.monotonic()
        self._step = max(1, math.ceil(total / LINES))
        self._next = (initial // self._step + 1) * self._step
        self._bar: Any = None
        self._lines = enabled and not _is_terminal(self._stream)
        if enabled and not self._lines:
            from tqdm import tqdm
            self._bar = tqdm(total=total, initial=initial, unit=unit.rstrip("s"), desc=desc,
                             leave=False, file=self._stream)

    def update(self, n: int) -> None:
        """``n`` more items are finished."""
        self.done += n
        if self._bar is not None:
            self._bar.update(n)
        elif self._lines and (self.done >= self._next or self.done >= self.total):
            self._next = (self.done // self._step + 1) * self._step
            print(self.line(), file=self._stream, flush=True)

    def line(self) -> str:
        """``benchmark: 500/10000 episodes (5 %), about 3 min 10 s left``."""
        elapsed = time.monotonic() - self._started
        percent = 100 * self.done // max(1, self.total)
        head = f"{self.desc}: {self.done}/{self.total} {self.unit} ({percent} %)"
        if self.done >= self.total:
            return f"{head}, done in {duration_text(elapsed)}"
        paced = self.done - self._initial
        if paced <= 0:
            return head
        left = elapsed / paced * (self.total - self.done)
        return f"{head}, about {duration_text(left)} left"

    def close(self) -> None:
        """Take the bar off the terminal (plain lines need nothing)."""
        if self._bar is not None:
            self._bar.close()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _is_terminal(stream: IO[str]) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False
