"""How fast a headless run is: steps per second and real-time factor, beside bare pymunk.

    python -m bench.simulation      (or: pymunk-bot bench)
"""
from __future__ import annotations

import math
import statistics
import time
from typing import Any

import numpy as np

from pymunk_bot.config import parse_scenario
from pymunk_bot.config.substeps import required_substeps
from pymunk_bot.engine.simulation import Simulation

# One robot, no sensors: at most this many times the CPU of a loop on bare pymunk doing the same
# physics (issue 32). A ratio measured in one run, so the verdict holds on any machine.
TARGET_RATIO = 2.5


def every_substep(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with its substep count named, so that every tick takes every substep: the
    reference the default (substeps only where a contact can start) is measured against."""
    data["world"]["substeps"] = required_substeps(parse_scenario(data, data["name"]))
    return data


def benchmark_scenario(n_obstacles: int = 20, n_robots: int = 1, lidar: bool = False,
                       seed: int = 0) -> dict[str, Any]:
    """A 20x20 m arena with random boxes and robots circling (so they meet obstacles)."""
    rng = np.random.default_rng(seed)
    obstacles: list[dict[str, Any]] = []
    robots: list[dict[str, Any]] = []
    while len(obstacles) < n_obstacles:
        x, y = rng.uniform(1.0, 19.0, size=2)
        obstacles.append({"type": "box", "center": [float(x), float(y)],
                          "size": [float(s) for s in rng.uniform(0.3, 1.0, size=2)],
                          "angle": float(rng.uniform(0, np.pi))})
    for i in range(n_robots):
        robot = {"name": f"r{i}", "pose": [1.0 + 0.5 * (i % 36), 0.5 + 0.5 * (i // 36), 0.0],
                 "controller": {"type": "wheels", "left": 0.9, "right": 1.0}}
        if lidar:
            robot["lidar"] = {"beams": 360, "max_range": 10.0}
        robots.append(robot)
    for obstacle in list(obstacles):  # keep the start poses free
        cx, cy = obstacle["center"]
        if any(abs(cx - r["pose"][0]) < 1.0 and abs(cy - r["pose"][1]) < 1.0 for r in robots):
            obstacles.remove(obstacle)
    return {"name": "bench", "world": {"size": [20.0, 20.0]}, "obstacles": obstacles,
            "robots": robots}


def time_run(scenario: dict, sim_seconds: float) -> float:
    """CPU seconds for a headless run of ``sim_seconds``."""
    sim = Simulation(parse_scenario(scenario, "bench"))
    started = time.process_time()
    sim.run(sim_seconds)
    return time.process_time() - started


def time_bare_pymunk(scenario: dict, sim_seconds: float) -> float:
    """CPU seconds for what a user would write by hand with bare pymunk: the same Space (the
    same obstacles and bodies), each robot's body given the velocity of its command every tick
    (wheels or a body velocity, along its heading), then one ``space.step(dt)``."""
    sim = Simulation(parse_scenario(scenario, "bench"))
    space, dt = sim.space, sim.dt
    commands = []
    for config, robot in zip(scenario["robots"], sim.robots.values()):
        controller = config["controller"]
        if controller["type"] == "wheels":
            track = robot.config.track_width
            v = 0.5 * (controller["left"] + controller["right"])
            omega = (controller["right"] - controller["left"]) / track
        else:
            v, omega = controller["v"], controller["omega"]
        commands.append((robot.body, v, omega))
    started = time.process_time()
    for _ in range(round(sim_seconds / dt)):
        for body, v, omega in commands:
            heading = body.angle
            body.velocity = (v * math.cos(heading), v * math.sin(heading))
            body.angular_velocity = omega
        space.step(dt)
    return time.process_time() - started


def scraping_scenario() -> dict:
    """One robot circling among IR-SIM's benchmark obstacles, where it scrapes along a box."""
    from bench import irsim

    data = irsim.scenario()
    robot = dict(data["robots"][0])
    robot.pop("lidar")
    v, omega = irsim.COMMAND
    robot["controller"] = {"type": "velocity", "v": v, "omega": omega}
    data["robots"] = [robot]
    data["name"] = "bench_scraping"
    return data


def measure(repeats: int = 5, sim_seconds: float = 60.0) -> list[dict]:
    cases = [("1 robot, 20 obstacles", benchmark_scenario()),
             ("1 robot, IR-SIM's obstacles", scraping_scenario()),
             ("1 robot + 360-beam LiDAR @10 Hz", benchmark_scenario(lidar=True)),
             ("10 robots, 20 obstacles", benchmark_scenario(n_robots=10)),
             ("100 robots, 20 obstacles", benchmark_scenario(n_robots=100))]
    rows = []
    for label, scenario in cases:
        ours, bare = [], []
        # Untimed first, as long as a timed run: a process pays once for loading numba's
        # compiled functions from their cache (2-3 ms each), which two quick repeats' median
        # would count at half weight. A shorter warm-up left some unloaded: a robot's first
        # graded substeps come after 1 s (measured: the first 60 s run 24.5 ms, the next 17.5).
        time_run(scenario, sim_seconds)
        for _ in range(repeats):  # interleaved so both see the same machine load
            ours.append(time_run(scenario, sim_seconds))
            bare.append(time_bare_pymunk(scenario, sim_seconds))
        wall, physics = statistics.median(ours), statistics.median(bare)
        steps = round(sim_seconds / (1 / 60))
        rows.append({"case": label, "sim_s": sim_seconds, "wall_s": wall,
                     "steps_per_s": steps / wall, "real_time_factor": sim_seconds / wall,
                     "bare_pymunk_s": physics, "overhead": wall / physics})
    return rows


def main(repeats: int = 5) -> list[dict]:
    """Print the table; returns its rows."""
    print(f"{'case':<34} {'CPU [s]':>9} {'steps/s':>9} {'x real':>8} {'bare [s]':>11} "
          f"{'ours/bare':>11}")
    rows = measure(repeats)
    for r in rows:
        print(f"{r['case']:<34} {r['wall_s']:>9.4f} {r['steps_per_s']:>9.0f} "
              f"{r['real_time_factor']:>8.0f} {r['bare_pymunk_s']:>11.4f} {r['overhead']:>11.1f}")
    return rows


if __name__ == "__main__":
    main()
