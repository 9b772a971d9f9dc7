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


def pytest_configure(config):
    """With pytest-xdist, numba's kernels that nearly every test runs (the tick's drives,
    steering, bookkeeping, odometry, substeps, ray casting and the walkers' social force,
    clearances and ORCA) are compiled here, once, before
    the workers start: on a first run after installing, workers starting together would each
    compile them (5-10 s of CPU twice over). Later runs load them from numba's cache (about a
    second here)."""
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return  # a worker, or no workers
    sim = Simulation(parse_scenario(scenario(
        [{"name": "r1", "pose": [1.0, 1.0, 0.0], "goal": {"position": [4.0, 1.0]},
          "lidar": {"beams": 36, "noise_std": 0.01}, "odometry": {"wheel_noise_std": 0.01}},
         {"name": "r2", "pose": [1.0, 3.0, 0.0], "controller": {"type": "velocity", "v": 0.5,
                                                               "omega": 0.3}}],
        [{"type": "box", "center": [2.5, 2.0], "size": [0.4, 0.4]},
         {"type": "pedestrian", "center": [4.0, 3.5], "goals": [[4.5, 2.5]]},
         {"type": "pedestrian", "center": [3.0, 0.5], "goals": [[4.5, 0.5]], "policy": "orca"}]),
        "warm-up"), seed=0)
    sim.run(1.0)


@pytest.fixture
def make_sim():
    """make_sim(robots, obstacles, ...) -> Simulation."""
    def make(robots, obstacles=None, seed=None, **extra):
        return Simulation(parse_scenario(scenario(robots, obstacles, **extra), "test"), seed=seed)
    return make
