"""Robots that nothing can reach step apart (pymunk_bot/physics/apart.py): a fleet where most
step once a tick in a Space of their own while the others substep keeps its contacts shallow,
runs the same twice, and gives the whole world back to whoever asks for its Space.

The engine plans this from SPLIT_FROM robots on, a threshold set by speed alone; these tests
lower it to FLEET, so that the same code runs on a tenth of the robots."""
from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest

from bench.fleet import swarm_scenario
from pymunk_bot.physics import world as physics_world
from pymunk_bot.engine.simulation import Simulation

FLEET = 200  # robots


@pytest.fixture(autouse=True)
def split_from_fleet(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(physics_world, "SPLIT_FROM", FLEET)


def _swarm(**changes: object) -> Simulation:
    data = swarm_scenario(FLEET)
    data["robots"][0].update(changes)
    return Simulation.from_dict(data, source="swarm")


def _apart(sim: Simulation) -> int:
    """How many robots step in the apart Space now."""
    return sum(r.body.space is sim.world.apart_space for r in sim.robots.values())


def _deepest_overlap(sim: Simulation) -> float:
    """[m] the deepest any robot overlaps anything now (pymunk's shape queries)."""
    space = sim.world.contact_space  # every shape but those of the robots apart
    deepest = 0.0
    for robot in sim.robots.values():
        robot.shape.cache_bb()  # a robot apart: its shape is in no Space, nothing updates it
        for info in space.shape_query(robot.shape):
            for point in info.contact_point_set.points:
                deepest = max(deepest, -point.distance)
    return deepest


def test_most_robots_step_apart_and_every_contact_stays_shallow() -> None:
    sim = _swarm()
    deepest, apart = 0.0, []
    for tick in range(180):  # 3 s: the swarm's robots meet (after 1.5 s) and push each other
        sim.step()
        if tick % 10 == 9:
            deepest = max(deepest, _deepest_overlap(sim))
            apart.append(_apart(sim))
    assert min(apart) > FLEET // 2, apart
    assert sum(r.collisions for r in sim.robots.values()) > 20  # there were contacts
    assert deepest <= 0.01, deepest
    # one pymunk step a tick of the apart Space, on top of the contact Space's
    assert sim.pymunk_steps > sim.steps


def test_a_robot_apart_driven_at_a_wall_stops_at_it() -> None:
    # Robot r0 starts 1.5 m from the arena's left wall, nothing near, and drives at it at
    # 1 m/s: it steps apart first, and is back in the contact Space before it can touch.
    sim = _swarm(pose=[1.5, 1.0, math.pi], controller={"type": "velocity", "v": 1.0, "omega": 0.0})
    robot = sim.robots["r0"]
    radius = robot.radius
    went_apart, touching_apart = False, False
    deepest = 0.0
    for _ in range(150):  # 2.5 s
        sim.step()
        x = robot.body.position.x
        went_apart |= robot.body.space is sim.world.apart_space
        touching_apart |= x - radius < 0.02 and robot.body.space is sim.world.apart_space
        deepest = max(deepest, radius - x)
    assert went_apart and not touching_apart
    assert robot.collisions >= 1
    assert deepest <= 0.01, deepest


def test_the_same_seed_runs_the_same() -> None:
    runs = []
    for _ in range(2):
        sim = _swarm()
        sim.run(1.0)
        assert _apart(sim) > 0
        runs.append(np.array([r.pose for r in sim.robots.values()]))
    assert np.array_equal(*runs)


def test_one_solver_iteration_apart_moves_robots_as_ten() -> None:
    # The swarm's robots are discs: their joints pull through the centre of gravity, and one
    # iteration solves them (the Space apart takes one).
    poses = []
    for iterations in (None, 10):
        sim = _swarm()
        if iterations is not None:
            sim.world.apart_space.iterations = iterations
        assert sim.world.apart_space.iterations == (iterations or 1)
        sim.run(1.0)
        poses.append(np.array([r.pose for r in sim.robots.values()]))
    assert np.abs(poses[0] - poses[1]).max() < 1e-12


def test_a_robot_apart_drives_the_arc_it_drives_alone() -> None:
    # Held for the whole tick in the Space apart (its motors settled), as alone in the world
    # it is held for the one pymunk step a tick that nothing near needs.
    data = swarm_scenario(FLEET)
    sim = Simulation.from_dict(data, source="swarm")
    sim.run(2.0)
    checked = 0
    for entry in data["robots"][:12]:
        robot = sim.robots[entry["name"]]
        if robot.body.space is not sim.world.apart_space:
            continue
        alone = Simulation.from_dict(dict(data, robots=[entry]), source="alone")
        alone.run(2.0)
        x, y, theta = alone.robots[entry["name"]].pose
        assert math.hypot(robot.pose[0] - x, robot.pose[1] - y) < 2e-4  # [m] after ~1 m
        assert abs(robot.pose[2] - theta) < 1e-9
        checked += 1
    assert checked >= 8


def test_a_lidar_fleet_steps_apart_and_sees_the_robots_apart() -> None:
    # The caster reads both Spaces: robots with LiDARs step apart too, their shapes with
    # them, and every scan is what pymunk gives over both (rays end on robots apart).
    from pymunk_bot.sensors.raycast import Spaces, reference_cast

    sim = Simulation.from_dict(swarm_scenario(FLEET, beams=32, max_range=4.0), source="swarm")
    world = sim.world
    both = Spaces((world.contact_space, world.apart_space))
    scans = on_robots_apart = 0
    for _ in range(60):
        sim.step()
        for robot in list(sim.robots.values())[:40]:
            scan = robot.lidar.latest
            if scan is None or scan.time != sim.time:
                continue
            origin, angles = tuple(robot.body.position), robot.lidar.angles + robot.body.angle
            want = reference_cast(both, origin, angles, 4.0, robot.shape.filter)
            assert np.array_equal(scan.ranges, want)
            contact_only = reference_cast(world.contact_space, origin, angles, 4.0,
                                          robot.shape.filter)
            on_robots_apart += int((contact_only != want).any())
            scans += 1
    assert _apart(sim) > FLEET // 2 and not world.whole
    assert scans >= 200 and on_robots_apart >= scans // 2


def test_asking_for_the_space_brings_every_robot_back() -> None:
    sim = _swarm()
    sim.run(0.5)
    assert _apart(sim) > 0
    space = sim.space
    bodies = set(space.bodies)
    assert all(r.body in bodies and r.control in bodies for r in sim.robots.values())
    assert not sim.world.apart_space.bodies
    sim.run(0.5)  # the run goes on in one Space
    assert _apart(sim) == 0 and not sim.world.apart_space.bodies


def test_a_robot_teleported_into_another_is_pushed_out() -> None:
    sim = _swarm()
    sim.run(0.5)
    mover = next(r for r in sim.robots.values() if r.body.space is sim.world.apart_space)
    other = next(r for r in sim.robots.values() if r is not mover
                 and r.body.space is sim.world.apart_space)
    x, y = other.body.position
    mover.teleport(x + 0.1, y, 0.0)  # 10 cm from its centre: deep inside it
    sim.step()
    assert mover.body.space is sim.world.contact_space
    hits = sim.world.contact_space.point_query(tuple(mover.body.position), 0.0,
                                               pymunk.ShapeFilter())
    assert mover.shape in {hit.shape for hit in hits}  # back, where it landed
    sim.run(0.5)
    assert math.dist(mover.body.position, other.body.position) > mover.radius + other.radius - 0.01
