"""pygame events -> Viewer actions. The key map lives here and in the help text (hud.py)."""
from __future__ import annotations

import pygame

from pymunk_bot.viewer.app import CLICK_SLOP, Viewer

ZOOM_STEP = 1.15  # scale factor per wheel notch

TELEOP_KEYS = {
    pygame.K_UP: "up", pygame.K_w: "up",
    pygame.K_DOWN: "down", pygame.K_s: "down",
    pygame.K_LEFT: "left", pygame.K_a: "left",
    pygame.K_RIGHT: "right", pygame.K_d: "right",
    pygame.K_z: "slide_left", pygame.K_x: "slide_right",  # omni robots only
}
LAYER_KEYS = {pygame.K_l: "rays", pygame.K_t: "trails", pygame.K_g: "grid",
              pygame.K_o: "ghost", pygame.K_p: "paths", pygame.K_m: "built_map",
              pygame.K_k: "particles", pygame.K_v: "covariance", pygame.K_e: "estimate"}
FASTER = {pygame.K_PLUS, pygame.K_EQUALS, pygame.K_KP_PLUS}
SLOWER = {pygame.K_MINUS, pygame.K_KP_MINUS, pygame.K_UNDERSCORE}


class InputHandler:
    """Turns a stream of pygame events into actions on one :class:`Viewer`."""

    def __init__(self, viewer: Viewer) -> None:
        self.viewer = viewer
        self.mouse = (0, 0)  # last known pointer position [px]
        self._press: tuple[int, int] | None = None  # where the left button went down
        self._dragging = False

    def handle(self, event: pygame.event.Event) -> None:
        """Act on one event."""
        v = self.viewer
        kind = event.type
        if kind == pygame.QUIT:
            v.quit()
        elif kind == pygame.KEYDOWN:
            self._key_down(event)
        elif kind == pygame.KEYUP:
            key = getattr(event, "key", None)
            if key in TELEOP_KEYS and v.source.interactive:
                v.teleop_key(TELEOP_KEYS[key], down=False)
        elif kind == pygame.MOUSEBUTTONDOWN:
            self.mouse = event.pos
            if event.button in (1, 2, 3):  # 4/5 are the legacy wheel events; MOUSEWHEEL has them
                self._press, self._dragging = event.pos, event.button != 1
        elif kind == pygame.MOUSEMOTION:
            self._motion(event)
        elif kind == pygame.MOUSEBUTTONUP:
            self.mouse = event.pos
            if event.button == 1 and self._press is not None and not self._dragging:
                v.click(*event.pos)
            if event.button in (1, 2, 3):
                self._press, self._dragging = None, False
        elif kind == pygame.MOUSEWHEEL:
            notches = event.y if not getattr(event, "flipped", False) else -event.y
            if notches:
                v.camera.zoom(ZOOM_STEP ** notches, self.mouse)
        elif kind == pygame.VIDEORESIZE:
            v.resize(event.size)
        elif kind == getattr(pygame, "WINDOWSIZECHANGED", None):
            v.resize((event.x, event.y))

    def _motion(self, event: pygame.event.Event) -> None:
        self.mouse = event.pos
        if self._press is None:
            return
        if not self._dragging:
            dx, dy = event.pos[0] - self._press[0], event.pos[1] - self._press[1]
            if dx * dx + dy * dy <= CLICK_SLOP * CLICK_SLOP:
                return
            self._dragging = True
            # The first move past the slop pans by the whole way from the press.
            self.viewer.camera.pan(dx, dy)
            return
        self.viewer.camera.pan(*event.rel)

    def _key_down(self, event: pygame.event.Event) -> None:
        v = self.viewer
        key = event.key
        char = getattr(event, "unicode", "")
        replay = not v.source.interactive
        if key in (pygame.K_q, pygame.K_ESCAPE):
            v.quit()
        elif key == pygame.K_SPACE:
            v.toggle_pause()
        elif key in (pygame.K_PERIOD, pygame.K_KP_PERIOD) or char == ".":
            v.step_once(1)
        elif (key == pygame.K_COMMA or char == ",") and replay:
            v.step_once(-1)
        elif key in FASTER or char == "+":
            v.change_speed(+1)
        elif key in SLOWER or char == "-":
            v.change_speed(-1)
        elif key == pygame.K_TAB:
            v.select_next()
        elif key == pygame.K_h:
            v.help = not v.help
        elif key == pygame.K_f:
            v.fit()
        elif key == pygame.K_r:
            v.reset()
        elif key == pygame.K_c:
            v.release_teleop()
        elif replay and key in (pygame.K_RIGHT, pygame.K_LEFT):
            v.seek(1.0 if key == pygame.K_RIGHT else -1.0)
        elif key in TELEOP_KEYS:
            if replay:
                v.say("a replay cannot be driven")
            else:
                v.teleop_key(TELEOP_KEYS[key], down=True)
        elif key in LAYER_KEYS:
            v.toggle(LAYER_KEYS[key])
