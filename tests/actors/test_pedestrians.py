"""Pedestrians (social force model): they reach their goals, avoid each other, robots and
walls, are seen by LiDAR as discs, count as collisions, and are deterministic per seed."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot

from pymunk_bot.config.errors import ScenarioError


def walker(start, goals, **extra) -> dict:
    return {"type": "pedestrian", "center": list(start), "goals": [list(g) for g in goals], **extra}


def corridor_walkers(**extra) -> list[dict]:
    """Two people walking at each other down a 2.4 m wide corridor."""
    return [walker((1.0, 1.2), [(11.0, 1.2)], mode="once", **extra),
            walker((11.0, 1.25), [(1.0, 1.25)], mode="once", **extra)]


def track(sim, seconds: float) -> np.ndarray:
    """Positions of every pedestrian at every tick, shape (T, P, 2)."""
    walkers = [o for o in sim.world.obstacles if o.config.type == "pedestrian"]
    out = []
    for _ in range(round(seconds / sim.dt)):
        sim.step()
        out.append([tuple(w.body.position) for w in walkers])
    return np.array(out)


def test_two_walkers_pass_each_other_without_touching_and_reach_their_goals(make_sim):
    sim = make_sim([robot([6, 2.2, 0], radius=0.1)], corridor_walkers(), size=(12.0, 2.4))
    path = track(sim, 14.0)
    gap = np.hypot(*(path[:, 0] - path[:, 1]).T)
    assert gap.min() > 0.5  # two 0.25 m bodies never touch
    assert math.dist(path[-1, 0], (11.0, 1.2)) < 0.3
    assert math.dist(path[-1, 1], (1.0, 1.25)) < 0.3
    # They stay off the walls (y = 0 and y = 2.4) by more than their radius.
    assert path[:, :, 1].min() > 0.25 and path[:, :, 1].max() < 2.4 - 0.25


def test_walkers_step_around_a_standing_robot(make_sim):
    sim = make_sim([robot([6, 2.0, 0], radius=0.3)],
                   [walker((1.0, 2.0), [(11.0, 2.0)], mode="once")], size=(12.0, 4.0))
    path = track(sim, 12.0)
    clearance = np.hypot(path[:, 0, 0] - 6.0, path[:, 0, 1] - 2.0)
    assert clearance.min() > 0.55  # never touched the robot
    assert sim.robots["r"].collisions == 0
    assert path[-1, 0, 0] > 10.5


def test_a_robot_that_bumps_a_walker_counts_a_collision(make_sim):
    sim = make_sim([robot([2, 3, 0])], [walker((4.0, 3.0), [(4.0, 3.0)], social_strength=0.0,
                                                 wall_strength=0.0)],
                   size=(8.0, 6.0))
    sim.robots["r"].set_velocity(1.0, 0.0)
    sim.run(3.0)
    # Pushing a walker is chaotic (a millimetre of start moves 1 to 9 separate contact
    # episodes): what must hold is that the bump counts.
    assert sim.robots["r"].collisions >= 1


def test_lidar_sees_a_walker_as_a_disc(make_sim):
    lidar = {"beams": 8, "max_range": 10.0}
    sim = make_sim([robot([1, 3, 0], lidar=lidar)],
                   [walker((4.0, 3.0), [(4.0, 3.0)], radius=0.3)], size=(8.0, 6.0))
    sim.step()
    lidar = sim.robots["r"].lidar
    ahead = int(np.argmin(np.abs(lidar.angles)))
    x = sim.world.obstacles[0].body.position.x
    assert lidar.scan()[ahead] == pytest.approx(x - 0.3 - 1.0, abs=1e-6)


def test_the_same_seed_gives_the_same_crowd_and_another_seed_another(make_sim):
    extra = {"speed_std": 0.2, "fluctuation": 0.3}
    runs = [track(make_sim([robot([6, 2.2, 0], radius=0.1)], corridor_walkers(**extra),
                           size=(12.0, 2.4), seed=seed), 3.0) for seed in (4, 4, 5)]
    assert np.array_equal(runs[0], runs[1])
    assert not np.allclose(runs[0], runs[2])


def test_pingpong_walks_back_and_loop_goes_round(make_sim):
    sim = make_sim([robot([9, 7, 0])],
                   [walker((2.0, 1.0), [(2.0, 1.0), (6.0, 1.0)], mode="pingpong"),
                    walker((2.0, 6.0), [(2.0, 6.0), (6.0, 6.0), (6.0, 4.0)], mode="loop")],
                   size=(10.0, 8.0))
    path = track(sim, 14.0)
    x = path[:, 0, 0]
    first_far = int(np.argmax(x > 5.6))
    back = first_far + int(np.argmax(x[first_far:] < 2.4))
    assert 0 < first_far < back and (x[back:] > 5.6).any()  # there, back, and there again
    # After (6, 4) the looping walker cuts diagonally back to (2, 6): x = 4 at y = 5.
    loop = path[:, 1]
    corner = int(np.argmax(loop[:, 1] < 4.3))
    diagonal = loop[corner:][np.abs(loop[corner:, 0] - 4.0) < 0.05]
    assert corner > 0 and len(diagonal) and diagonal[0, 1] == pytest.approx(5.0, abs=0.3)


@pytest.mark.parametrize("obstacle, message", [
    (walker((9.0, 1.0), [(2.0, 1.0)]), r"obstacles\[0\]\.center: pedestrian .* not inside"),
    (walker((2.0, 1.0), [(2.0, 1.0), (7.9, 1.0)]), r"obstacles\[0\]\.goals\[1\]: pedestrian"),
    (walker((2.0, 1.0), []), r"obstacles\[0\]\.goals: "),
    (walker((2.0, 1.0), [(3, 1)], speed=9.0), r"obstacles\[0\]\.speed: "),
])
def test_bad_pedestrians_are_one_line_errors(make_sim, obstacle, message):
    with pytest.raises(ScenarioError, match=message):
        make_sim([robot([1, 5, 0])], [obstacle], size=(8.0, 6.0))


def test_robot_starting_on_a_walker_is_bad_input(make_sim):
    with pytest.raises(ScenarioError, match=r"robots\[0\]\.pose: robot starts inside obstacles\[0\]"):
        make_sim([robot([2.1, 1.0, 0])], [walker((2.0, 1.0), [(5.0, 1.0)])], size=(8.0, 6.0))
