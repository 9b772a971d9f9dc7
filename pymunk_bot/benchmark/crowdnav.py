"""CrowdNav's test layouts, drawn exactly as its released code draws them (vita-epfl/CrowdNav,
crowd_sim/envs/crowd_sim.py; facts taken from it, the code written anew).

``crowdnav_circle_crossing``, in CrowdNav's own frame (origin at the circle's centre):
- the robot starts at (0, -R) and its goal is (0, R) (R the circle radius, 4 m);
- each human in turn draws an angle a uniform in [0, 2 pi) and a start
  R (cos a, sin a) + (u_x - 0.5, u_y - 0.5) v_pref (u uniform in [0, 1): the noise is on the
  start, up to half a metre each way at 1 m/s); its goal is the start mirrored through the
  centre, -start;
- a draw is kept when the start is at least r_human + r_other + 0.2 m (the discomfort
  distance) from the start and from the goal of the robot and of every human placed before
  (0.8 m with radii 0.3); else it is drawn again;
- the draws come from numpy's legacy Mersenne Twister seeded with 1000 + i for test case i
  (CrowdNav seeds ``np.random.seed(1000 + i)``: its validation cases take the first 1000), so
  seed i here is CrowdNav's test case i, start for start.

``crowdnav_square_crossing`` (CrowdNav's other test rule), the robot as above:
- each human in turn draws a side (u > 0.5: left, x < 0; else right), then a start with x
  uniform over that half of a square of side W (10 m) and y uniform in [-W/2, W/2), redrawn
  until it is at least r_human + r_other + 0.2 m from every earlier agent's start (the robot's
  too); then a goal the same way on the other half, redrawn until as far from every earlier
  agent's goal;
- the same seeds as above.

The legacy generator is used only here, to give CrowdNav's episodes; everything else in a run
draws from the run's own seeded Generator.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

CROWDNAV_LAYOUTS = ("crowdnav_circle_crossing", "crowdnav_square_crossing")
TEST_CASE_OFFSET = 1000  # CrowdNav's test case i is seeded with 1000 + i
DISCOMFORT_DISTANCE = 0.2  # [m] kept between bodies at the start, beyond touching
SQUARE_WIDTH = 10.0  # [m] CrowdNav's square_width (configs/env.config)
MAX_DRAWS = 100_000  # per human; a crowd too dense for the circle fails instead of hanging


class CrowdNavLayoutError(ValueError):
    """No room for the humans (one line)."""


Layout = tuple[np.ndarray, np.ndarray, list[tuple[np.ndarray, np.ndarray]]]
Agent = tuple[np.ndarray, np.ndarray, float]  # start, goal [m] and radius [m]


def _drawn_clear(propose: Callable[[], np.ndarray], clear_of: Callable[[np.ndarray], bool],
                 problem: str) -> np.ndarray:
    """``propose()`` drawn again until ``clear_of`` the point, as CrowdNav redraws; at most
    MAX_DRAWS times, then CrowdNavLayoutError ("no room for ``problem``")."""
    for _ in range(MAX_DRAWS):
        p = propose()
        if clear_of(p):
            return p
    raise CrowdNavLayoutError(f"no room for {problem} after {MAX_DRAWS} draws")


def _apart(p: np.ndarray, radius: float, agent: Agent, of: int) -> bool:
    """``p`` (a body of ``radius``) is the discomfort distance beyond touching ``agent``'s
    start (``of`` 0) or goal (1)."""
    return math.hypot(*(p - agent[of])) >= radius + agent[2] + DISCOMFORT_DISTANCE


def circle_crossing(seed: int, humans: int, circle_radius: float, robot_radius: float,
                    human_radius: float, human_speed: float) -> Layout:
    """(robot start, robot goal, [(human start, human goal), ...]) of CrowdNav's circle
    crossing test case ``seed``, in CrowdNav's frame [m] (see the module doc)."""
    draw = np.random.RandomState(TEST_CASE_OFFSET + seed).random_sample
    start, goal = np.array([0.0, -circle_radius]), np.array([0.0, circle_radius])
    placed: list[Agent] = [(start, goal, robot_radius)]

    def on_circle() -> np.ndarray:
        angle = draw() * 2.0 * math.pi
        noise_x = (draw() - 0.5) * human_speed
        noise_y = (draw() - 0.5) * human_speed
        return np.array([circle_radius * math.cos(angle) + noise_x,
                         circle_radius * math.sin(angle) + noise_y])

    for h in range(humans):
        p = _drawn_clear(on_circle, lambda p: all(
            _apart(p, human_radius, a, 0) and _apart(p, human_radius, a, 1) for a in placed),
            f"human {h + 1} of {humans} on a circle of radius {circle_radius} m")
        placed.append((p, -p, human_radius))
    return start, goal, [(s, g) for s, g, _ in placed[1:]]


def square_crossing(seed: int, humans: int, circle_radius: float, square_width: float,
                    robot_radius: float, human_radius: float) -> Layout:
    """(robot start, robot goal, [(human start, human goal), ...]) of CrowdNav's square
    crossing test case ``seed``, in CrowdNav's frame [m] (see the module doc)."""
    draw = np.random.RandomState(TEST_CASE_OFFSET + seed).random_sample
    start, goal = np.array([0.0, -circle_radius]), np.array([0.0, circle_radius])
    placed: list[Agent] = [(start, goal, robot_radius)]

    def on_half(sign: float) -> Callable[[], np.ndarray]:
        return lambda: np.array([draw() * 0.5 * square_width * sign,
                                 (draw() - 0.5) * square_width])

    for h in range(humans):
        sign = -1.0 if draw() > 0.5 else 1.0
        where = f"human {h + 1} of {humans} in a square of side {square_width} m"
        p = _drawn_clear(on_half(sign), lambda p: all(
            _apart(p, human_radius, a, 0) for a in placed), f"the start of {where}")
        g = _drawn_clear(on_half(-sign), lambda g: all(
            _apart(g, human_radius, a, 1) for a in placed), f"the goal of {where}")
        placed.append((p, g, human_radius))
    return start, goal, [(s, g) for s, g, _ in placed[1:]]
