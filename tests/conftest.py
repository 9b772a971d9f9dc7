"""Shared fixtures: build small scenarios in code, headless pygame."""
from __future__ import annotations

import os

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from pymunk_bot import Simulation  # noqa: E402
from pymunk_bot.config import parse_scenario  # noqa: E402


def scenario(robots: list[dict], obstacles: list[dict] | None = None, size=(20.0, 20.0),
             **extra) -> dict:
    """A scenario mapping with sensible defaults; ``extra`` adds top-level keys or world keys."""
    world = {"size": list(size)}
    for key in ("dt", "substeps", "duration", "wall_friction"):
        if key in extra:
            world[key] = extra.pop(key)
    return {"name": "test", "world": world, "obstacles": obstacles or [], "robots": robots, **extra}


def robot(pose, **keys) -> dict:
    return {"name": keys.pop("name", "r"), "pose": list(pose), **keys}


def wheels(left: float, right: float) -> dict:
    return {"type": "wheels", "left": left, "right": right}


@pytest.fixture
def make_sim():
    """make_sim(robots, obstacles, ...) -> Simulation."""
    def make(robots, obstacles=None, seed=None, **extra):
        return Simulation(parse_scenario(scenario(robots, obstacles, **extra), "test"), seed=seed)
    return make
