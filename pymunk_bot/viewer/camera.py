"""World <-> pixel transform: the only place where metres become pixels and y flips."""
from __future__ import annotations

import numpy as np

MIN_SCALE = 2.0  # [px/m]; zooming out further shows nothing useful
MAX_SCALE = 4000.0  # [px/m]; 0.25 mm per pixel
FIT_MARGIN = 24  # [px] left around the arena when the view fits it


class Camera:
    """Maps world points (x right, y up, metres) to screen pixels (x right, y down).

    ``centre`` is the world point at the middle of the viewport and ``scale`` the number of
    pixels per metre. ``user_moved`` turns true once the user zooms or pans, so that a window
    resize refits the view only while the user has not chosen one.
    """

    def __init__(self, viewport: tuple[int, int], scale: float = 50.0,
                 centre: tuple[float, float] = (0.0, 0.0)) -> None:
        self.width, self.height = int(viewport[0]), int(viewport[1])
        self.scale = float(scale)
        self.centre = (float(centre[0]), float(centre[1]))
        self.user_moved = False

    # ------------------------------------------------------------------ set-up
    def fit(self, x0: float, y0: float, x1: float, y1: float, margin: int = FIT_MARGIN) -> None:
        """Show the world rectangle [x0, x1] x [y0, y1] as large as fits, ``margin`` px around."""
        room_x = max(self.width - 2 * margin, 1)
        room_y = max(self.height - 2 * margin, 1)
        span_x, span_y = max(x1 - x0, 1e-6), max(y1 - y0, 1e-6)
        self.scale = float(np.clip(min(room_x / span_x, room_y / span_y), MIN_SCALE, MAX_SCALE))
        self.centre = (0.5 * (x0 + x1), 0.5 * (y0 + y1))
        self.user_moved = False

    def resize(self, viewport: tuple[int, int]) -> None:
        """A new viewport size in pixels; the world point at the centre stays there."""
        self.width, self.height = max(int(viewport[0]), 1), max(int(viewport[1]), 1)

    # ------------------------------------------------------------------ transforms
    def to_screen(self, x: float, y: float) -> tuple[float, float]:
        """World point [m] -> pixel coordinates (floats)."""
        return (0.5 * self.width + (x - self.centre[0]) * self.scale,
                0.5 * self.height - (y - self.centre[1]) * self.scale)

    def points_to_screen(self, points: np.ndarray) -> np.ndarray:
        """(N, 2) world points [m] -> (N, 2) pixel coordinates."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        out = np.empty_like(pts)
        out[:, 0] = 0.5 * self.width + (pts[:, 0] - self.centre[0]) * self.scale
        out[:, 1] = 0.5 * self.height - (pts[:, 1] - self.centre[1]) * self.scale
        return out

    def to_world(self, px: float, py: float) -> tuple[float, float]:
        """Pixel coordinates -> world point [m]."""
        return (self.centre[0] + (px - 0.5 * self.width) / self.scale,
                self.centre[1] - (py - 0.5 * self.height) / self.scale)

    def length(self, metres: float) -> float:
        """A world length [m] in pixels."""
        return metres * self.scale

    # ------------------------------------------------------------------ user moves
    def zoom(self, factor: float, about: tuple[float, float] | None = None) -> None:
        """Scale by ``factor``, keeping the world point under pixel ``about`` where it is."""
        if about is None:
            about = (0.5 * self.width, 0.5 * self.height)
        wx, wy = self.to_world(*about)
        self.scale = float(np.clip(self.scale * factor, MIN_SCALE, MAX_SCALE))
        # Move the centre so that (wx, wy) maps back to the same pixel.
        self.centre = (wx - (about[0] - 0.5 * self.width) / self.scale,
                       wy + (about[1] - 0.5 * self.height) / self.scale)
        self.user_moved = True

    def pan(self, dx: float, dy: float) -> None:
        """Drag the view by (dx, dy) pixels: the scene follows the mouse."""
        self.centre = (self.centre[0] - dx / self.scale, self.centre[1] + dy / self.scale)
        self.user_moved = True
