"""Helpers for the viewer tests: small scenarios built in code, a Viewer fed synthetic events."""
from __future__ import annotations

import os

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import pygame  # noqa: E402

from pymunk_bot import Simulation  # noqa: E402
from pymunk_bot.config import parse_scenario  # noqa: E402
from pymunk_bot.viewer.app import Viewer  # noqa: E402
from pymunk_bot.viewer.input import InputHandler  # noqa: E402
from pymunk_bot.viewer.sources import LiveSource  # noqa: E402


def build(robots, obstacles=None, size=(4.0, 3.0), seed=0, **world) -> Simulation:
    """A Simulation from plain dicts."""
    data = {"name": "viewer_test", "seed": seed, "world": {"size": list(size), **world},
            "obstacles": obstacles or [], "robots": robots}
    return Simulation(parse_scenario(data, "viewer_test"))


def wheels(left, right):
    return {"type": "wheels", "left": left, "right": right}


class FakeClock:
    """A wall clock that moves 0.1 ms per reading: frame budgets cut at the same step on any
    machine, however loaded."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        self.now += 1e-4
        return self.now


class Harness:
    """A Viewer on an offscreen surface, fed synthetic events."""

    def __init__(self, sim_or_source, size=(400, 300), duration=None):
        source = sim_or_source if hasattr(sim_or_source, "scene") else LiveSource(sim_or_source)
        self.source = source
        self.surface = pygame.Surface(size)
        self.viewer = Viewer(source, size, duration, clock=FakeClock())
        self.input = InputHandler(self.viewer)

    def key(self, key, unicode="", up=False):
        kind = pygame.KEYUP if up else pygame.KEYDOWN
        self.input.handle(pygame.event.Event(kind, key=key, mod=0, unicode=unicode))

    def click(self, pos, button=1):
        self.input.handle(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=pos, button=button))
        self.input.handle(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=pos, button=button))

    def drag(self, start, end, button=1):
        self.input.handle(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=start, button=button))
        self.input.handle(pygame.event.Event(
            pygame.MOUSEMOTION, pos=end, rel=(end[0] - start[0], end[1] - start[1]),
            buttons=(1, 0, 0)))
        self.input.handle(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=end, button=button))

    def draw(self, hud=False):
        """Render a frame; without the HUD unless asked, so that it hides nothing."""
        self.viewer.draw(self.surface, hud=hud)
        return self.surface

    def pixel(self, world_xy):
        """The colour drawn at a world point [m]."""
        px, py = self.viewer.camera.to_screen(*world_xy)
        return tuple(self.surface.get_at((int(px), int(py))))[:3]


def near(colour, target, tol=12) -> bool:
    return all(abs(int(a) - int(b)) <= tol for a, b in zip(colour, target))
