"""The comparative benches compare like with like: same worlds, baselines that really move."""
from __future__ import annotations

import math

import numpy as np
import pytest

from bench import SECTIONS, fleet, irsim, learning_loop, run_all
from pymunk_bot.config import parse_scenario
from pymunk_bot.sensors.lidar import beam_angles
from pymunk_bot.engine.simulation import Simulation


@pytest.mark.slow  # end-to-end, several seconds: .ci/run runs it (-m slow)
def test_swarm_keeps_its_density_and_starts_clear():
    for n in (10, 100, 1000):
        config = parse_scenario(fleet.swarm_scenario(n), "swarm")  # robots inside boxes: exit 2
        width, height = config.world.size
        assert len(config.robots) == n
        assert 3.0 <= width * height / n <= 6.0  # [m^2] per robot, about 4 at any size
        assert len(config.obstacles) == max(1, n // fleet.ROBOTS_PER_BOX)
    assert fleet.swarm_scenario(50, seed=3) == fleet.swarm_scenario(50, seed=3)


def test_bare_baseline_moves_the_swarm_on_the_same_space():
    sim = Simulation.from_dict(fleet.swarm_scenario(20))
    sim.run(fleet.WARM_UP)
    before = np.array([r.pose[:2] for r in sim.robots.values()])
    fleet._bare_ticks(sim, 30)  # 0.5 s of space.step alone
    moved = np.hypot(*(np.array([r.pose[:2] for r in sim.robots.values()]) - before).T)
    assert np.median(moved) > 0.5 * 0.2 * 0.5  # the slowest command is 0.2 m/s


def test_irsim_world_has_the_same_beams_and_robots():
    config = parse_scenario(irsim.scenario(), "irsim")
    world = irsim.irsim_world()
    assert len(config.robots) == world["robot"][0]["number"] == 10
    lidar = world["robot"][0]["sensors"][0]
    theirs = np.linspace(-lidar["angle_range"] / 2, lidar["angle_range"] / 2, lidar["number"])
    ours = config.robots[0].lidar.offset[2] + beam_angles(config.robots[0].lidar.beams,
                                                         config.robots[0].lidar.fov)
    np.testing.assert_allclose(ours, theirs, atol=1e-12)
    assert all(-math.pi < pose[2] <= math.pi for pose in irsim.ring_poses())


def test_irsim_skips_with_a_message_without_its_venv(tmp_path):
    result = irsim.run(quick=True, venv=tmp_path / "nowhere")
    assert "--setup" in result["skipped"] and result["ours_cpu_s"] > 0


def test_bare_learning_loop_sees_the_same_world():
    data = learning_loop.scenario()
    sim = Simulation.from_dict(data)
    robot = sim.robots["r0"]
    joints = robot.body.constraints
    loop = learning_loop.BareLoop(data, 1.0, 1.0, sim.substeps, sim.dt)
    x, y, theta = robot.pose
    bare = []
    for a in robot.lidar.angles:
        end = (x + learning_loop.MAX_RANGE * math.cos(theta + a),
               y + learning_loop.MAX_RANGE * math.sin(theta + a))
        hit = loop.space.segment_query_first((x, y), end, 0.0, loop.filter)
        bare.append(learning_loop.MAX_RANGE if hit is None else hit.alpha * learning_loop.MAX_RANGE)
    np.testing.assert_allclose(robot.lidar.scan(), bare, atol=1e-6)
    assert len(joints) == 2 and loop.steps_per_period == round(0.1 / sim.dt) * sim.substeps


def test_unknown_bench_section_is_refused():
    with pytest.raises(ValueError, match="valid: simulation"):
        run_all(only=["nope"])
    assert {"fleet", "learning_loop", "irsim", "contacts", "fuzz"} <= set(SECTIONS)
