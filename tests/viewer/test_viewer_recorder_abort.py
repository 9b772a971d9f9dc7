"""An interrupt can strike a recording inside the frame queue's own locking; the abort that
follows must still stop the writer thread at once (it once waited for ever: a SIGTERM during
`run --record` left the process hung)."""
from __future__ import annotations

import random
import signal
import threading
import time

import pytest

pytest.importorskip("pygame")

from pymunk_bot.viewer.recorder import _Background  # noqa: E402

TRIALS = 2000  # the old abort hung about once in a thousand


class _SlowEncoder:
    """An encoder that takes 0-2 ms a frame, so the queue is full and `append` waits on it."""

    def __init__(self, rng: random.Random) -> None:
        self.rng = rng

    def append(self, frame: bytes) -> None:
        time.sleep(self.rng.uniform(0.0, 0.002))

    def abort(self) -> None:
        pass

    def close(self) -> None:
        pass


def _terminate(signum, frame):
    raise SystemExit(128 + signum)


@pytest.mark.slow
def test_an_abort_after_an_interrupt_in_append_stops_the_writer_at_once():
    rng = random.Random(0)
    previous = signal.signal(signal.SIGALRM, _terminate)
    try:
        for trial in range(TRIALS):
            background = _Background(_SlowEncoder(rng))
            with pytest.raises(SystemExit):
                # armed inside: a timer of 0.5 ms could fire in pytest.raises' own set-up
                signal.setitimer(signal.ITIMER_REAL, rng.uniform(0.0005, 0.01))
                while True:
                    background.append(b"frame")
            aborting = threading.Thread(target=background.abort, daemon=True)
            aborting.start()
            aborting.join(timeout=_Background.ABORT_WAIT + 3.0)
            assert not aborting.is_alive(), f"abort hung after trial {trial}'s interrupt"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
