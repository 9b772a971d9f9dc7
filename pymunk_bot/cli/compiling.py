"""numba's first compile, said aloud and kept out of a run's speed (issue 35).

pymunk-bot's kernels are compiled by numba with ``cache=True``: the first run after installing
(or upgrading, or with an empty ``NUMBA_CACHE_DIR``) compiles those the scenario uses, which
takes tens of seconds, and every later run loads them from the cache in a fraction of that.
:class:`CompileWatch` listens to numba's own ``numba:compile`` events, which numba raises only
when it really compiles (not when it loads from its cache), so it needs no list of kernels:
the first compile prints one line on stderr saying what is happening and about how long it
takes, and the ticks during which numba compiled are kept out of the run's ``wall_time`` and
``real_time_factor`` (the whole tick: numba also writes its cache after the compile event; a
handful of ticks among thousands, so the factor is the steps' speed to well under 1 %).
numba compiles while the scenario is built, before the run's output options are checked: the
note waits until they are (:meth:`CompileWatch.release`), so a run refused for bad input still
prints exactly one line.
"""
from __future__ import annotations

import sys
import time
from typing import TextIO

FIRST_COMPILE_ESTIMATE = "about 30 s"  # measured: 26 s for the maze on a 2-core machine
ANNOUNCEMENT = (f"note: compiling pymunk-bot's numba kernels for this machine, once "
                f"({FIRST_COMPILE_ESTIMATE}; later runs load them from numba's cache); the "
                "compile time is not counted in the real-time factor")


class CompileWatch:
    """Time spent in numba compiles while it is open (a context manager).

    ``seconds`` [s] is the wall time of the outermost compiles so far (a kernel that calls
    another compiles it inside its own compile: counted once). Without numba it stays 0.
    ``stream`` (default stderr) hears of the first compile, once :meth:`release` is called.
    """

    def __init__(self, stream: TextIO | None = None) -> None:
        self._stream: TextIO = stream or sys.stderr
        self._held = True  # the note waits until the run is known to go ahead
        self.seconds = 0.0
        self.compiles = 0  # outermost compiles so far
        self._seen: tuple[int, float] = (0, 0.0)  # compiles, the run's wall_time after a tick
        self._depth = 0
        self._started = 0.0
        self._announced = False
        self._listener: object | None = None

    def __enter__(self) -> "CompileWatch":
        try:
            from numba.core import event
        except ImportError:  # no numba: the numpy fallbacks compile nothing
            return self
        watch = self

        class _Listener(event.Listener):
            def on_start(self, ev: object) -> None:
                watch.compile_started()

            def on_end(self, ev: object) -> None:
                watch.compile_ended()

        self._listener = _Listener()
        event.register("numba:compile", self._listener)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._listener is not None:
            from numba.core import event

            event.unregister("numba:compile", self._listener)
            self._listener = None

    def release(self) -> None:
        """The run goes ahead (its input was good): say now if numba is compiling, or has."""
        self._held = False
        if self.compiles or self._depth:
            self._announce()

    def report(self) -> None:
        """After the run: how long compiling took, if it was announced."""
        if self._announced:
            print(f"note: compiling took {self.seconds:.1f} s", file=self._stream, flush=True)

    def _announce(self) -> None:
        if not self._announced:
            self._announced = True
            print(ANNOUNCEMENT, file=self._stream, flush=True)

    def compile_started(self) -> None:
        """numba starts a compile (nested ones count with the outermost)."""
        if self._depth == 0:
            if not self._held:
                self._announce()
            self._started = time.perf_counter()
        self._depth += 1

    def compile_ended(self) -> None:
        """numba ends a compile."""
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._started
            self.compiles += 1

    # An observer of the run (``Simulation.attach``): called after every tick.
    def on_reset(self, sim) -> None:
        """Start from the run's present wall time (compiles while building do not count)."""
        self._seen = (self.compiles, sim.wall_time)

    def __call__(self, sim) -> None:
        """Leave out of ``sim``'s wall time the tick that just ran, if numba compiled in it."""
        compiles, wall = self._seen
        if self.compiles != compiles:
            sim.exclude_from_wall_time(sim.wall_time - wall)
        self._seen = (self.compiles, sim.wall_time)
