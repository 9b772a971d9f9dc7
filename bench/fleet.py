"""Swarms: 100 to 10,000 robots, with and without LiDAR, in CPU time.

    python -m bench.fleet [--quick]      (also in `pymunk-bot bench`)

The swarm: robots on a grid 2 m apart (one robot per 4 m^2, however many there are), each with a
``velocity`` controller holding a random arc (v 0.2-0.6 m/s, |omega| <= 0.8 rad/s), so they
wander, meet and push each other; one static box per 50 robots, placed between grid points.

Figures (issue 8), each against a reference measured in the same run, on the same Space, so the
verdicts hold on any machine (issue 32); x real time is printed beside them:
1. 1000 robots, no sensors: CPU cost of one tick against the bare ``space.step`` of the same
   Space. After 0.5 s of running (every control body carries its velocity), the two are timed
   on that one Space in alternating blocks: ``sim.step()``, and ``space.step(dt / substeps)``
   ``substeps`` times per tick. Per robot-step the ratio is the same as per tick. Ours runs as
   a user runs it (the default takes one pymunk step in ticks where no contact can start; the
   report says how many of them did), the bare loop takes every substep.
2. 1000 robots with 32-beam LiDARs at 10 Hz, and 3. 100 robots with 360-beam LiDARs: our speed
   against the loop a user would write by hand on the same Space (every substep stepped, every
   robot's beams cast with one ``segment_query_first`` each, 10 times a simulated second).
4. 10,000 robots in one Space (a 200 x 200 m arena), no sensors, timed from t = 1 s (robots
   have met by then): our speed against the bare step of the same Space; building the scenario
   (validation included) against building the same bodies, shapes and joints by hand.

Where a figure's target was given in x real time on another machine, its ratio target is that
demand carried over through 0f820e9's engine, measured against the same references on this
one (see TARGET_RATIOS).
"""
from __future__ import annotations

import argparse
import gc
import math
import statistics
import time
from typing import Any

import numpy as np
import pymunk

from pymunk_bot.config.types import MAX_ROBOTS
from pymunk_bot.engine.simulation import Simulation
from pymunk_bot.sensors.raycast import reference_cast
from bench.simulation import every_substep

SPACING = 2.0  # [m] between grid neighbours
MARGIN = 1.0  # [m] from the arena walls to the outermost robots
ROBOTS_PER_BOX = 50
WARM_UP = 0.5  # [s] simulated before timing
SWARM_FROM = 1.0  # [s] the 10,000-robot figure is timed from then on (issue 32)
OVERHEAD_TARGET = 1.5  # ours / bare space.step, at most
# (robots, beams) -> our speed / the reference's, at least. Issue 32 asked for 3x real time with
# 1000 32-beam LiDARs (0f820e9 gave 2.05x on the machine) and 1x real time for 10,000
# robots from t = 1 s (0f820e9: 0.40x); 0f820e9 ran at 4.4-4.7x its hand-written loop and
# 2.5-3.3x the bare step here (2026-12-05, /work/s38/fleet_ab.py), hence 4.5 * 3 / 2.05 and
# 2.9 * 1 / 0.40. The 360-beam figure (issue 8: 10x real time) takes the LiDAR target, 5x
# what segment_query_first gives.
TARGET_RATIOS = {(1000, 32): 6.6, (100, 360): 5.0, (10_000, 0): 7.3}
# Building 10,000 robots: issue 32 asked <= 10 s where 0f820e9 took 9.3 s: at most 10 / 9.3 of
# 0f820e9's build, which took 4.46-4.62x the hand-written build here (build_cost, 2026-12-05).
BUILD_SLOWDOWN = 10.0 / 9.3
BUILD_RATIO_0F820E9 = 4.5
LIDAR_RATE = 10.0  # [Hz]


