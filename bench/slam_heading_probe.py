"""Where SLAM's error enters, keyframe by keyframe, in one revisiting run of the robustness
benchmark (issue 36).

    python -m bench.slam_heading_probe FAMILY PROFILE SEED [--settings JSON] [--keyframes]
                                       [--noise-free]
    e.g. python -m bench.slam_heading_probe warehouse uncalibrated 5 --keyframes

At each keyframe, as it is taken (before any later loop closure moves it): the estimate's
heading error, its position error split along the robot's heading (forward: the direction an
aisle or a corridor leaves to the odometry) and across it, the heading error of the step
from the previous keyframe, and the front end's match: the std of its position along its
worst and best axes and of its heading (a corridor: the worst axis near the odometry prior's).
The summary says which dominates: a forward error entered where the scan could not pin the
position along the route; a sideways error that grows with the distance driven, under a
steady heading error, entered with the heading.

The matcher's own heading error (``matcher_heading_error``): the keyframe's scan matched as
the front end matches it, but to the previous LOCAL_KEYFRAMES keyframes' scans placed at
their *true* poses, from the true pose, with no odometry prior. What it shows adds up along
the chain whatever the rest of SLAM does; ``--noise-free`` gives the LiDAR no range noise, so
what is left is the matcher's (docs/localization-journal.md, "SLAM: lines that are not lines").

The step's heading error is split into where it came from: the odometry's own step heading
error (the prior's mean), what the scan alone said (the match's information less the
prior's: ``scan_step_heading_error``) and how far the prior pulled the match from it
(``prior_pull``). The summary adds them up over the run: an odometry whose heading error is a
bias (wheel radii that differ: degrees per metre) shows as a prior pull of one sign.
"""
from __future__ import annotations

import json
import math
import sys
from collections import deque
from typing import NoReturn

import numpy as np

from bench.localization_robustness import (FAMILIES, MAX_SEEDS, REVISIT_MAX_TIME, Tour,
                                           lidar_for, odometry_for, settings_option,
                                           tour_goals, world_for)
from pymunk_bot.localization.icp import Reference, icp, seen_from
from pymunk_bot.localization.odometry_trust import scan_only
from pymunk_bot.localization.scanmatch import subsample
from pymunk_bot.localization.se2 import between, scan_points, wrap
from pymunk_bot.localization.slam import LOCAL_KEYFRAMES


def _refuse(problem: str) -> NoReturn:
    """One line on stderr, exit status 2."""
    print(f"slam_heading_probe: {problem}", file=sys.stderr)
    raise SystemExit(2)


def _sources(step, truth_turn: float) -> dict:
    """The step's heading error by its sources [deg] (module docstring), from the front end's
    latest match ``step`` (slam.FrontEndStep) and the true turn since the previous keyframe
    ``truth_turn`` [rad]."""
    odometry = float(wrap(between(step.last, step.predicted)[2] - truth_turn))
    scan = scan_only(step.pose, step.covariance, step.predicted, step.prior) if step.matched else None
    if scan is None:  # the keyframe took the prediction: no scan-only heading
        return {"odometry_step_heading_error": math.degrees(odometry),
                "scan_step_heading_error": math.nan, "prior_pull": 0.0}
    scan_heading = float(step.predicted[2]) + float(scan[0][2])
    return {"odometry_step_heading_error": math.degrees(odometry),
            "scan_step_heading_error": math.degrees(float(wrap(scan_heading - float(step.last[2]) - truth_turn))),
            "prior_pull": math.degrees(float(wrap(float(step.pose[2]) - scan_heading)))}


def matcher_heading_error(earlier: deque, points: np.ndarray, truth: np.ndarray, config,
                          sensor: np.ndarray) -> float:
    """[deg] the heading error of robot-frame scan ``points`` taken at ``truth`` [x, y, theta],
    matched as SLAM's front end (``config``: its SlamConfig) to ``earlier`` keyframes' (true
    pose, robot-frame points), placed at their true poses (module docstring); NaN if no match.
    ``sensor``: the LiDAR's mount (robot frame [m])."""
    world, facing = zip(*(seen_from(pose, p, sensor) for pose, p in earlier))
    reference = Reference.surfaces(np.concatenate(world), facing=np.concatenate(facing))
    match = icp(reference, subsample(points, config.max_beams), truth, config.iterations,
                config.max_pair, config.huber, sensor=sensor)
    return math.degrees(float(wrap(match.pose[2] - truth[2]))) if match.ok else math.nan


