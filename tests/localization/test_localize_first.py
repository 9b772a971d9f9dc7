"""Issue 20, defect 3: controllers that drive on an estimate localize first, and a kidnapping
(``events:`` teleport, ``r.teleport``) is noticed.

Before: a waypoint tour on a global start drove off at once on the filter's first guess (a
mean of particles spread over the whole office) and into the walls.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from pymunk_bot import Simulation
from pymunk_bot.controllers.base import LOCALIZING
from pymunk_bot.controllers.localizing import LOCALIZING_SPEED
from pymunk_bot.localization.base import LOCALIZED_POSITION_STD


def _office(localization, events=None) -> dict:
    data = yaml.safe_load((Path(__file__).parents[2] / "scenarios" / "mcl_office.yaml").read_text())
    robot = data["robots"][0]
    robot["localization"] = localization
    data["expect"] = {}
    if events is not None:
        data["events"] = events
    return data


def test_a_global_start_explores_at_a_creep_until_localized_then_tours_without_collision():
    data = _office({"type": "mcl", "initial": "global", "max_particles": 5000})
    data["robots"][0]["pose"] = [4.8, 3.6, 0.0]  # between rooms (from a corner: see the report)
    sim = Simulation.from_dict(data)
    robot = sim.robots["r1"]
    start = robot.pose[:2].copy()
    sim.step()
    assert robot.controller.message == LOCALIZING and not robot.localizer.localized
    while not robot.localizer.localized and sim.time < 20.0:
        sim.step()
        # waiting means exploring on the LiDAR at a creep, not driving on a guess
        assert robot.controller.message == LOCALIZING or robot.localizer.localized
        assert abs(robot.velocity[0]) <= LOCALIZING_SPEED + 0.02  # [m/s] forward
        assert robot.collisions == 0
    assert robot.localizer.localized, "no trustworthy estimate within 20 s of turning"
    assert np.hypot(*(robot.localizer.pose[:2] - robot.pose[:2])) < 0.3
    sim.run(10.0)
    assert robot.controller.message != LOCALIZING
    assert np.hypot(*(robot.pose[:2] - start)) > 1.0  # it drove on
    assert robot.collisions == 0


@pytest.mark.parametrize("target", [[8.0, 4.5, 3.14], [2.0, 6.5, 0.0]])
def test_a_kidnapped_robot_stops_driving_on_its_estimate_with_the_defaults(target):
    # Before the scan-fit check, the product likelihood kept the kidnapped cloud tight and
    # "localized": the waypoint tour drove on it into the walls (1-4 collisions in 10 s).
    sim = Simulation.from_dict(_office(
        "mcl", events=[{"at": 5.0, "robot": "r1", "teleport": target}]))
    robot = sim.robots["r1"]
    sim.run(5.0)
    before = robot.odometry.pose.copy()
    assert robot.localizer.localized and robot.localizer.scan_fit > 0.9
    sim.step()
    assert np.allclose(robot.pose[:2], target[:2], atol=0.05)
    assert np.hypot(*(robot.odometry.pose[:2] - before[:2])) < 0.05  # odometry was not told
    # The next filter update sees the scan no longer fit the map from the estimate. (The one
    # after may already have found the true pose again, seeded from the scan: with sigma_hit
    # 0.1 m it did at [2, 6.5] within 0.2 s, so the check is on the first update.)
    updates = robot.localizer.updates
    while robot.localizer.updates == updates and sim.time < 6.0:
        sim.step()
    assert not robot.localizer.localized and robot.localizer.scan_fit < 0.7
    sim.step()  # the controller hears of it on its next tick
    assert robot.controller.message == LOCALIZING
    # It collides with nothing while localizing, and drives again only on an estimate that
    # is right (MCL seeds particles where the scan fits the map). After that the waypoint
    # tour heads straight for its next waypoint from wherever it was put, which may cross a
    # wall: `waypoints` plans nothing, so no collision bound past that point.
    while robot.controller.message == LOCALIZING and sim.time < 15.0:
        sim.step()
        assert robot.collisions == 0
    assert robot.controller.message != LOCALIZING, "not re-localized within 10 s"
    assert np.hypot(*(robot.localizer.pose[:2] - robot.pose[:2])) < 0.3


def test_teleport_from_python_moves_at_once_and_refuses_a_point_outside():
    sim = Simulation.from_dict(_office("odometry"))
    robot = sim.robots["r1"]
    sim.run(1.0)
    distance = robot.distance
    robot.teleport(8.0, 4.5, 1.0)
    assert np.allclose(robot.pose, (8.0, 4.5, 1.0))
    sim.step()
    assert robot.distance - distance < 0.05  # the jump is not travel
    with pytest.raises(ValueError, match="outside the arena"):
        robot.teleport(20.0, 1.0, 0.0)


def test_an_event_for_an_unknown_robot_is_one_clear_line(tmp_path, capsys):
    from pymunk_bot.cli import main
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(_office("odometry", events=[
        {"at": 1.0, "robot": "r2", "teleport": [1.0, 1.0, 0.0]}])))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "events[0].robot" in err and "r2" in err and "Traceback" not in err


def test_the_bound_is_the_documented_one():
    assert LOCALIZED_POSITION_STD == 0.2
