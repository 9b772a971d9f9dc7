"""Walkers swapping places across a circle (exactly symmetric: RVO2's classic case), or crossing a
square in four groups, reach their goals without overlapping: a small seeded perturbation breaks
the symmetry that held ORCA walkers still in the middle for the whole run, and social-force
walkers' velocities close no gap within a tick (actors/clearance.py) (issue 33)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import pymunk_bot as pb
from pymunk_bot.actors.pedestrians import Crowd

OVERLAP = -0.001  # [m] disc clearance below this is an overlap (social-force walkers)
# [m] ... ORCA walkers': none at all. Nothing but walkers moves in these crossings and a walker's
# velocity is set before pymunk's step, so a walker moves exactly velocity * dt unless a contact
# pushes it; ORCA walkers stop CONTACT_MARGIN (5 mm, the contact solver's slop) short of each
# other (actors/orca.py, closing_limits), so contacts never start. Before that, ORCA's
# least-violating answers in the dense middle brought walkers up to 1.5 mm into each other.
ORCA_OVERLAP = 0.0
ORCA_SEEDS = range(4)
# [s] ORCA walkers crossing the circle or the square must all arrive within this. Each walks
# 2 * 2.5 = 5 m, 3.8 s at 1.3 m/s alone; social-force walkers crossing the square arrive by 5.4
# to 11.9 s (8 to 20 of them), and ORCA slows down earlier (it avoids anything it could meet
# within its 5 s horizon): 20 s, five free walks, leaves room for that, and none for a jam that
# holds them in the middle (before issue 33's fix, 12 and 16 walkers never left the square's in
# 40 s, and walkers crossing the circle took 25 to 36 s). Over seeds 0 to 15 the last walker
# arrives by 14.2 s in the circle and 19.4 s in the square (20 walkers, seed 3: the last one
# threading its way among those already standing at their goals; 18.0 s before they kept apart).
ORCA_CROSSING_TIME = 20.0


def circle_crossing(n: int, policy: str, radius: float = 2.5) -> dict:
    """``n`` walkers evenly on a circle about (4, 4), each walking to the opposite point."""
    walkers = []
    for k in range(n):
        a = 2.0 * math.pi * k / n
        dx, dy = radius * math.cos(a), radius * math.sin(a)
        walkers.append({"type": "pedestrian", "center": [4.0 + dx, 4.0 + dy],
                        "goals": [[4.0 - dx, 4.0 - dy]], "mode": "once", "policy": policy})
    return {"name": "circle_crossing", "world": {"size": [8.0, 8.0], "duration": 40.0},
            "obstacles": walkers,
            "robots": [{"name": "r1", "pose": [0.4, 0.4, 0.0], "controller": {"type": "wheels"}}]}


def square_crossing(n: int, policy: str, half: float = 2.5, spacing: float = 0.7) -> dict:
    """``n`` walkers (a multiple of 4) in four groups, one on each side of a square about
    (4, 4), each walker walking straight across to the opposite side: four-fold symmetric."""
    walkers = []
    for side in range(4):
        c, s = math.cos(math.pi / 2 * side), math.sin(math.pi / 2 * side)
        for k in range(n // 4):
            offset = (k - (n // 4 - 1) / 2) * spacing
            start, goal = (-half, offset), (half, offset)
            walkers.append({"type": "pedestrian", "mode": "once", "policy": policy,
                            "center": [4.0 + c * start[0] - s * start[1],
                                       4.0 + s * start[0] + c * start[1]],
                            "goals": [[4.0 + c * goal[0] - s * goal[1],
                                       4.0 + s * goal[0] + c * goal[1]]]})
    return {**circle_crossing(0, policy), "name": "square_crossing", "obstacles": walkers}


def crossing(n: int, policy: str, seconds: float = 40.0, layout=circle_crossing,
             seed: int = 0) -> tuple[bool, float]:
    """(every walker reached its goal, the smallest disc clearance between walkers [m]) in a run
    of ``seconds`` of the scenario ``layout`` makes with ``seed``; it ends when every walker has
    arrived (they stand still at their goals from then on)."""
    sim = pb.Simulation.from_dict({**layout(n, policy), "seed": seed})
    crowd = next(a for a in sim.world.actors if isinstance(a, Crowd))
    radius = crowd.radius
    closest = math.inf
    for _ in range(round(seconds / sim.config.world.dt)):
        sim.step()
        p = crowd.positions()
        gap = np.hypot(*(p[:, None, :] - p[None, :, :]).transpose(2, 0, 1)) - (
            radius[:, None] + radius[None, :])
        np.fill_diagonal(gap, np.inf)
        closest = min(closest, float(gap.min()))
        if crowd.done.all():  # done: a "once" walker reached its last goal
            break
    return bool(np.all(crowd.done)), closest


@pytest.mark.parametrize("seed", ORCA_SEEDS)
@pytest.mark.parametrize("n", [6, 8, 12, 16, 20])
def test_orca_walkers_swapping_across_a_circle_reach_their_goals_without_overlap(n, seed):
    reached, closest = crossing(n, "orca", ORCA_CROSSING_TIME, seed=seed)
    assert reached, f"{n} ORCA walkers did not all reach their goals within " \
                    f"{ORCA_CROSSING_TIME} s (seed {seed})"
    assert closest >= ORCA_OVERLAP, \
        f"walkers overlapped by {-closest * 1000:.3f} mm (seed {seed})"


@pytest.mark.parametrize("n", [6, 12, 20])
def test_social_force_walkers_swapping_across_a_circle_reach_their_goals_without_overlap(n):
    reached, closest = crossing(n, "social_force")
    assert reached, f"{n} social-force walkers did not all reach their goals"
    assert closest >= OVERLAP, f"walkers overlapped by {-closest * 1000:.1f} mm"


@pytest.mark.parametrize("n", [8, 12, 20])
def test_social_force_walkers_crossing_a_square_in_four_groups_reach_their_goals_without_overlap(n):
    reached, closest = crossing(n, "social_force", 30.0, square_crossing)
    assert reached, f"{n} social-force walkers did not all reach their goals"
    assert closest >= OVERLAP, f"walkers overlapped by {-closest * 1000:.1f} mm"


@pytest.mark.parametrize("seed", ORCA_SEEDS)
@pytest.mark.parametrize("n", [8, 12, 16, 20])
def test_orca_walkers_crossing_a_square_in_four_groups_reach_their_goals_without_overlap(n, seed):
    reached, closest = crossing(n, "orca", ORCA_CROSSING_TIME, square_crossing, seed)
    assert reached, f"{n} ORCA walkers did not all reach their goals within " \
                    f"{ORCA_CROSSING_TIME} s (seed {seed})"
    assert closest >= ORCA_OVERLAP, \
        f"walkers overlapped by {-closest * 1000:.3f} mm (seed {seed})"


def test_the_perturbation_is_seeded():
    first = pb.Simulation.from_dict(circle_crossing(6, "orca"))
    second = pb.Simulation.from_dict(circle_crossing(6, "orca"))
    first.run(5.0)
    second.run(5.0)
    assert [o.body.position for o in first.world.obstacles] == [
        o.body.position for o in second.world.obstacles]
