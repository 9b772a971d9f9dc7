"""Hand a robot back to its controller after a manual override, and see how the run ends.

The rule every goal-driving controller keeps (docs/navigation.md): after the override it makes
progress (arrives; a patrol keeps going round), or it ends with status "failed" and a message
that says why. Standing still with status "running" until the run ends is the defect.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import pymunk_bot as pb

# The shipped scenarios that drive with navigate, avoid, waypoints or policy.
SCENARIOS = {
    "navigate": ["warehouse", "doorway", "floor_plan", "maze", "moving_crossing", "parking",
                 "u_trap", "unreachable"],
    "avoid": ["cluttered_field", "corridor", "crossing", "head_on_swap", "pedestrian_corridor"],
    "waypoints": ["patrol", "omni_aisle", "ekf_office", "mcl_office", "slam_loop"],
    "policy": ["policy_clutter"],
}
PATROL_PROGRESS = 1.0  # [m] a looping robot must drive after the override to count as going on


@dataclass(frozen=True)
class Trial:
    scenario: str
    robot: str
    start: float  # [s] when the override begins
    length: float  # [s] how long it lasts
    v: float  # [m/s]
    omega: float  # [rad/s]


@dataclass(frozen=True)
class Outcome:
    trial: Trial
    status: str
    message: str
    ok: bool
    pose: tuple[float, float]


def draw_trials(count: int, seed: int) -> list[Trial]:
    """``count`` overrides of 0.5-3 s at any time of a run, spread over the controllers."""
    rng = np.random.default_rng(seed)
    kinds = sorted(SCENARIOS)
    trials = []
    for k in range(count):
        names = SCENARIOS[kinds[k % len(kinds)]]
        scenario = names[int(rng.integers(len(names)))]
        config = pb.Simulation.from_file(scenario).config
        robot = config.robots[int(rng.integers(len(config.robots)))]
        duration = float(config.world.duration)
        speed = float(getattr(robot, "max_wheel_speed", None) or getattr(robot, "max_speed", 1.0))
        trials.append(Trial(scenario, robot.name, float(rng.uniform(0.0, 0.8 * duration)),
                            float(rng.uniform(0.5, 3.0)), float(rng.uniform(-1.0, 1.0)) * speed,
                            float(rng.uniform(-1.5, 1.5))))
    return trials


def run_trial(trial: Trial) -> Outcome:
    """Run the override; then give the controller the scenario's duration plus a minute."""
    sim = pb.Simulation.from_file(trial.scenario)
    robot = sim.robots[trial.robot]
    sim.run(trial.start)
    robot.set_velocity(trial.v, trial.omega)
    sim.run(trial.length)
    robot.clear_command()
    handed_back = robot.distance
    limit = sim.time + float(sim.config.world.duration) + 60.0
    controller = robot.controller
    loop = bool(getattr(controller.config, "loop", False))
    while sim.time < limit and controller.status == "running" and not (
            loop and robot.distance - handed_back >= PATROL_PROGRESS):
        sim.run(0.5)
    status, message = controller.status, controller.message
    ok = (status == "arrived" or (status == "failed" and bool(message))
          or (loop and robot.distance - handed_back >= PATROL_PROGRESS))
    return Outcome(trial, status, message, ok, (float(robot.pose[0]), float(robot.pose[1])))


def describe(outcome: Outcome) -> str:
    t = outcome.trial
    return (f"{t.scenario}/{t.robot} override at {t.start:.2f} s for {t.length:.2f} s "
            f"(v {t.v:.2f}, omega {t.omega:.2f}): {outcome.status} {outcome.message!r} "
            f"at ({outcome.pose[0]:.2f}, {outcome.pose[1]:.2f})")


if __name__ == "__main__":  # the 200-trial figure: python tests/controllers/override_trials.py
    import sys
    import time

    count = int(sys.argv[1]) if len(sys.argv) > 1 else 200
    cpu = time.process_time()
    failures = []
    by_status: dict[str, int] = {}
    for trial in draw_trials(count, seed=2026):
        outcome = run_trial(trial)
        by_status[outcome.status] = by_status.get(outcome.status, 0) + 1
        if not outcome.ok:
            failures.append(describe(outcome))
            print("BAD", describe(outcome), flush=True)
    print(f"{count - len(failures)}/{count} trials arrived or ended with a failure status and "
          f"message; statuses {by_status}; {time.process_time() - cpu:.0f} s CPU")
    sys.exit(1 if failures else 0)
