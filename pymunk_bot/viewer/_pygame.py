"""Import pygame and open the display, or say in one line why not."""
from __future__ import annotations

from . import ViewerUnavailable


def require_pygame():
    """The pygame module, quietly imported (no banner on stdout)."""
    try:
        import pygame
    except ImportError:
        raise ViewerUnavailable("pygame is not installed (pip install pygame)") from None
    return pygame


def open_display():
    """pygame with its display initialised; ViewerUnavailable when there is no display."""
    pygame = require_pygame()
    try:
        pygame.display.init()
    except pygame.error as exc:
        raise ViewerUnavailable(f"no display available ({exc})") from None
    return pygame
