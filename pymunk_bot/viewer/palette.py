"""Colours of the viewer, recordings and plots.

Robots take the Okabe-Ito colours (Okabe & Ito, "Color Universal Design", 2008), which stay
distinct under the common forms of colour blindness. Movable obstacles are orange and also
carry a cross mark, so they differ from fixed ones by shape as well as by hue.
"""
from __future__ import annotations

RGB = tuple[int, int, int]

BACKGROUND: RGB = (38, 40, 44)  # outside the arena
FLOOR: RGB = (250, 250, 246)
GRID: RGB = (222, 224, 220)
GRID_MAJOR: RGB = (196, 199, 194)
WALL: RGB = (70, 72, 76)  # arena walls
STATIC: RGB = (98, 102, 110)  # fixed obstacles
STATIC_EDGE: RGB = (52, 54, 58)
MOVABLE: RGB = (230, 159, 0)  # Okabe-Ito orange
MOVABLE_EDGE: RGB = (120, 80, 0)
OUTLINE: RGB = (20, 20, 20)
HEADING: RGB = (255, 255, 255)
SELECTION: RGB = (240, 228, 66)  # Okabe-Ito yellow
HUD_BACK: tuple[int, int, int, int] = (20, 22, 26, 200)
HUD_TEXT: RGB = (236, 236, 236)
HUD_DIM: RGB = (160, 164, 170)
HUD_WARN: RGB = (240, 228, 66)

# Robot colours in order: blue, vermillion, bluish green, reddish purple, sky blue, black-ish.
ROBOTS: tuple[RGB, ...] = (
    (0, 114, 178), (213, 94, 0), (0, 158, 115), (204, 121, 167), (86, 180, 233), (60, 60, 60),
)


def robot_colour(index: int) -> RGB:
    """The colour of the ``index``-th robot (cycling after six)."""
    return ROBOTS[index % len(ROBOTS)]


def hex_colour(rgb: RGB) -> str:
    """'#rrggbb' for matplotlib."""
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def mix(a: RGB, b: RGB, t: float) -> RGB:
    """The colour a fraction ``t`` of the way from ``a`` to ``b``."""
    return tuple(int(round(x + (y - x) * t)) for x, y in zip(a, b))  # type: ignore[return-value]
