"""Speed benchmarks (`pymunk-bot bench`): ratios measured in one run, never timed unit tests."""
from __future__ import annotations


def run_all(quick: bool = False) -> None:
    from . import lidar, movers, simulation

    print("Simulation: 60 s of simulated time, median of repeats")
    simulation.main(repeats=2 if quick else 5)
    print()
    print("LiDAR: microseconds per ray, 360-beam scans")
    lidar.main()
    print()
    print("Pedestrians and scripted obstacles: microseconds per step (one LiDAR robot)")
    movers.main(repeats=1 if quick else 3)
