"""Test harness: a Simulation driven along a route, its localizer fed exactly as the core feeds
it (LocalizerInputs after every sim.step()), truth and estimate recorded every step.

The loop itself lives in ``pymunk_bot.localization.trial`` so the bench measures the same way.
"""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot import Simulation
from bench import localization_worlds as worlds
from pymunk_bot.localization.trial import Trial, make_context, run_trial
from pymunk_bot.maps.rasterize import scenario_grid

MAP_RESOLUTION = 0.05  # [m]


def office(seed: int = 0, start_index: int = 0, odometry: dict | None = None):
    """(sim, map, route) in the 10 x 8 m office with drifting odometry."""
    start, route = worlds.route_from(worlds.OFFICE_ROUTE, (1.0, 1.0), start_index)
    sim = Simulation.from_dict(worlds.office_scenario(seed, odometry, start=start))
    return sim, scenario_grid(sim.config, MAP_RESOLUTION), route


def ros_map(seed: int = 0, start_index: int = 0):
    """(sim, map, route) on the ROS-style map image (unknown cells outside the building)."""
    start, route = worlds.route_from(worlds.ROS_ROUTE, worlds.ROS_START, start_index)
    data, grid = worlds.ros_map_world(seed, start=start)
    return Simulation.from_dict(data), grid, route


def run(world, make_localizer, seconds: float, seed: int = 0, drive_on: str = "estimate",
        on_step=None) -> tuple[Trial, object, object]:
    """Build the localizer for ``world`` = (sim, map, route) and drive; (trial, localizer, sim)."""
    sim, grid, route = world
    localizer = make_localizer(make_context(sim, "r1", seed, grid))
    trial = run_trial(sim, localizer, route, seconds, drive_on=drive_on, on_step=on_step)
    return trial, localizer, sim


def converged(trial: Trial, position: float = 0.3, heading: float = np.deg2rad(10.0)) -> float:
    """The time [s] after which the estimate stays within ``position`` [m] and ``heading``
    [rad] of the truth to the end of the run; inf if it never settles."""
    t, truth, est = trial.arrays()
    err = np.hypot(*(truth[:, :2] - est[:, :2]).T)
    dh = np.abs((est[:, 2] - truth[:, 2] + np.pi) % (2 * np.pi) - np.pi)
    bad = np.flatnonzero((err > position) | (dh > heading))
    if bad.size == 0:
        return float(t[0])
    return float(t[bad[-1] + 1]) if bad[-1] + 1 < t.size else float("inf")


def scan_of_segments(segments, pose=(0.0, 0.0, 0.0), beams: int = 360, max_range: float = 8.0,
                     noise: float = 0.01, rng: np.random.Generator | None = None) -> np.ndarray:
    """End points (robot frame) of a scan of the ``segments`` (x0, y0, x1, y1) [m] from
    ``pose`` [x, y, theta] (default: the origin, heading along x): each beam's nearest hit,
    range noise ``noise`` [m]."""
    rng = rng or np.random.default_rng(0)
    x, y, theta = pose
    c, s = math.cos(theta), math.sin(theta)
    bearings = np.linspace(-math.pi, math.pi, beams, endpoint=False)
    direction = np.column_stack([np.cos(bearings), np.sin(bearings)])
    ranges = np.full(beams, np.inf)
    for x0, y0, x1, y1 in segments:
        # the segment in the robot's frame
        a = np.array([c * (x0 - x) + s * (y0 - y), -s * (x0 - x) + c * (y0 - y)])
        b = np.array([c * (x1 - x) + s * (y1 - y), -s * (x1 - x) + c * (y1 - y)])
        e = b - a
        # origin + r d = a + u e  ->  [d, -e] [r, u]^T = a
        det = direction[:, 0] * -e[1] - direction[:, 1] * -e[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            r = (a[0] * -e[1] - a[1] * -e[0]) / det
            u = (direction[:, 0] * a[1] - direction[:, 1] * a[0]) / det
        hit = (np.abs(det) > 1e-12) & (r > 0) & (u >= 0) & (u <= 1)
        ranges = np.where(hit & (r < ranges), r, ranges)
    ranges = ranges + rng.normal(0.0, noise, beams)
    keep = np.isfinite(ranges) & (ranges < max_range)
    return direction[keep] * ranges[keep, None]
