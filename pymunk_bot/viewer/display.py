"""Import pygame and open the display, or say in one line why not."""
from __future__ import annotations

import os

from pymunk_bot.viewer.unavailable import ViewerUnavailable

# SDL falls back to these when no real display answers: a window there is invisible.
INVISIBLE_DRIVERS = ("offscreen", "dummy")


def require_pygame():
    """The pygame module, quietly imported (no banner on stdout)."""
    try:
        import pygame
    except ImportError:
        raise ViewerUnavailable("pygame is not installed (pip install pygame)") from None
    return pygame


def open_display():
    """pygame with its display initialised; ViewerUnavailable when there is no display.

    An invisible driver is accepted only when SDL_VIDEODRIVER asks for it by name (tests do):
    otherwise SDL's silent fall-back would run a window nobody can see or close.
    """
    pygame = require_pygame()
    try:
        pygame.display.init()
    except pygame.error as exc:
        raise ViewerUnavailable(f"no display available ({exc})") from None
    driver = pygame.display.get_driver()
    if driver in INVISIBLE_DRIVERS and os.environ.get("SDL_VIDEODRIVER") != driver:
        pygame.display.quit()
        raise ViewerUnavailable("no display answered (SDL fell back to its "
                                f"'{driver}' driver)")
    return pygame
