"""Cars plan paths they can drive (Hybrid A*), may reverse, and park; controllers respect the
turning circle."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from builders import drive_to_goal, robot

from pymunk_bot import Simulation
from pymunk_bot.config.loader import parse_scenario
from pymunk_bot.geometry.footprint import Footprint
from pymunk_bot.geometry.plane import box_corners
from pymunk_bot.planning.grid import ClearanceGrid
from pymunk_bot.planning.hybrid_astar import FootprintChecker, HybridParams, hybrid_astar
from pymunk_bot.planning.map import MapInfo, MapPolygon

REPO = Path(__file__).resolve().parents[2]
CAR = {"drive": "ackermann", "wheelbase": 0.33, "max_steer": 0.5, "max_speed": 1.0,
       "footprint": {"type": "box", "size": [0.5, 0.3], "center": [0.165, 0.0]}}
RADIUS = 0.33 / math.tan(0.5)


def car_checker(world_map: MapInfo, resolution: float = 0.05) -> FootprintChecker:
    footprint = Footprint("polygon", (0.165, 0.0), 0.0, box_corners((0.165, 0.0), (0.5, 0.3)))
    centres, radii = footprint.covering_discs(0.15)
    grid = ClearanceGrid.from_map(world_map, resolution, cap=0.5)
    return FootprintChecker(grid, centres, radii, margin=0.02)


def turning_radii(poses: np.ndarray) -> np.ndarray:
    """Radius of the arc between consecutive poses [m] (inf on straights)."""
    step = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    turn = np.abs(np.diff(poses[:, 2]))
    return np.where(turn > 1e-9, step / np.maximum(2 * np.sin(turn / 2), 1e-12), np.inf)


def test_turning_around_in_a_dead_end_corridor_needs_reversing():
    # A 1.2 m wide corridor closed at its end: turning round takes a three-point turn.
    walls = [box_corners((3.0, 0.1), (6.0, 0.2)), box_corners((3.0, 1.5), (6.0, 0.2))]
    world = MapInfo((6.0, 1.6), tuple(MapPolygon(w) for w in walls))
    checker = car_checker(world)
    result = hybrid_astar(checker, (2.0, 0.8, 0.0), (1.0, 0.8), 0.15, RADIUS,
                          goal_heading=math.pi, heading_tolerance=0.2)
    assert result.found, result.reason
    assert (result.direction < 0).any()  # it backed up
    assert np.all(turning_radii(result.poses) >= RADIUS - 1e-6)
    assert checker.free(result.poses).all()
    assert math.dist(result.poses[-1, :2], (1.0, 0.8)) <= 0.15


def test_an_enclosed_goal_fails_cleanly_within_the_expansion_budget():
    box = box_corners((4.0, 2.0), (1.2, 1.2))
    hole = MapInfo((6.0, 4.0), (MapPolygon(box),))
    result = hybrid_astar(car_checker(hole), (1.0, 2.0, 0.0), (4.0, 2.0), 0.1, RADIUS,
                          HybridParams(max_expansions=3000))
    assert not result.found
    assert "no drivable path" in result.reason


def test_the_car_parks_between_two_cars():
    sim = Simulation.from_file(REPO / "scenarios" / "parking.yaml")
    sim.run(sim.config.world.duration)
    car = sim.robots["car"]
    assert car.goal_reached and car.collisions == 0
    assert abs(math.remainder(car.pose[2], 2 * math.pi)) < 0.2
    plan = car.controller.plan
    assert (plan.direction < 0).any()  # it reversed into the space
    assert all(c.passed for c in sim.check_expectations())


def test_waypoints_respect_the_turning_circle(make_sim):
    sim = make_sim([robot([2, 2, 0], name="car", **CAR, goal={"position": [2, 6]},
                          controller={"type": "waypoints", "points": [[6, 2], [6, 6], [2, 6]]})],
                   size=(10.0, 10.0))
    poses = []
    for _ in range(round(25 / sim.dt)):
        sim.step()
        poses.append(sim.robots["car"].pose.copy())
    car = sim.robots["car"]
    assert car.goal_reached
    assert turning_radii(np.array(poses)[::6]).min() >= RADIUS * 0.98


def test_go_to_goal_backs_out_of_a_goal_inside_its_turning_circle(make_sim):
    # The goal is 0.5 m to the left: inside the 0.6 m circle a car cannot turn tighter than.
    sim = make_sim([robot([5, 5, 0], name="car", **CAR, goal={"position": [5, 5.5],
                                                              "tolerance": 0.15},
                          controller={"type": "go_to_goal"})])
    sim.run(15.0)
    car = sim.robots["car"]
    assert car.goal_reached


@pytest.mark.parametrize("drive", ["omni", "ackermann"])
def test_navigate_works_for_every_drive(make_sim, drive):
    keys = CAR if drive == "ackermann" else {"drive": "omni",
                                             "footprint": {"type": "box", "size": [0.5, 0.3]}}
    wall = {"type": "wall", "start": [4.0, 0.0], "end": [4.0, 4.5], "thickness": 0.2}
    sim = make_sim([robot([1.5, 2.0, 0], name="r", **keys, goal={"position": [7.0, 2.0]},
                          lidar={"beams": 90, "max_range": 5.0},
                          controller={"type": "navigate", "max_speed": 0.8})],
                   [wall], size=(9.0, 7.0))
    sim.run(30.0)
    r = sim.robots["r"]
    assert r.goal_reached, r.controller.message
    assert r.collisions == 0


def test_parks_in_a_space_only_2_2_car_lengths_long():
    cars = [box_corners((2.5, 0.3), (0.5, 0.3)), box_corners((4.1, 0.3), (0.5, 0.3))]
    street = MapInfo((8.0, 3.0), tuple(MapPolygon(c) for c in cars))
    checker = car_checker(street)
    result = hybrid_astar(checker, (0.6, 1.4, 0.0), (3.135, 0.3), 0.06, 0.33 / math.tan(0.6),
                          HybridParams(step=0.2, switch_cost=0.5), goal_heading=0.0,
                          heading_tolerance=0.12, heuristic_clearance=0.16)
    assert result.found, result.reason
    assert checker.free(result.poses).all()
    assert (result.direction < 0).any()


def test_a_car_plans_around_a_crate_that_is_not_on_its_map(make_sim):
    crate = {"type": "box", "center": [5.0, 2.0], "size": [0.6, 0.6], "movable": True,
             "mass": 50.0}
    sim = make_sim([robot([1.5, 2.0, 0], name="car", **CAR, goal={"position": [8.5, 2.0]},
                          lidar={"beams": 120, "max_range": 5.0},
                          controller={"type": "navigate", "max_speed": 0.6})],
                   [crate], size=(10.0, 4.0))
    sim.run(40.0)
    car = sim.robots["car"]
    assert car.goal_reached, car.controller.message
    assert car.collisions == 0
    assert sim.world.obstacles[0].body.position.x == pytest.approx(5.0, abs=0.01)


@pytest.mark.parametrize("rate", [5.0, 7.0])  # [Hz] slower than the 10 Hz controller; in step or not
def test_a_car_turning_round_a_wall_does_not_block_itself_with_its_own_scans(rate):
    # The goal is behind a wall; the car drives round its end in a tight turn (1.7 rad/s). The
    # controller is handed the LiDAR's latest scan on every tick; placed with a later tick's
    # pose, a scan puts the walls 10 deg off and the car stops for "unmapped" copies of them
    # (7 Hz, starting away from the wall's end: 103 such returns, stopped for 9 s).
    wall = {"type": "wall", "start": [0.0, 2.0], "end": [4.5, 2.0], "thickness": 0.2}
    for heading in np.radians([0.0, 90.0, 180.0, 270.0]):  # [rad] facing every way at first
        car = {"name": "car", "pose": [1.0, 1.0, float(heading)], **CAR,
               "lidar": {"beams": 270, "max_range": 8.0, "rate": rate},
               "controller": {"type": "navigate"},
               "goal": {"position": [1.0, 3.0], "tolerance": 0.3}}
        sim = Simulation(parse_scenario({"name": "t", "world": {"size": [6.0, 4.0]},
                                         "obstacles": [wall], "robots": [car]}, "test"))
        r = sim.robots["car"]
        stopped = drive_to_goal(sim, "car")
        assert r.goal_reached and r.collisions == 0, (heading, r.controller.message)
        assert not stopped, heading  # nothing but the map is there: nothing to stop for
