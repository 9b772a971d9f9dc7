"""Social-force walkers never move into contact (actors/clearance.py): not with each other, not
with walls, not with a robot, even squeezed in a narrow corridor, and a dense counterflow still
gets through (their pushes pass on by impulses, as contacts did)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import pymunk_bot as pb
from pymunk_bot.actors.pedestrians import Crowd

OVERLAP = -0.001  # [m] a clearance below this is an overlap


def counterflow(walkers: int, width: float, robot_x: float, seed: int = 0,
                speed_std: float = 0.0, policy: str = "social_force") -> dict:
    """``walkers`` walking both ways down a 14 m corridor ``width`` wide, in queues 0.6 m
    apart, with ``policy``; a standing robot (radius 0.2 m) on the corridor's axis at
    ``robot_x``."""
    people = []
    for k in range(walkers):
        y = 0.35 + (width - 0.7) * ((k * 0.37) % 1.0)
        start, goal = (0.5 + 0.6 * (k // 2), 11.5) if k % 2 else (11.5 - 0.6 * (k // 2), 0.5)
        people.append({"type": "pedestrian", "center": [start, y], "goals": [[goal, y]],
                       "mode": "once", "speed_std": speed_std, "policy": policy})
    return {"name": "counterflow", "seed": seed,
            "world": {"size": [14.0, width], "duration": 40.0}, "obstacles": people,
            "robots": [{"name": "r1", "pose": [robot_x, width / 2, 0.0], "radius": 0.2,
                        "controller": {"type": "wheels"}}]}


def clearances(data: dict, seconds: float) -> dict:
    """The smallest clearances [m] over the run (walker-walker, walker-wall, walker-robot),
    the robot's contact episodes and how many walkers arrived."""
    sim = pb.Simulation.from_dict(data)
    crowd = next(a for a in sim.world.actors if isinstance(a, Crowd))
    r = crowd.radius
    width, height = sim.config.world.size
    robot = sim.robots["r1"]
    out = {"walkers": math.inf, "walls": math.inf, "robot": math.inf}
    for _ in range(round(seconds / sim.config.world.dt)):
        sim.step()
        p = crowd.positions()
        gap = np.hypot(*(p[:, None, :] - p[None, :, :]).transpose(2, 0, 1)) - (
            r[:, None] + r[None, :])
        np.fill_diagonal(gap, np.inf)
        walls = np.minimum.reduce([p[:, 0], width - p[:, 0], p[:, 1], height - p[:, 1]]) - r
        to_robot = np.hypot(*(p - robot.pose[:2]).T) - r - robot.spec.radius
        for key, now in (("walkers", gap), ("walls", walls), ("robot", to_robot)):
            out[key] = min(out[key], float(now.min()))
    out["collisions"] = robot.collisions
    out["arrived"] = int(crowd.done.sum())
    return out


def test_a_counterflow_in_a_narrow_corridor_gets_through_without_touching():
    # 12 walkers in a 1.6 m corridor (three bodies wide), the robot out of their way.
    seen = clearances(counterflow(12, 1.6, robot_x=13.0, speed_std=0.15), 30.0)
    assert seen["walkers"] >= OVERLAP, f"walkers overlapped by {-seen['walkers'] * 1e3:.1f} mm"
    assert seen["walls"] >= OVERLAP, f"a walker overlapped a wall by {-seen['walls'] * 1e3:.1f} mm"
    assert seen["arrived"] >= 11  # (before the clearance: 11; limiting each walker's own
    # velocity without impulses on the other froze this corridor: 0 to 9 arrived)


def test_orca_walkers_in_a_narrow_counterflow_never_overlap_nor_walk_into_the_robot():
    # ORCA's constraints leave no room here; its least-violating answers brought walkers 1.3 mm
    # into each other and twice into the robot near the corridor's end (seed 2), before ORCA
    # walkers were kept 5 mm apart, off the walls and off robots they see (actors/orca.py).
    seen = clearances(counterflow(12, 1.6, robot_x=13.0, seed=2, speed_std=0.15,
                                  policy="orca"), 30.0)
    assert seen["walkers"] >= 0.0, f"walkers overlapped by {-seen['walkers'] * 1e3:.2f} mm"
    assert seen["walls"] >= 0.0 and seen["robot"] >= 0.0
    assert seen["collisions"] == 0
    assert seen["arrived"] >= 9  # as many as before


def test_walkers_squeezing_past_a_standing_robot_never_walk_into_it():
    # 8 walkers in a 1.6 m corridor with a robot standing in its middle: they jam around it
    # (0.7 m on either side of it, for two flows), and press against it and the walls.
    seen = clearances(counterflow(8, 1.6, robot_x=6.0), 15.0)
    assert seen["collisions"] == 0
    assert seen["robot"] >= OVERLAP, f"overlapped the robot by {-seen['robot'] * 1e3:.1f} mm"
    assert seen["walkers"] >= OVERLAP and seen["walls"] >= OVERLAP


@pytest.mark.parametrize("react", [True, False])
def test_only_walkers_that_react_to_robots_keep_clear_of_them(react):
    # One walker heading straight through a standing robot, its repulsions switched off: it
    # stops short of the robot if it reacts to robots, and walks into it (a contact the robot
    # counts) if it does not.
    data = {"name": "into_robot", "world": {"size": [8.0, 4.0]},
            "obstacles": [{"type": "pedestrian", "center": [1.0, 2.0], "goals": [[7.0, 2.0]],
                           "mode": "once", "social_strength": 0.0, "wall_strength": 0.0,
                           "react_to_robot": react}],
            "robots": [{"name": "r1", "pose": [4.0, 2.0, 0.0], "radius": 0.2,
                        "controller": {"type": "wheels"}}]}
    seen = clearances(data, 4.0)
    if react:
        assert seen["collisions"] == 0 and seen["robot"] >= OVERLAP
    else:
        assert seen["collisions"] >= 1
