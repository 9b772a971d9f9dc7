"""Every drive from Python: a car drives its tightest circle, an omni robot slides sideways,
and both meet a pedestrian and a scripted box in one arena.

Run it:  python examples/drives.py
"""
from __future__ import annotations

import math

import pymunk_bot as pb

SCENARIO = {
    "name": "drives_demo",
    "world": {"size": [10.0, 6.0]},
    "obstacles": [
        {"type": "box", "center": [8.0, 1.0], "size": [0.4, 0.4],
         "motion": {"path": [[8.0, 1.0], [8.0, 5.0]], "speed": 0.5, "mode": "pingpong"}},
        {"type": "pedestrian", "center": [1.0, 5.0], "goals": [[9.0, 5.0], [1.0, 5.0]]},
    ],
    "robots": [
        {"name": "car", "drive": "ackermann", "pose": [3.0, 2.0, 0.0], "wheelbase": 0.33,
         "max_steer": 0.5, "footprint": {"type": "box", "size": [0.5, 0.3], "center": [0.165, 0.0]}},
        {"name": "holo", "drive": "omni", "pose": [6.0, 1.0, math.pi / 2], "wheels": "mecanum"},
    ],
}


def main() -> None:
    sim = pb.Simulation.from_dict(SCENARIO, seed=1)
    car, holo = sim.robots["car"], sim.robots["holo"]
    car.set_velocity(0.8, 10.0)  # far beyond full lock: clipped to the tightest circle
    holo.set_velocity(0.0, 0.0, vy=0.4)  # facing +y, sliding to its left (-x)
    sim.run(6.0)
    print(f"car: tightest circle radius {car.drive.min_turn_radius:.3f} m, "
          f"steering {car.drive.steering_angle:.2f} rad, pose {car.pose.round(2)}")
    print(f"holo: pose {holo.pose.round(2)} (slid {6.0 - holo.pose[0]:.2f} m sideways), "
          f"odometry {holo.odometry.pose.round(2)}")
    walker = sim.world.obstacles[1].body.position
    box = sim.world.obstacles[0].body.position
    print(f"pedestrian at ({walker.x:.2f}, {walker.y:.2f}), box at ({box.x:.2f}, {box.y:.2f})")


if __name__ == "__main__":
    main()
