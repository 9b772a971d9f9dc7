"""A light crate shoved by a heavy robot holds at a wall (issue 24, item 5): the substep rule
counts the mass ratio (config/substeps.py `hardest_shove`), and a ratio the solver cannot hold
within the substep limit is refused with a message naming the crate's mass."""
from __future__ import annotations

import math

import numpy as np
import pytest

from bench.contacts import deepest_overlap
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.engine.simulation import Simulation

WALL_X = 3.0  # [m]


def crate_push(crate_mass: float, robot_mass: float, speed: float, dt: float,
               wall: float = 0.044, radius: float = 0.2, crate_radius: float = 0.03,
               accel: float = 3.0) -> dict:
    """A robot driving a crate straight into a wall of thickness ``wall`` [m]."""
    return {"name": "shove", "world": {"size": [6.0, 4.0], "dt": dt},
            "obstacles": [{"type": "circle", "center": [1.0 + radius + crate_radius + 0.02, 2.0],
                           "radius": crate_radius, "movable": True, "mass": crate_mass,
                           "ground_friction": 0.3},
                          {"type": "wall", "start": [WALL_X, 0.0], "end": [WALL_X, 4.0],
                           "thickness": wall}],
            "robots": [{"name": "a", "pose": [1.0, 2.0, 0.0], "radius": radius,
                        "mass": robot_mass, "track_width": max(0.06, 1.5 * radius),
                        "max_wheel_speed": speed, "max_accel": accel,
                        "controller": {"type": "velocity", "v": speed}}]}


def push(data: dict, seconds: float = 3.0) -> tuple[bool, float]:
    """(the crate or robot crossed the wall, deepest overlap [m])."""
    sim = Simulation.from_dict(data)
    worst = 0.0
    for _ in range(round(seconds / sim.dt)):
        sim.step()
        worst = max(worst, deepest_overlap(sim.space))
    crate = sim.world.obstacles[0].body.position.x
    return crate > WALL_X or sim.robots["a"].pose[0] > WALL_X, worst


def test_the_reported_crate_is_refused_with_a_message_naming_its_mass():
    with pytest.raises(ScenarioError) as error:
        Simulation.from_dict(crate_push(0.01, 50.0, 1.4, 1 / 30))
    message = str(error.value)
    assert "obstacles[0].mass: 0.01 kg is too light to be pushed by a 50 kg body" in message
    assert "substeps" in message and "lower world.dt" in message


def test_the_reported_crate_holds_at_a_dt_the_solver_can_hold():
    crossed, worst = push(crate_push(0.01, 50.0, 1.4, 1 / 60))
    assert not crossed and worst <= 0.01


@pytest.mark.parametrize("seed", [1, 2])
def test_random_mass_ratios_hold_or_are_refused(seed):
    rng = np.random.default_rng(seed)
    held = 0
    for _ in range(20):
        data = crate_push(crate_mass=float(10 ** rng.uniform(-3, 0.5)),
                          robot_mass=float(10 ** rng.uniform(0, 2.5)),
                          speed=float(rng.uniform(0.2, 3.0)),
                          dt=float(rng.choice([1 / 30, 1 / 60, 1 / 120])),
                          wall=float(rng.uniform(0.01, 0.05)),
                          radius=float(rng.uniform(0.05, 0.3)),
                          crate_radius=float(rng.uniform(0.01, 0.1)),
                          accel=float(10 ** rng.uniform(0, math.log10(50))))
        try:
            crossed, worst = push(data, seconds=2.5)
        except ScenarioError as exc:
            assert "too light to be pushed" in str(exc)
            continue
        held += 1
        assert not crossed and worst <= 0.01, data
    assert held >= 12  # most draws run: the refusal is for ratios the solver cannot hold
