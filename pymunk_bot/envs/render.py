"""Frames of an env's simulation through the viewer's offscreen renderer (what `--record` uses),
and the "human" window. pygame is imported only here, and only when a frame is asked for."""
from __future__ import annotations

from typing import TYPE_CHECKING, Iterable

import numpy as np

if TYPE_CHECKING:
    import pygame

DEFAULT_LONG_SIDE = 640  # [px] of an rgb_array frame along the arena's long side
MARGIN = 24  # [px]


class FrameRenderer:
    """Draws a simulation. It watches every physics step (as an observer) so trails and scans
    are drawn exactly as the viewer would; after a reset it starts over."""

    def __init__(self, sim, size: tuple[int, int] | None = None,
                 agents: Iterable[str] = ()) -> None:
        """``agents``: the robots the env's agent drives, labelled as such in the HUD."""
        from pymunk_bot.viewer.display import require_pygame

        self.pygame = require_pygame()
        from pymunk_bot.viewer.app import Viewer
        from pymunk_bot.viewer.sources import LiveSource

        self.sim = sim
        self.source = LiveSource(sim)
        if size is None:
            width, height = sim.world.width, sim.world.height
            scale = (DEFAULT_LONG_SIDE - 2 * MARGIN) / max(width, height)
            size = (int(width * scale) + 2 * MARGIN, int(height * scale) + 2 * MARGIN)
        self.size = size
        self.viewer = Viewer(self.source, size)
        self.viewer.recording = True  # no speed and key hints in the frame
        self.viewer.agents = frozenset(agents)
        self.surface = self.pygame.Surface(size)
        self._window: pygame.Surface | None = None  # the "human" window, once opened
        sim.observers.append(self)

    # observer protocol: trails and scans, after every step and reset
    def __call__(self, sim) -> None:
        self.source.observe()

    def on_reset(self, sim) -> None:
        self.source.rebuild()

    def rgb(self) -> np.ndarray:
        """The present state as an (H, W, 3) uint8 RGB array."""
        self.viewer.draw(self.surface)
        w, h = self.size
        data = self.pygame.image.tobytes(self.surface, "RGB")
        return np.frombuffer(data, np.uint8).reshape(h, w, 3).copy()

    def show(self, title: str) -> None:
        """Draw into a window (opened on first use; ViewerUnavailable without a display)."""
        pygame = self.pygame
        if self._window is None:
            from pymunk_bot.viewer.display import open_display

            open_display()
            self._window = pygame.display.set_mode(self.size)
            pygame.display.set_caption(title)
        pygame.event.pump()  # keep the window responsive
        self.viewer.draw(self._window)
        pygame.display.flip()

    def close(self) -> None:
        if self.sim is not None and self in self.sim.observers:
            self.sim.observers.remove(self)
        if self._window is not None:
            self.pygame.display.quit()
            self._window = None
