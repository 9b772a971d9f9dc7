"""Pedestrians in copies of a world that share one pymunk Space (the vector env's copies): each
copy's walkers meet and feel its own robot and never another copy's, by body, by force or by
LiDAR."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from pymunk_bot.actors.pedestrians import WALKER_CATEGORIES  # noqa: E402
from pymunk_bot.envs import NavigationVectorEnv  # noqa: E402

# One walker stands in the robot's way, 3 m ahead (it neither steps aside nor walks); another
# stands beside that way, and steps away from a robot that comes near.
STANDING = {"type": "pedestrian", "center": [4.0, 1.5], "goals": [[4.0, 1.5]],
            "social_strength": 0.0, "wall_strength": 0.0}
BYSTANDER = {"type": "pedestrian", "center": [3.5, 0.6], "goals": [[3.5, 0.6]]}
CORRIDOR = {"name": "crowd_copies", "world": {"size": [8.0, 3.0], "duration": 6.0},
            "obstacles": [STANDING, BYSTANDER],
            "robots": [{"name": "r1", "pose": [1.0, 1.5, 0.0], "radius": 0.2,
                        "goal": {"position": [7.0, 1.5]},
                        "lidar": {"beams": 36, "max_range": 6.0}}]}
FORWARD, STILL = [1.0, 0.0], [0.0, 0.0]


def run(first_slot: list[float]):
    """Both copies for 4 s, copy 0's robot driving ``first_slot``, copy 1's holding still:
    (the sims, each copy's walkers at every step (2, T, walkers, 2), copy 1's LiDAR straight
    ahead at every step)."""
    envs = NavigationVectorEnv(num_envs=2, scenario=CORRIDOR)
    envs.reset(seed=0)
    sims = [episode.sim for episode in envs.episodes]
    ahead = int(np.argmin(np.abs(sims[1].robots["r1"].lidar.angles)))
    walkers, seen = [], []
    for _ in range(40):
        envs.step(np.array([first_slot, STILL], np.float32))
        walkers.append([[tuple(o.body.position) for o in sim.world.obstacles] for sim in sims])
        seen.append(float(sims[1].robots["r1"].lidar.scan()[ahead]))
    return sims, np.array(walkers).transpose(1, 0, 2, 3), np.array(seen)


def test_a_walker_meets_and_feels_its_own_copys_robot_and_never_the_other_copys():
    sims, walkers, seen = run(FORWARD)
    assert sims[0].world.space is sims[1].world.space  # the copies share one Space
    bits = [sim.world.obstacles[0].shapes[0].filter.categories for sim in sims]
    assert bits[0] != bits[1] and all(b & WALKER_CATEGORIES == b for b in bits)
    robots = [sim.robots["r1"] for sim in sims]
    assert robots[0].collisions >= 1  # copy 0's robot ran into copy 0's walker ...
    assert robots[0].pose[0] < 4.0 - 0.45 + 0.05  # ... and was held up by it
    assert robots[1].collisions == 0  # copy 1's robot was never touched
    _, alone, _ = run(STILL)  # copy 0's robot stays put
    assert np.abs(walkers[0] - alone[0]).max() > 1e-4  # copy 0's walkers felt their robot come
    np.testing.assert_allclose(walkers[1], alone[1], atol=1e-12)  # copy 1's felt nothing of it
    # Copy 1's LiDAR sees its own walker 3 m ahead (less the radii) the whole time.
    assert seen == pytest.approx([4.0 - 0.25 - 1.0] * len(seen), abs=0.02)
