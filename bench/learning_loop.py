"""A learning loop on pymunk-bot against the same loop written by hand on bare pymunk.

    python -m bench.learning_loop [--quick]      (also in `pymunk-bot bench`)

The loop is what an RL agent or a 10 Hz controller does: set a command, advance 0.1 s, read the
180-beam scan and the odometry. The world: 20x20 m, 20 random boxes, one robot (radius 0.2 m,
5 kg), a full-circle 180-beam LiDAR with 10 m range and no noise. Commands are seeded random
draws of (v, omega) within the robot's limits, one per 0.1 s as an RL agent sends them (so the
motors ramp most of the time), the same sequence for both loops. pymunk-bot runs twice: as a user runs it (the default:
substeps only where a contact can start) and, for reference, with every substep in every tick
(``world.substeps`` named).

- pymunk-bot: ``robot.set_velocity(v, omega)``, ``sim.run(0.1)`` (the scan is taken at 10 Hz
  by the simulation itself), ``robot.lidar.latest.ranges``, ``robot.odometry.pose``.
- bare pymunk, as a user would write it: a Space from the same ``physics.new_space`` settings
  with the same boxes and arena walls, the robot's disc pulled by a kinematic control body
  through a pivot and a gear joint with exactly our force limits (read off our joints), one
  ``space.step(1/60)`` per tick; the control body's velocity set once per 0.1 s; then 180
  ``segment_query_first`` calls with the robot's shape filter, and odometry as the integrated
  commanded velocity (cheaper than wheel encoders).

Both loops are timed in CPU time (``time.process_time``), alternating, and the figure is the
ratio of the medians (bare / ours: above 1, ours is faster).
"""
from __future__ import annotations

import argparse
import math
import statistics
import time
from typing import Any

import numpy as np
import pymunk

from pymunk_bot.physics import settings as physics
from pymunk_bot.engine.simulation import Simulation
from pymunk_bot.config.substeps import ARENA_WALL_THICKNESS
from bench.simulation import benchmark_scenario, every_substep

TARGET = 2.5  # issue 8: >= 2.5x the bare pymunk loop
PERIOD = 0.1  # [s] one loop iteration
BEAMS = 180
MAX_RANGE = 10.0  # [m]


def scenario(every: bool = False) -> dict:
    """20x20 m, 20 boxes, one robot with a 180-beam LiDAR and no controller (``every``: every
    substep in every tick)."""
    data = benchmark_scenario(n_obstacles=20, n_robots=1, seed=0)
    robot = data["robots"][0]
    robot.pop("controller")
    robot["lidar"] = {"beams": BEAMS, "max_range": MAX_RANGE, "rate": 1.0 / PERIOD}
    data["name"] = "learning_loop"
    return every_substep(data) if every else data


def commands(iterations: int, seed: int = 0) -> list[tuple[float, float]]:
    """Random draws of (v [m/s], omega [rad/s]) within the robot's limits, one per period."""
    rng = np.random.default_rng(seed)
    return [(float(rng.uniform(-0.3, 0.8)), float(rng.uniform(-1.5, 1.5)))
            for _ in range(iterations)]


def ours(steps: list[tuple[float, float]], every: bool = False) -> tuple[float, np.ndarray]:
    """CPU seconds of the pymunk-bot loop, and the final pose (``every``: every substep)."""
    sim = Simulation.from_dict(scenario(every), source="learning-loop")
    robot = sim.robots["r0"]
    lidar, odometry = robot.lidar, robot.odometry
    started = time.process_time()
    for v, omega in steps:
        robot.set_velocity(v, omega)
        sim.run(PERIOD)
        ranges = lidar.latest.ranges
        pose = odometry.pose
    cpu = time.process_time() - started
    assert len(ranges) == BEAMS and len(pose) == 3
    return cpu, robot.pose


def _box(body: pymunk.Body, center: Any, size: Any, angle: float) -> pymunk.Poly:
    w, h = size
    c, s = math.cos(angle), math.sin(angle)
    corners = [(-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2)]
    return pymunk.Poly(body, corners, pymunk.Transform(a=c, b=s, c=-s, d=c, tx=center[0],
                                                       ty=center[1]))


