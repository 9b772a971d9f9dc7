"""Views of a simulation: the interactive pygame window, video recordings and replays.

Importing this package does not import pygame: the functions below do it when called, and
raise :class:`ViewerUnavailable` with a one-line reason (pygame missing, no display) that the
CLI prints before it falls back to a headless run.
"""
from __future__ import annotations

import os
from pathlib import Path

# pygame prints a banner on import unless told not to; our output is the run summary.
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")


from pymunk_bot.viewer.unavailable import ViewerUnavailable


def run_window(sim, duration: float | None = None) -> None:
    """Show ``sim`` in an interactive window until the user quits.

    The run pauses when ``duration`` simulated seconds have passed (space runs on, q quits).
    """
    from pymunk_bot.viewer.window import run_window as run

    run(sim, duration)


def replay_window(log) -> None:
    """Play a :class:`~pymunk_bot.outcomes.runlog.RunLog` in the window."""
    from pymunk_bot.viewer.window import replay_window as replay

    replay(log)


def record_video(source, path: str | Path, duration: float | None, fps: float | None = None,
                 size: tuple[int, int] | None = None, progress: bool = True,
                 until_settled: bool = True) -> int:
    """Render ``duration`` simulated seconds of a live simulation or run log to .mp4 or .gif.

    ``source`` is a Simulation or a RunLog; returns the number of frames written. ``duration``
    None records a whole RunLog; a Simulation needs a duration. A Simulation's video ends once
    the run has settled (every robot done and nothing moving for 1 s) unless ``until_settled``
    is False; the simulation runs ``duration`` either way.
    """
    from pymunk_bot.viewer.recorder import record

    return record(source, path, duration, fps=fps, size=size, progress=progress,
                  until_settled=until_settled)


__all__ = ["ViewerUnavailable", "record_video", "replay_window", "run_window"]
