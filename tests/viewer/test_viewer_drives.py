"""The viewer draws footprints, a car's steering and moving obstacles; teleop drives every kind."""
from __future__ import annotations

import math

import pygame
import pytest

from pymunk_bot.viewer import palette as pal
from viewer_helpers import Harness, build, near

ROBOT = pal.robot_colour(0)
CAR = {"name": "car", "drive": "ackermann", "pose": [1.0, 1.5, 0.0], "wheelbase": 0.33,
       "footprint": {"type": "box", "size": [0.6, 0.3], "center": [0.165, 0.0]}}


def test_a_box_footprint_is_drawn_as_a_box_not_a_disc():
    sim = build([CAR])
    h = Harness(sim)
    h.viewer.layers.grid = False
    h.draw()
    assert near(h.pixel((1.0 + 0.165 + 0.25, 1.5 + 0.1)), ROBOT, 2)  # the front corner
    assert near(h.pixel((1.0 - 0.1, 1.5 - 0.1)), ROBOT, 2)  # behind the rear axle
    assert not near(h.pixel((1.0 + 0.165, 1.5 + 0.2)), ROBOT, 30)  # beside it: floor


def test_car_teleop_steers_and_drives():
    sim = build([CAR])
    h = Harness(sim)
    h.key(pygame.K_UP)
    h.key(pygame.K_LEFT)
    for _ in range(30):
        h.source.step()
    car = sim.robots["car"]
    assert car.overridden and car.drive.speed > 0.2
    assert car.drive.steering_angle > 0.3
    h.draw()  # with the wheels turned


def test_omni_teleop_slides_sideways():
    sim = build([{"name": "holo", "drive": "omni", "pose": [2.0, 1.5, 0.0]}])
    h = Harness(sim)
    h.key(pygame.K_z)
    for _ in range(60):
        h.source.step()
    holo = sim.robots["holo"]
    assert holo.pose[1] > 1.8 and abs(holo.pose[0] - 2.0) < 1e-6 and abs(holo.pose[2]) < 1e-9


def test_a_moving_obstacle_is_drawn_where_it_is_now():
    mover = {"type": "box", "center": [1.0, 2.5], "size": [0.4, 0.4],
             "motion": {"path": [[1.0, 2.5], [3.0, 2.5]], "speed": 1.0, "mode": "once"}}
    sim = build([{"name": "r", "pose": [0.4, 0.4, 0.0]}], obstacles=[mover])
    h = Harness(sim)
    h.viewer.layers.grid = False
    h.draw()
    before = h.pixel((1.0, 2.5))
    for _ in range(120):
        h.source.step()
    h.draw()
    assert h.pixel((3.0, 2.5)) == before
    assert h.pixel((1.0, 2.5)) != before


def test_run_logs_and_replays_hold_cars_omni_robots_and_moving_things(tmp_path):
    from pymunk_bot.outcomes.runlog import RunLogger, load_log
    from pymunk_bot.viewer.sources import ReplaySource

    mover = {"type": "circle", "center": [3.0, 0.5], "radius": 0.2,
             "motion": {"path": [[3.0, 0.5], [3.0, 2.5]], "speed": 1.0, "mode": "pingpong"}}
    walker = {"type": "pedestrian", "center": [3.6, 2.5], "goals": [[3.6, 0.5]]}
    sim = build([CAR, {"name": "holo", "drive": "omni", "pose": [2.0, 2.5, 0.0],
                       "controller": {"type": "velocity", "vy": -0.3}}],
                obstacles=[mover, walker], size=(4.0, 3.0))
    sim.robots["car"].set_velocity(0.5, 0.5)
    logger = RunLogger().attach(sim)
    sim.run(1.0)
    path = tmp_path / "run.npz"
    logger.save(path)
    log = load_log(path)
    assert log.obstacle_pose.shape == (61, 2, 3)  # the mover and the walker, every step
    assert log.obstacle_pose[-1, 0, 1] == pytest.approx(1.5, abs=1e-9)
    assert log.obstacle_pose[-1, 1, 1] < 2.3  # walking down
    assert log.meta["robots"][0]["footprint"] is not None
    h = Harness(ReplaySource(log))
    h.draw()
