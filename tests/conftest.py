"""Shared fixtures: build small scenarios in code, headless pygame."""
from __future__ import annotations

import os

import pytest

pytest_plugins = ["pytester"]  # tests of the scenario plugin run pytest in-process

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from builders import scenario  # noqa: E402

from pymunk_bot import Simulation  # noqa: E402
from pymunk_bot.config import parse_scenario  # noqa: E402


@pytest.fixture
def make_sim():
    """make_sim(robots, obstacles, ...) -> Simulation."""
    def make(robots, obstacles=None, seed=None, **extra):
        return Simulation(parse_scenario(scenario(robots, obstacles, **extra), "test"), seed=seed)
    return make
