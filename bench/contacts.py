"""Contacts that hold: randomized trials at every speed, acceleration and dt a scenario allows.

    python -m bench.contacts [TRIALS]      (also part of `pymunk-bot bench`)

Each trial drives robots of random size, speed and acceleration at one of four hazards: a thin
wall, a small post, a light crate pushed into a 1 cm wall, another robot head-on. It counts
crossings (a robot or crate ending up on the far side of a wall, or a centre passing through a
post or another robot) and the deepest overlap pymunk reports in any contact.

The robots drive at their top speed (the scenario's substep count holds them), and in a third
set (``slower``) at 20-90 % of it, with diff, car-like and omni drives in turn: by default a
tick with substeps then takes only as many as those speeds need (physics/substeps.py).
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pymunk

from pymunk_bot.config.schema import MAX_ACCEL
from pymunk_bot.engine.simulation import Simulation
from bench.simulation import every_substep

KINDS = ("wall", "post", "crate", "head-on")
DRIVES = ("diff", "ackermann", "omni")  # the slower trials' drives, in turn
MAX_TRIAL_SPEED = 3.0  # [m/s]
DTS = (1 / 30, 1 / 60, 1 / 120, 1 / 240)  # [s]
WALL_X = 3.0  # [m]


@dataclass
class Summary:
    """Counts over many trials."""

    trials: int = 0
    crossings: int = 0
    deeper_than_1cm: int = 0
    max_penetration: float = 0.0  # [m]
    by_kind: dict = field(default_factory=dict)

    def add(self, kind: str, crossed: bool, penetration: float) -> None:
        self.trials += 1
        self.crossings += crossed
        self.deeper_than_1cm += penetration > 0.01
        self.max_penetration = max(self.max_penetration, penetration)
        n, c, worst = self.by_kind.get(kind, (0, 0, 0.0))
        self.by_kind[kind] = (n + 1, c + crossed, max(worst, penetration))


def deepest_overlap(space: pymunk.Space) -> float:
    """The deepest overlap [m] of any contact pymunk holds now."""
    worst = 0.0

    def visit(arbiter: pymunk.Arbiter) -> None:
        nonlocal worst
        for point in arbiter.contact_point_set.points:
            worst = max(worst, -point.distance)

    for body in space.bodies:
        if body.body_type == pymunk.Body.DYNAMIC:
            body.each_arbiter(visit)
    return worst


def trial_scenario(kind: str, rng: np.random.Generator, drive: str | None = None) -> dict:
    """One randomized trial as scenario data; ``drive``: the robots have that drive and are
    commanded 20-90 % of its top speed (None: diff drives at their top speed)."""
    v = float(rng.uniform(0.2, MAX_TRIAL_SPEED))
    accel = float(10 ** rng.uniform(0.0, math.log10(MAX_ACCEL)))
    radius = float(rng.uniform(0.05, 0.3))
    heading = float(rng.uniform(-0.6, 0.6))
    a: dict[str, Any] = {
        "name": "a", "pose": [1.0, 2.0, heading], "radius": radius,
        "track_width": max(0.06, 1.5 * radius), "max_wheel_speed": v, "max_accel": accel,
        "controller": {"type": "velocity", "v": v}}
    robots, obstacles = [a], []
    if kind == "wall":
        thickness = float(rng.uniform(0.01, 0.05))
        obstacles.append({"type": "wall", "start": [WALL_X, 0.0], "end": [WALL_X, 4.0],
                          "thickness": thickness})
    elif kind == "post":
        obstacles.append({"type": "circle", "radius": float(rng.uniform(0.01, 0.05)),
                          "center": [WALL_X, 2.0 + float(rng.uniform(-radius, radius))]})
    elif kind == "crate":
        a["pose"] = [1.0, 2.0, 0.0]
        obstacles.append({"type": "circle", "center": [1.0 + radius + 0.05, 2.0], "radius": 0.03,
                          "movable": True, "mass": float(10 ** rng.uniform(-1, 0.5)),
                          "ground_friction": 0.3})
        obstacles.append({"type": "wall", "start": [WALL_X, 0.0], "end": [WALL_X, 4.0],
                          "thickness": 0.01})
    else:
        robots.append(dict(a, name="b", pose=[5.0, 2.0 + float(rng.uniform(-radius, radius)),
                                             math.pi - heading]))
    data = {"name": "contact-trial", "world": {"size": [6.0, 4.0], "dt": float(rng.choice(DTS))},
            "obstacles": obstacles, "robots": robots}
    if drive is not None:  # drawn after the rest: the top-speed trials stay as they were
        share = float(rng.uniform(0.2, 0.9))
        for robot in robots:
            robot["controller"] = dict(robot["controller"], v=share * v)
            if drive != "diff":
                del robot["max_wheel_speed"], robot["track_width"]
                robot.update(drive=drive, max_speed=v)
    return data


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance from point p to segment a-b."""
    ab = b - a
    t = 0.0 if not ab.any() else float(np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0.0, 1.0))
    return float(np.hypot(*(a + t * ab - p)))