def swarm_scenario(n_robots: int, beams: int = 0, max_range: float = 8.0, seed: int = 0,
                   every: bool = False) -> dict:
    """``n_robots`` wandering on a grid in an arena scaled to keep the density; ``beams`` > 0
    gives each a full-circle LiDAR at 10 Hz with ``max_range`` [m]; ``every``: every substep in
    every tick."""
    if not 1 <= n_robots <= MAX_ROBOTS:
        raise ValueError(f"n_robots must be in [1, {MAX_ROBOTS}] (got {n_robots})")
    rng = np.random.default_rng(seed)
    columns = math.ceil(math.sqrt(n_robots))
    rows = math.ceil(n_robots / columns)
    width, height = 2 * MARGIN + SPACING * (columns - 1), 2 * MARGIN + SPACING * (rows - 1)
    robots: list[dict[str, Any]] = []
    for i in range(n_robots):
        x, y = MARGIN + SPACING * (i % columns), MARGIN + SPACING * (i // columns)
        robot: dict[str, Any] = {
            "name": f"r{i}", "pose": [x, y, float(rng.uniform(-math.pi, math.pi))],
            "controller": {"type": "velocity", "v": float(rng.uniform(0.2, 0.6)),
                           "omega": float(rng.uniform(-0.8, 0.8))}}
        if beams:
            robot["lidar"] = {"beams": beams, "max_range": max_range, "rate": 10.0}
        robots.append(robot)
    boxes = []
    cells = [(c, r) for c in range(columns - 1) for r in range(rows - 1)]
    count = min(len(cells), max(1, n_robots // ROBOTS_PER_BOX)) if cells else 0
    for k in rng.choice(len(cells), size=count, replace=False) if count else []:
        c, r = cells[int(k)]  # the middle of a grid cell: 1.4 m from its four robots
        boxes.append({"type": "box", "center": [MARGIN + SPACING * (c + 0.5),
                                                MARGIN + SPACING * (r + 0.5)],
                      "size": [0.6, 0.6], "angle": float(rng.uniform(0, math.pi / 2))})
    data = {"name": f"swarm_{n_robots}", "world": {"size": [width, height]},
            "obstacles": boxes, "robots": robots}
    return every_substep(data) if every else data


def _ticks(sim: Simulation, ticks: int) -> float:
    started = time.process_time()
    for _ in range(ticks):
        sim.step()
    return time.process_time() - started


def _bare_ticks(sim: Simulation, ticks: int) -> float:
    # Robots stepping apart (physics/apart.py) come back first: the bare loop steps the whole
    # world in one Space, every substep; the next tick of ours decides anew.
    sim.world.gather()
    space, substeps = sim.world.contact_space, sim.substeps
    h = sim.dt / substeps
    started = time.process_time()
    for _ in range(ticks * substeps):
        space.step(h)
    return time.process_time() - started


def overhead(n_robots: int = 1000, sim_seconds: float = 5.0, blocks: int = 5) -> dict:
    """Figure 1: our tick against the bare space.step of the same Space (no sensors)."""
    started = time.process_time()
    sim = Simulation.from_dict(swarm_scenario(n_robots), source="fleet-bench")
    build = time.process_time() - started
    sim.run(WARM_UP)
    ticks = max(1, round(sim_seconds / sim.dt / blocks))
    ours, bare = [], []
    single = sim.single_substep_ticks
    for _ in range(blocks):  # alternating, so load changes hit both alike
        ours.append(_ticks(sim, ticks))
        bare.append(_bare_ticks(sim, ticks))
    single = sim.single_substep_ticks - single  # ours in one step (bare: every substep)
    o, b = sum(ours), sum(bare)
    steps = ticks * blocks * n_robots
    moving = sum(r.distance > 0.1 for r in sim.robots.values())
    return {"robots": n_robots, "substeps": sim.substeps, "build_cpu_s": build,
            "sim_seconds": ticks * blocks * sim.dt, "ours_cpu_s": o, "bare_cpu_s": b,
            "us_per_robot_step": 1e6 * o / steps, "bare_us_per_robot_step": 1e6 * b / steps,
            "ratio": o / b, "target": OVERHEAD_TARGET, "passed": o / b <= OVERHEAD_TARGET,
            "real_time_factor": ticks * blocks * sim.dt / o, "robots_moving": moving,
            "single_step_share": single / (ticks * blocks)}


def _hand_written_ticks(sim: Simulation, ticks: int) -> float:
    """CPU time [s] of the loop a user would write for ``ticks`` ticks on the same Space: every
    substep stepped, and at LIDAR_RATE every robot's LiDAR cast beam by beam with one
    ``segment_query_first`` each (from its body, at its heading, through its shape's filter)."""
    sim.world.gather()
    space, substeps = sim.world.contact_space, sim.substeps
    h = sim.dt / substeps
    lidars = [(r.body, r.lidar.angles, r.lidar.config.max_range, r.shape.filter)
              for r in sim.robots.values() if r.sensor("lidar") is not None]
    every = max(1, round(1.0 / (LIDAR_RATE * sim.dt)))
    started = time.process_time()
    for tick in range(ticks):
        for _ in range(substeps):
            space.step(h)
        if tick % every == 0:
            for body, angles, max_range, shape_filter in lidars:
                reference_cast(space, tuple(body.position), angles + body.angle, max_range,
                               shape_filter)
    return time.process_time() - started


def hand_built(scenario: dict) -> float:
    """CPU time [s] to build ``scenario``'s robots and boxes by hand in bare pymunk: per robot
    a dynamic disc, its kinematic control body and the pivot and gear joints between them (what
    a scenario's robot is made of), without validation."""
    started = time.process_time()
    space = pymunk.Space()
    for box in scenario["obstacles"]:
        w, h = box["size"]
        shape = pymunk.Poly.create_box(space.static_body, (w, h))
        shape.friction = 0.5
        space.add(shape)
    for robot in scenario["robots"]:
        x, y, theta = robot["pose"]
        body = pymunk.Body(5.0, pymunk.moment_for_circle(5.0, 0.0, 0.2))
        body.position, body.angle = (x, y), theta
        disc = pymunk.Circle(body, 0.2)
        disc.friction = 0.5
        control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        control.position, control.angle = (x, y), theta
        pivot = pymunk.PivotJoint(control, body, (0.0, 0.0), (0.0, 0.0))
        gear = pymunk.GearJoint(control, body, 0.0, 1.0)
        for joint, force in ((pivot, 31.7), (gear, 4.75)):
            joint.max_bias, joint.max_force = 0.0, force
        space.add(body, disc, control, pivot, gear)
    return time.process_time() - started


def real_time(n_robots: int, beams: int, sim_seconds: float, repeats: int = 1,
              every: bool = False, warm_up: float = WARM_UP) -> dict:
    """Figures 2 to 4: our speed against the hand-written loop on the same Space (median of
    repeats), and simulated seconds per CPU second (real time); without sensors, also the cost
    per robot-step against the bare step."""
    target = TARGET_RATIOS.get((n_robots, beams))
    cpu, reference = [], []
    for _ in range(repeats):
        sim = Simulation.from_dict(swarm_scenario(n_robots, beams, every=every),
                                   source="fleet-bench")
        sim.run(warm_up)
        ticks = round(sim_seconds / sim.dt)
        single = sim.single_substep_ticks
        cpu.append(_ticks(sim, ticks))
        single = sim.single_substep_ticks - single
        scans = [r.lidar.latest_time for r in sim.robots.values()
                 if r.sensor("lidar") is not None]
        if any(t is None or sim.time - t > 0.1 + 1e-9 for t in scans):
            raise RuntimeError("a LiDAR did not keep its 10 Hz")
        reference.append(_hand_written_ticks(sim, ticks))
    ours, theirs = statistics.median(cpu), statistics.median(reference)
    result = {"robots": n_robots, "beams": beams, "substeps": sim.substeps,
              "sim_seconds": ticks * sim.dt, "from_s": warm_up,
              "cpu_s": ours, "reference_cpu_s": theirs, "speed_ratio": theirs / ours,
              "single_step_share": single / ticks, "real_time_factor": ticks * sim.dt / ours,
              "reference_real_time_factor": ticks * sim.dt / theirs, "target": target,
              "passed": None if target is None else theirs / ours >= target}
    if not beams:
        steps = ticks * n_robots
        result.update(us_per_robot_step=1e6 * ours / steps,
                      bare_us_per_robot_step=1e6 * theirs / steps)
    return result


def build_cost(n_robots: int, repeats: int = 3) -> dict:
    """Building ``n_robots`` (validation included) against building them by hand, alternately,
    each from a collected heap (the collector's work grows with what is alive); medians."""
    scenario = swarm_scenario(n_robots)
    ours, hand = [], []
    for _ in range(repeats):
        gc.collect()
        hand.append(hand_built(scenario))
        gc.collect()
        started = time.process_time()
        Simulation.from_dict(scenario, source="fleet-bench")
        ours.append(time.process_time() - started)
    build, by_hand = statistics.median(ours), statistics.median(hand)
    target = BUILD_SLOWDOWN * BUILD_RATIO_0F820E9
    return {"robots": n_robots, "build_cpu_s": build, "hand_build_cpu_s": by_hand,
            "build_ratio": build / by_hand, "build_target": target,
            "build_passed": build / by_hand <= target}


def run(quick: bool = False) -> dict:
    """Every figure, measured (quick: shorter runs)."""
    seconds = 1.0 if quick else 10.0  # [s] simulated per figure
    return {"overhead_1000": overhead(1000, sim_seconds=2 * seconds, blocks=4 if quick else 10),
            "lidar32_1000": real_time(1000, 32, seconds),
            "lidar360_100": real_time(100, 360, seconds, repeats=1 if quick else 3),
            "build_10000": build_cost(10_000, repeats=1 if quick else 3),
            "swarm_10000": real_time(10_000, 0, 0.5 if quick else 2.0, warm_up=SWARM_FROM),
            "swarm_10000_every": real_time(10_000, 0, 0.5 if quick else 2.0, every=True,
                                           warm_up=SWARM_FROM)}


def _verdict(passed: bool | None) -> str:
    return "" if passed is None else ("PASS" if passed else "MISS")


def report(result: dict) -> None:
    o = result["overhead_1000"]
    print(f"{o['robots']} robots, no sensors ({o['substeps']} substeps, {o['sim_seconds']:.1f} s "
          f"simulated, built in {o['build_cpu_s']:.1f} s CPU, {o['robots_moving']} moved)")
    print(f"  ours {o['us_per_robot_step']:6.2f} us per robot-step ({o['real_time_factor']:.2f}x "
          f"real time), bare space.step {o['bare_us_per_robot_step']:6.2f} us: "
          f"{o['ratio']:.2f}x (target <= {o['target']:g}x): {_verdict(o['passed'])}; "
          f"{100 * o['single_step_share']:.0f} % of our ticks in one pymunk step")
    for key in ("lidar32_1000", "lidar360_100"):
        r = result[key]
        print(f"{r['robots']} robots, {r['beams']}-beam LiDAR at 10 Hz ({r['substeps']} substeps, "
              f"{r['sim_seconds']:.1f} s simulated): {r['speed_ratio']:.2f}x the speed of the "
              f"hand-written loop (target >= {r['target']:g}x): {_verdict(r['passed'])}; "
              f"{r['real_time_factor']:.2f}x real time, the loop "
              f"{r['reference_real_time_factor']:.2f}x")
    b = result["build_10000"]
    print(f"{b['robots']} robots built in {b['build_cpu_s']:.1f} s CPU, {b['build_ratio']:.2f}x "
          f"building them by hand ({b['hand_build_cpu_s']:.2f} s; target <= "
          f"{b['build_target']:.2f}x): {_verdict(b['build_passed'])}")
    r = result["swarm_10000"]
    print(f"{r['robots']} robots, no sensors ({r['substeps']} substeps, {r['sim_seconds']:.1f} s "
          f"simulated from t = {r['from_s']:g} s): {r['speed_ratio']:.2f}x the speed of the bare step (target >= {r['target']:g}x): "
          f"{_verdict(r['passed'])}; {r['real_time_factor']:.2f}x real time; ours "
          f"{r['us_per_robot_step']:.2f} us per robot-step, bare space.step "
          f"{r['bare_us_per_robot_step']:.2f} us; {100 * r['single_step_share']:.0f} % of ticks "
          f"in one pymunk step")
    r = result["swarm_10000_every"]
    print(f"  the same with every substep in every tick: {r['real_time_factor']:.2f}x real time, "
          f"{r['speed_ratio']:.2f}x the bare step")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    report(run(parser.parse_args(argv).quick))
    return 0


if __name__ == "__main__":
    main()
