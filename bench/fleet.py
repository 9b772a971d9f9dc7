"""Swarms: 100 to 10,000 robots, with and without LiDAR, in CPU time.

    python -m bench.fleet [--quick]      (also in `pymunk-bot bench`)

The swarm: robots on a grid 2 m apart (one robot per 4 m^2, however many there are), each with a
``velocity`` controller holding a random arc (v 0.2-0.6 m/s, |omega| <= 0.8 rad/s), so they
wander, meet and push each other; one static box per 50 robots, placed between grid points.

Figures (issue 8):
1. 1000 robots, no sensors: CPU cost of one tick against the bare ``space.step`` of the same
   Space. After 0.5 s of running (every control body carries its velocity), the two are timed
   on that one Space in alternating blocks: ``sim.step()``, and ``space.step(dt / substeps)``
   ``substeps`` times per tick. Per robot-step the ratio is the same as per tick. Ours runs as
   a user runs it (the default takes one pymunk step in ticks where no contact can start; the
   report says how many of them did), the bare loop takes every substep.
2. 1000 robots with 32-beam LiDARs at 10 Hz: simulated seconds per CPU second (real time).
3. 100 robots with 360-beam LiDARs at 10 Hz: the same.
4. 10,000 robots in one Space (a 200 x 200 m arena), no sensors: building the scenario
   (validation included) and real time, with the cost per robot-step against the bare step.
"""
from __future__ import annotations

import argparse
import math
import statistics
import time
from typing import Any

import numpy as np

from pymunk_bot.config.types import MAX_ROBOTS
from pymunk_bot.engine.simulation import Simulation
from bench.simulation import every_substep

SPACING = 2.0  # [m] between grid neighbours
MARGIN = 1.0  # [m] from the arena walls to the outermost robots
ROBOTS_PER_BOX = 50
WARM_UP = 0.5  # [s] simulated before timing
OVERHEAD_TARGET = 1.5  # ours / bare space.step, at most
# (robots, beams) -> x real time, at least
TARGETS_REAL_TIME = {(1000, 32): 3.0, (100, 360): 10.0, (10_000, 0): 1.0}
BUILD_TARGET = 10.0  # [s] CPU to validate and build 10,000 robots, at most


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


def real_time(n_robots: int, beams: int, sim_seconds: float, repeats: int = 1,
              every: bool = False) -> dict:
    """Figures 2 to 4: simulated seconds per CPU second (median of repeats); without sensors,
    also the cost per robot-step against the bare step of the same Space."""
    target = TARGETS_REAL_TIME.get((n_robots, beams))
    cpu, bare = [], []
    for _ in range(repeats):
        started = time.process_time()
        sim = Simulation.from_dict(swarm_scenario(n_robots, beams, every=every),
                                   source="fleet-bench")
        build = time.process_time() - started
        sim.run(WARM_UP)
        ticks = round(sim_seconds / sim.dt)
        single = sim.single_substep_ticks
        cpu.append(_ticks(sim, ticks))
        single = sim.single_substep_ticks - single
        if not beams:
            bare.append(_bare_ticks(sim, ticks))
        scans = [r.lidar.latest for r in sim.robots.values() if r.sensor("lidar") is not None]
        if any(s is None or sim.time - s.time > 0.1 + 1e-9 for s in scans):
            raise RuntimeError("a LiDAR did not keep its 10 Hz")
    factor = ticks * sim.dt / statistics.median(cpu)
    result = {"robots": n_robots, "beams": beams, "substeps": sim.substeps, "build_cpu_s": build,
              "sim_seconds": ticks * sim.dt, "cpu_s": statistics.median(cpu),
              "single_step_share": single / ticks,
              "real_time_factor": factor, "target": target,
              "passed": None if target is None else factor >= target}
    if bare:
        steps = ticks * n_robots
        result.update(us_per_robot_step=1e6 * statistics.median(cpu) / steps,
                      bare_us_per_robot_step=1e6 * statistics.median(bare) / steps,
                      build_target=BUILD_TARGET, build_passed=build <= BUILD_TARGET)
    return result


def run(quick: bool = False) -> dict:
    """Every figure, measured (quick: shorter runs)."""
    seconds = 1.0 if quick else 10.0  # [s] simulated per figure
    return {"overhead_1000": overhead(1000, sim_seconds=2 * seconds, blocks=4 if quick else 10),
            "lidar32_1000": real_time(1000, 32, seconds),
            "lidar360_100": real_time(100, 360, seconds, repeats=1 if quick else 3),
            "swarm_10000": real_time(10_000, 0, 0.5 if quick else 2.0),
            "swarm_10000_every": real_time(10_000, 0, 0.5 if quick else 2.0, every=True)}


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
              f"{r['sim_seconds']:.1f} s simulated): {r['real_time_factor']:.2f}x real time "
              f"(target >= {r['target']:g}x): {_verdict(r['passed'])}")
    r = result["swarm_10000"]
    print(f"{r['robots']} robots, no sensors ({r['substeps']} substeps, {r['sim_seconds']:.1f} s "
          f"simulated): built in {r['build_cpu_s']:.1f} s CPU (target <= {r['build_target']:g} s): "
          f"{_verdict(r['build_passed'])}; {r['real_time_factor']:.2f}x real time (target >= "
          f"{r['target']:g}x): {_verdict(r['passed'])}; ours {r['us_per_robot_step']:.2f} us per "
          f"robot-step, bare space.step {r['bare_us_per_robot_step']:.2f} us; "
          f"{100 * r['single_step_share']:.0f} % of ticks in one pymunk step")
    r = result["swarm_10000_every"]
    print(f"  the same with every substep in every tick: {r['real_time_factor']:.2f}x real time")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    report(run(parser.parse_args(argv).quick))
    return 0


if __name__ == "__main__":
    main()