def run_trial(kind: str, rng: np.random.Generator, seconds: float = 4.0,
              every: bool = False, drive: str | None = None) -> tuple[bool, float]:
    """(crossed, deepest overlap [m]) of one trial (``every``: every substep in every tick; by
    default, only where a contact can start; ``drive``: see trial_scenario)."""
    data = trial_scenario(kind, rng, drive)
    if every:
        every_substep(data)
    sim = Simulation.from_dict(data)
    a = sim.robots["a"]
    b = sim.robots.get("b")
    post = data["obstacles"][0] if kind == "post" else None
    crossed, worst = False, 0.0
    last = a.pose[:2] if b is None else a.pose[:2] - b.pose[:2]
    for _ in range(round(seconds / sim.dt)):
        sim.step()
        worst = max(worst, deepest_overlap(sim.space))
        now = a.pose[:2] if b is None else a.pose[:2] - b.pose[:2]
        if post is not None:  # the centre's path this tick went through the post
            reach = _segment_distance(np.asarray(post["center"]), last, now)
            crossed |= reach < post["radius"] + a.radius - 0.01
        elif b is not None:  # the robots' relative path went through each other
            crossed |= _segment_distance(np.zeros(2), last, now) < a.radius + b.radius - 0.01
        last = now
    if kind == "wall":
        crossed |= a.pose[0] > WALL_X
    elif kind == "crate":
        crossed |= sim.world.obstacles[0].body.position.x > WALL_X or a.pose[0] > WALL_X
    return crossed, worst


def run_trials(trials: int, seed: int = 0, every: bool = False,
               slower: bool = False) -> Summary:
    """``trials`` randomized trials, the hazards in turn (``slower``: below top speed, the
    drives in turn too)."""
    rng = np.random.default_rng(seed)
    summary = Summary()
    for i in range(trials):
        kind = KINDS[i % len(KINDS)]
        drive = DRIVES[(i // len(KINDS)) % len(DRIVES)] if slower else None
        summary.add(kind, *run_trial(kind, rng, every=every, drive=drive))
    return summary


def main(trials: int = 1000, every: bool = False, slower: bool = False) -> Summary:
    summary = run_trials(trials, every=every, slower=slower)
    how = " (every substep)" if every else " (below top speed; diff, car, omni)" if slower else ""
    print(f"{summary.trials} trials{how}: "
          f"{summary.crossings} crossings, "
          f"{summary.deeper_than_1cm} deeper than 1 cm, deepest {summary.max_penetration * 1000:.1f} mm")
    for kind, (n, crossed, worst) in summary.by_kind.items():
        print(f"  {kind:<8} {n:>5} trials  {crossed} crossings  deepest {worst * 1000:.1f} mm")
    return summary


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1000)
