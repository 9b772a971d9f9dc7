"""The substep count is computed from speeds and geometry, so nothing tunnels."""
from __future__ import annotations

import pytest
from builders import robot

from pymunk_bot.config.substeps import PUSHING_CONTACT_STEP, shove_factor, \
    substeps_against_overlap, substeps_against_tunnelling


def test_formula():
    # 1 m/s, dt 1/60: moves 1.7 cm per step, far below (0.2 + 0.01) / 2 -> one substep
    assert substeps_against_tunnelling(1 / 60, 1.0, 0.2, 0.01) == 1
    # 30 m/s against a 2 cm wall with a 5 cm robot: 0.5 m per step vs 3 cm allowed
    assert substeps_against_tunnelling(1 / 60, 30.0, 0.05, 0.01) == 17


def test_world_uses_the_thinnest_wall_and_fastest_robot(make_sim):
    wall = {"type": "wall", "start": [5, 1], "end": [5, 9], "thickness": 0.01}
    sim = make_sim([robot([1, 5, 0], radius=0.05, max_wheel_speed=20.0)], [wall], size=(10, 10))
    assert sim.substeps >= substeps_against_tunnelling(1 / 60, 20.0, 0.05, 0.005)
    # 20 m/s moves 33 cm per step: contact must start within 8 mm, so 42 substeps
    assert sim.substeps == substeps_against_overlap(1 / 60, 20.0) == 42


def test_a_pushed_crate_counts_as_a_mover(make_sim):
    wall = {"type": "wall", "start": [5, 1], "end": [5, 9], "thickness": 0.01}
    pellet = {"type": "circle", "center": [3, 5], "radius": 0.005, "movable": True, "mass": 0.01}
    pusher = robot([1, 5, 0], radius=0.3, max_wheel_speed=1.0)
    alone = make_sim([pusher], [wall], size=(10, 10)).substeps
    with_pellet = make_sim([pusher], [wall, pellet], size=(10, 10)).substeps
    # a 5 mm pellet pushed at 1 m/s must not skip a 1 cm wall: (0.005 + 0.005) / 2 per substep
    assert with_pellet >= substeps_against_tunnelling(1 / 60, 1.0, 0.005, 0.005) == 4
    # and at 10 g shoved by a 5 kg robot it sinks sqrt(500) / 5 times its step (at 4 substeps
    # it passes the wall): 13
    assert with_pellet == substeps_against_overlap(
        1 / 60, 1.0 * shove_factor(5.0 / 0.01), PUSHING_CONTACT_STEP) == 13
    assert alone == substeps_against_overlap(1 / 60, 1.0) == 3


def test_explicit_substeps_are_respected(make_sim):
    assert make_sim([robot([1, 1, 0])], substeps=3).substeps == 3


@pytest.mark.parametrize("count", [2, 5])
def test_two_robots_consider_closing_speed(make_sim, count):
    robots = [robot([1 + i, 1, 0], name=f"r{i}", radius=0.1, max_wheel_speed=8.0)
              for i in range(count)]
    sim = make_sim(robots)
    assert sim.substeps >= substeps_against_tunnelling(1 / 60, 16.0, 0.1, 0.1)