def probe(family: str, profile: str, seed: int, settings: dict | None = None,
          noise_free: bool = False) -> dict:
    """Per keyframe figures (``keyframes``: a list of dicts, [deg] and [cm]) and a summary;
    ``noise_free``: the LiDAR without range noise."""
    from pymunk_bot.engine.simulation import Simulation

    data = world_for(family, seed, revisit=True)
    if data is None:
        _refuse(f"the {family} map is not here")
    tour = Tour(tour_goals(family, seed, data)[1:])
    robot = data["robots"][0]
    robot.update(lidar={**lidar_for(seed), **({"noise_std": 0.0} if noise_free else {})},
                 odometry=odometry_for(profile, seed),
                 localization={"type": "slam", **(settings or {})})
    data["seed"] = seed
    data.setdefault("world", {})["duration"] = REVISIT_MAX_TIME
    try:
        sim = Simulation.from_dict(data)
    except Exception as exc:  # e.g. a --settings key SLAM does not have: one line, not a traceback
        _refuse(f"{family} {profile} seed {seed}: {type(exc).__name__}: {exc}".splitlines()[0])
    r = sim.robots["r1"]
    slam = r.localizer
    rows: list[dict] = []
    last_truth = last_pose = None
    seen = 0  # keyframes seen so far (one new keyframe a row; the first has no step)
    earlier: deque = deque(maxlen=LOCAL_KEYFRAMES)  # (true pose, scan points) of the latest keyframes
    while sim.time < REVISIT_MAX_TIME:
        sim.step()
        if len(slam.keyframes) > seen:
            seen = len(slam.keyframes)
            truth, pose = np.array(r.pose, dtype=float), np.array(slam.keyframes[-1], dtype=float)
            points = scan_points(r.lidar.latest)[0]  # the keyframe's scan (taken this step)
            matcher = (matcher_heading_error(earlier, points, truth, slam.config,
                                                 np.asarray(slam.context.lidar_offset[:2]))
                       if earlier else math.nan)
            earlier.append((truth, points))
            if last_truth is not None:
                c, s = math.cos(truth[2]), math.sin(truth[2])
                d = pose[:2] - truth[:2]
                cov = np.asarray(slam.covariance)
                axes = np.sqrt(np.maximum(np.linalg.eigvalsh(cov[:2, :2]), 0.0))
                truth_turn = float(between(last_truth, truth)[2])
                rows.append({
                    "time": round(sim.time, 2),
                    "heading_error": math.degrees(float(wrap(pose[2] - truth[2]))),
                    "forward_error": 100.0 * float(c * d[0] + s * d[1]),
                    "sideways_error": 100.0 * float(-s * d[0] + c * d[1]),
                    "step_heading_error": math.degrees(float(wrap(between(last_pose, pose)[2]
                                                                  - between(last_truth, truth)[2]))),
                    "match_std_worst": 100.0 * float(axes[1]), "match_std_best": 100.0 * float(axes[0]),
                    "match_heading_std": math.degrees(math.sqrt(max(float(cov[2, 2]), 0.0))),
                    "driven": 100.0 * float(np.hypot(*(truth[:2] - last_truth[:2]))),
                    "matcher_heading_error": matcher,
                    **_sources(slam.front_end_step, truth_turn)})
            last_truth, last_pose = truth, pose
        if not tour.next_goal(r):
            break
    if not rows:
        _refuse(f"{family} {profile} seed {seed}: SLAM took no keyframe")
    table = {k: np.array([row[k] for row in rows]) for k in rows[0]}
    heading, forward, sideways = table["heading_error"], table["forward_error"], table["sideways_error"]
    summary = {"keyframes": len(rows), "goal_reached": bool(r.goal_reached),
               "heading_error_rms_deg": float(np.sqrt(np.mean(heading ** 2))),
               "heading_error_max_deg": float(np.abs(heading).max()),
               "forward_error_rms_cm": float(np.sqrt(np.mean(forward ** 2))),
               "sideways_error_rms_cm": float(np.sqrt(np.mean(sideways ** 2))),
               "step_heading_error_rms_deg": float(np.sqrt(np.mean(table["step_heading_error"] ** 2))),
               "match_heading_std_median_deg": float(np.median(table["match_heading_std"])),
               "match_std_worst_median_cm": float(np.median(table["match_std_worst"])),
               "closures": len(slam.closures),
               "odometry_heading_error_deg_per_m": float(np.sum(table["odometry_step_heading_error"])
                                                          / max(float(np.sum(table["driven"])) / 100.0, 1e-9)),
               "step_heading_error_sum_deg": float(np.sum(table["step_heading_error"])),
               "scan_step_heading_error_sum_deg": float(np.nansum(table["scan_step_heading_error"])),
               "prior_pull_sum_deg": float(np.sum(table["prior_pull"])),
               "matcher_heading_error_rms_deg": float(np.sqrt(np.nanmean(table["matcher_heading_error"] ** 2))),
               "matcher_heading_error_mean_deg": float(np.nanmean(table["matcher_heading_error"])),
               "matcher_heading_error_sum_deg": float(np.nansum(table["matcher_heading_error"]))}
    return {"summary": summary, "keyframes": rows}


def main(argv: list[str] | None = None) -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("family", choices=FAMILIES)
    parser.add_argument("profile", choices=("perfect", "typical", "uncalibrated"))
    parser.add_argument("seed", type=int)
    parser.add_argument("--settings", default="{}", metavar="JSON", help="extra SLAM keys")
    parser.add_argument("--keyframes", action="store_true", help="a line for every keyframe")
    parser.add_argument("--noise-free", action="store_true", help="a LiDAR without range noise")
    args = parser.parse_args(argv)
    if not 0 <= args.seed < MAX_SEEDS:
        parser.error(f"seed must be 0..{MAX_SEEDS - 1} (got {args.seed})")
    settings = settings_option(parser, args.settings, "SLAM")
    out = probe(args.family, args.profile, args.seed, settings, args.noise_free)
    if args.keyframes:
        for k, row in enumerate(out["keyframes"], start=1):
            print(f"{k:4d} " + " ".join(f"{key} {value:.2f}" for key, value in row.items()))
    print(json.dumps({k: (round(v, 3) if isinstance(v, float) else v) for k, v in out["summary"].items()}))


if __name__ == "__main__":
    main()
