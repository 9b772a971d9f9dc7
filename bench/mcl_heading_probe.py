"""Where MCL's heading error comes from, in one run of the robustness benchmark (issue 36).

    python -m bench.mcl_heading_probe FAMILY PROFILE SEED [--settings JSON]
    e.g. python -m bench.mcl_heading_probe turtlebot3 uncalibrated 17 --settings '{"sigma_hit": 0.2}'

At every filter update it prints, over the run: the estimate's heading error (RMSE and signed
mean: a mean near the RMSE is a lag behind a drifting odometry, not noise), the heading error
of the odometry prediction before the update (the estimate just before, moved by the odometry),
the cloud's heading spread, and what the scan alone says: the used beams' log-likelihood at the
*true* position over headings +-6 deg, its peak (where the scan puts the heading) and the
heading std its curvature stands for (how sure the filter takes the scan to be).
"""
from __future__ import annotations

import math
import sys
from typing import NoReturn

import numpy as np

from bench.localization_robustness import (FAMILIES, MAX_SEEDS, MAX_TIME, PEOPLE_FAMILIES,
                                           lidar_for, odometry_for, settings_option,
                                           world_for)
from pymunk_bot.localization.se2 import transform_points, wrap

PROBE_SPAN = math.radians(6.0)  # [rad] headings tried either side of the truth
PROBE_STEPS = 241
FIT_SPAN = math.radians(2.5)  # [rad] the parabola fitted to the log-likelihood within this


def scan_heading_profile(mcl, scan, truth: np.ndarray) -> tuple[float, float]:
    """(peak offset [rad], heading std of its curvature [rad]) of ``mcl``'s likelihood field
    model for ``scan`` at the true position, over headings around the true one."""
    c = mcl.config
    offsets = np.linspace(-PROBE_SPAN, PROBE_SPAN, PROBE_STEPS)
    poses = np.repeat(truth[None], offsets.size, axis=0)
    poses[:, 2] += offsets
    d = mcl.field.distance(transform_points(poses, mcl.used_points(scan)))
    log_l = np.log(c.z_hit * np.exp(-d * d / (2.0 * c.sigma_hit ** 2)) + c.z_rand / scan.max_range).sum(axis=1)
    near = np.abs(offsets) <= FIT_SPAN
    curvature = np.polyfit(offsets[near], log_l[near], 2)[0]
    std = 1.0 / math.sqrt(-2.0 * curvature) if curvature < 0 else math.inf
    return float(offsets[np.argmax(log_l)]), std


def _refuse(problem: str) -> NoReturn:
    """One line on stderr, exit status 2."""
    print(f"mcl_heading_probe: {problem}", file=sys.stderr)
    raise SystemExit(2)


def probe(family: str, profile: str, seed: int, settings: dict | None = None) -> dict[str, float]:
    """The figures above [deg] for one run (MCL, the benchmark's world, LiDAR and odometry)."""
    from pymunk_bot.engine.simulation import Simulation

    try:
        data = world_for(family, seed)
    except ValueError as exc:  # e.g. fewer walkers fit than asked
        _refuse(f"{family} seed {seed}: {exc}")
    if data is None:
        _refuse(f"the {family} map is not here")
    robot = data["robots"][0]
    robot.update(lidar=lidar_for(seed), odometry=odometry_for(profile, seed),
                 localization={"type": "mcl", **(settings or {})})
    data["seed"] = seed
    sim = Simulation.from_dict(data)
    r = sim.robots["r1"]
    mcl = r.localizer
    post, prior, spread, peak, scan_std = [], [], [], [], []
    before = np.asarray(mcl.pose, dtype=float)  # the estimate one tick before
    updates = mcl.updates
    while sim.time < MAX_TIME and not r.goal_reached:
        sim.step()
        truth = np.array(r.pose, dtype=float)
        if mcl.updates != updates:
            updates = mcl.updates
            scan = r.lidar.latest
            post.append(wrap(mcl.pose[2] - truth[2]))
            prior.append(wrap(before[2] - truth[2]))
            spread.append(math.sqrt(mcl.covariance[2, 2]))
            offset, std = scan_heading_profile(mcl, scan, truth)
            peak.append(offset)
            scan_std.append(std)
        before = np.asarray(mcl.pose, dtype=float)
    deg = np.degrees
    post_a, peak_a = np.asarray(post), np.asarray(peak)
    return {"updates": len(post), "heading_rmse": float(deg(np.sqrt(np.mean(post_a ** 2)))),
            "heading_mean": float(deg(post_a.mean())), "before_update_mean": float(deg(np.mean(prior))),
            "cloud_heading_std": float(deg(np.mean(spread))),
            "scan_peak_mean": float(deg(peak_a.mean())), "scan_peak_rms": float(deg(np.sqrt(np.mean(peak_a ** 2)))),
            "scan_heading_std_median": float(deg(np.median(scan_std)))}


def main(argv: list[str] | None = None) -> None:
    import argparse
    import json

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("family", choices=FAMILIES + PEOPLE_FAMILIES)
    parser.add_argument("profile", choices=("perfect", "typical", "uncalibrated"))
    parser.add_argument("seed", type=int)
    parser.add_argument("--settings", default="{}", metavar="JSON", help="extra MCL keys")
    args = parser.parse_args(argv)
    if not 0 <= args.seed < MAX_SEEDS:
        parser.error(f"seed must be 0..{MAX_SEEDS - 1} (got {args.seed})")
    settings = settings_option(parser, args.settings, "MCL")
    print(json.dumps({k: round(v, 3) for k, v in probe(args.family, args.profile, args.seed, settings).items()}))


if __name__ == "__main__":
    main()
