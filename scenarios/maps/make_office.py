"""How scenarios/maps/office.pgm was made: `python scenarios/maps/make_office.py`.

An office floor (`pymunk-bot generate office --seed 7`, 16 x 10 m) rasterised at 5 cm, then made
to look like a SLAM map: the arena's walls stay occupied (two cells thick) and everything beyond
them is unknown, as a robot that mapped the floor from inside would leave it.
"""
from pathlib import Path

import numpy as np

from pymunk_bot.config import parse_scenario
from pymunk_bot.maps.generate import generate
from pymunk_bot.maps.grid import UNKNOWN, OccupancyGrid
from pymunk_bot.maps.rasterize import scenario_grid
from pymunk_bot.maps.ros import write_ros_map

SEED = 7
RESOLUTION = 0.05  # [m]
UNKNOWN_BORDER = 20  # [cells] of unknown around the walls


def main() -> None:
    grid = scenario_grid(parse_scenario(generate("office", SEED), "office"), RESOLUTION)
    data = np.pad(grid.data, UNKNOWN_BORDER, constant_values=UNKNOWN)
    pad = UNKNOWN_BORDER * RESOLUTION
    slam_like = OccupancyGrid(data, RESOLUTION, (grid.origin[0] - pad, grid.origin[1] - pad))
    out = Path(__file__).with_name("office.yaml")
    write_ros_map(slam_like, out)
    print(f"wrote {out} ({slam_like.cols} x {slam_like.rows} cells)")


if __name__ == "__main__":
    main()
