"""Contacts hold at every speed, acceleration and dt a scenario allows: no robot passes an
obstacle, no pushed crate passes a wall, no contact deeper than 1 cm (a seeded subset of the
bench's 1000 randomized trials: `python -m bench.contacts`)."""
from __future__ import annotations

import pytest

from bench.contacts import WALL_X, deepest_overlap, run_trials
from pymunk_bot.engine.simulation import Simulation


@pytest.mark.parametrize("seed", [11, 12])
def test_randomized_contacts_hold(seed):
    summary = run_trials(24, seed=seed)
    assert summary.trials == 24 and set(summary.by_kind) == {"wall", "post", "crate", "head-on"}
    assert summary.crossings == 0, summary.by_kind
    assert summary.max_penetration <= 0.01, summary.by_kind


def test_contacts_hold_below_top_speed_where_ticks_take_fewer_substeps():
    """Diff, car-like and omni robots at 20-90 % of their top speed: by default a tick with
    substeps takes only as many as those speeds need, and contacts hold as at full speed."""
    summary = run_trials(24, seed=13, slower=True)
    assert summary.trials == 24 and set(summary.by_kind) == {"wall", "post", "crate", "head-on"}
    assert summary.crossings == 0, summary.by_kind
    assert summary.max_penetration <= 0.01, summary.by_kind


def test_a_robot_at_a_third_of_its_top_speed_meets_a_wall_in_the_substeps_its_speed_needs():
    """A robot built for 2 m/s (5 substeps per 1/60 s tick) driving at 0.6 m/s into a thin
    wall: the ticks near the wall take 2 substeps (0.6 m/s plus what the motors could add
    within two ticks), and it stops at the wall no deeper than 1 cm."""
    data = {"name": "slow", "world": {"size": [6.0, 4.0]},
            "obstacles": [{"type": "wall", "start": [WALL_X, 0.0], "end": [WALL_X, 4.0],
                           "thickness": 0.02}],
            "robots": [{"name": "a", "pose": [1.0, 2.0, 0.0], "max_wheel_speed": 2.0,
                        "controller": {"type": "velocity", "v": 0.6}}]}
    sim = Simulation.from_dict(data)
    deepest = 0.0
    for _ in range(round(6.0 / sim.dt)):
        sim.step()
        deepest = max(deepest, deepest_overlap(sim.space))
    assert sim.substeps == 5
    assert WALL_X - 0.25 < sim.robots["a"].pose[0] < WALL_X  # stopped at the wall
    assert 0.0 < deepest <= 0.01
    took_substeps = sim.steps - sim.single_substep_ticks
    assert took_substeps > 100  # pushing against the wall from about 4 s on
    # every one of them 2 steps, but the run's first tick, which takes the full count
    assert sim.pymunk_steps == sim.single_substep_ticks + 2 * (took_substeps - 1) + 5