class BareLoop:
    """The same robot and world built by hand on pymunk (see the module docstring)."""

    def __init__(self, data: dict, force: float, torque: float, substeps: int,
                 dt: float) -> None:
        self.space = space = physics.new_space(pushable=False)
        width, height = data["world"]["size"]
        t = ARENA_WALL_THICKNESS
        static = space.static_body
        for center, size in (((width / 2, -t / 2), (width + 2 * t, t)),
                             ((width / 2, height + t / 2), (width + 2 * t, t)),
                             ((-t / 2, height / 2), (t, height)),
                             ((width + t / 2, height / 2), (t, height))):
            space.add(_box(static, center, size, 0.0))
        for o in data["obstacles"]:
            space.add(_box(static, o["center"], o["size"], o.get("angle", 0.0)))
        rc = data["robots"][0]
        x, y, theta = rc["pose"]
        radius, mass = 0.2, 5.0  # the schema's defaults
        self.body = body = pymunk.Body(mass, pymunk.moment_for_circle(mass, 0, radius))
        body.position, body.angle = (x, y), theta
        shape = pymunk.Circle(body, radius)
        shape.friction = 0.5
        shape.filter = pymunk.ShapeFilter(group=1)
        self.control = control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        control.position, control.angle = (x, y), theta
        pivot = pymunk.PivotJoint(control, body, (0, 0), (0, 0))
        gear = pymunk.GearJoint(control, body, 0.0, 1.0)
        pivot.max_bias = gear.max_bias = 0.0
        pivot.max_force, gear.max_force = force, torque
        space.add(body, shape, control, pivot, gear)
        self.filter = shape.filter
        self.h = dt / substeps
        self.steps_per_period = round(PERIOD / dt) * substeps
        self.odometry = np.array([x, y, theta], dtype=float)
        self.angles = (np.arange(BEAMS) - BEAMS // 2) * (2.0 * math.pi / BEAMS)

    def run(self, steps: list[tuple[float, float]]) -> float:
        """CPU seconds of the loop."""
        space, body, control, h = self.space, self.body, self.control, self.h
        angles, shape_filter, odometry = self.angles.tolist(), self.filter, self.odometry
        ranges = [MAX_RANGE] * BEAMS
        started = time.process_time()
        for v, omega in steps:
            heading = body.angle
            control.velocity = (v * math.cos(heading), v * math.sin(heading))
            control.angular_velocity = omega
            for _ in range(self.steps_per_period):
                space.step(h)
            x, y = body.position
            theta = body.angle
            for i, a in enumerate(angles):
                end = (x + MAX_RANGE * math.cos(theta + a), y + MAX_RANGE * math.sin(theta + a))
                hit = space.segment_query_first((x, y), end, 0.0, shape_filter)
                ranges[i] = MAX_RANGE if hit is None else hit.alpha * MAX_RANGE
            odometry[2] += omega * PERIOD  # integrated command: the cheapest odometry there is
            odometry[0] += v * PERIOD * math.cos(odometry[2])
            odometry[1] += v * PERIOD * math.sin(odometry[2])
        return time.process_time() - started


def bare(steps: list[tuple[float, float]]) -> tuple[float, np.ndarray]:
    """CPU seconds of the bare pymunk loop, and the final pose."""
    data = scenario()
    sim = Simulation.from_dict(data, source="learning-loop")  # for its joint limits
    joints = sim.robots["r0"].body.constraints
    force = next(j.max_force for j in joints if isinstance(j, pymunk.PivotJoint))  # [N]
    torque = next(j.max_force for j in joints if isinstance(j, pymunk.GearJoint))  # [N m]
    loop = BareLoop(data, force, torque, 1, sim.dt)  # one space.step per tick, as users write
    cpu = loop.run(steps)
    return cpu, np.array([*loop.body.position, loop.body.angle])


def run(quick: bool = False) -> dict:
    """Alternating repeats of both loops: the median of each pair's ratio (the VM's speed
    drifts less within a pair than across the run), and each loop's median time."""
    iterations, repeats = (100, 3) if quick else (600, 9)
    steps = commands(iterations)
    ours_cpu, every_cpu, bare_cpu = [], [], []
    for _ in range(repeats):
        cpu, our_pose = ours(steps)
        ours_cpu.append(cpu)
        every_cpu.append(ours(steps, every=True)[0])
        cpu, bare_pose = bare(steps)
        bare_cpu.append(cpu)
    o, e, b = (statistics.median(t) for t in (ours_cpu, every_cpu, bare_cpu))
    ratio = statistics.median(bare / ours for ours, bare in zip(ours_cpu, bare_cpu))
    every_ratio = statistics.median(bare / ours for ours, bare in zip(every_cpu, bare_cpu))
    return {"iterations": iterations, "sim_seconds": iterations * PERIOD, "repeats": repeats,
            "ours_cpu_s": o, "bare_cpu_s": b, "ratio": ratio, "target": TARGET,
            "passed": ratio >= TARGET, "ours_loops_per_s": iterations / o,
            "every_substep_loops_per_s": iterations / e, "every_substep_ratio": every_ratio,
            "bare_loops_per_s": iterations / b,
            "final_pose_gap_m": float(np.hypot(*(our_pose[:2] - bare_pose[:2])))}


def report(result: dict) -> None:
    print(f"1 robot, {BEAMS}-beam LiDAR: set a command, advance {PERIOD} s, read scan + odometry "
          f"({result['iterations']} loops, {result['repeats']} alternating pairs, the median "
          "pair's ratio, CPU time)")
    print(f"  pymunk-bot {result['ours_loops_per_s']:7.0f} loops/s (every substep "
          f"{result['every_substep_loops_per_s']:.0f}, {result['every_substep_ratio']:.2f}x)   bare pymunk + "
          f"segment_query_first {result['bare_loops_per_s']:7.0f} loops/s")
    print(f"  ratio {result['ratio']:.2f}x (target >= {TARGET:g}x): "
          f"{'PASS' if result['passed'] else 'MISS'}   (final poses {result['final_pose_gap_m']:.2f} m "
          "apart: the bare loop drives straight lines within each 0.1 s)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    report(run(parser.parse_args(argv).quick))
    return 0


if __name__ == "__main__":
    main()
