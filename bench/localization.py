"""How well and how fast the localizers work: issue 11's figures, 10 seeds per world.

    python -m bench.localization [--seeds 10] [--quick] [--out bench.json]
    python -m bench.localization --robustness [--seeds 10] [--quick]
        # the defaults on unseen worlds (localization_robustness.py)

Worlds (benchmarks/localization_worlds.py): the 10 x 8 m office and the ROS-style map, both
with drifting odometry (its error after each run is reported too) and a 360-beam LiDAR with
1 cm noise. Every run drives a ~36 m tour by pure pursuit on the *estimate* (global
localization: on the truth, since the estimate means nothing until it converges), feeding the
localizer after every physics step exactly as the core does (localization/trial.py).

- mcl: position RMSE and heading RMSE (targets 5 cm, 2 deg);
- global: time until the estimate stays within 0.3 m and 10 deg (target <= 15 s in 9/10),
  each seed starting at a different place of the tour;
- ekf: RMSE and the fraction of updates whose NEES lies in the two-sided 95 % chi^2(3) band;
- slam: ATE / RPE (evo's definitions), map precision against scenario_grid at one-cell
  tolerance, and the real-time factor (simulated seconds per wall second, physics included);
- mcl_update_cost: one filter update (motion, 60-beam likelihood field, KLD resampling) for
  500 and 5000 particles, median CPU time of this thread.
"""
from __future__ import annotations

import argparse
import gc
from typing import Any
import statistics
import time

import numpy as np
from scipy.stats import chi2

from pymunk_bot.localization import EkfConfig, EkfLocalizer, MclConfig, MclLocalizer, SlamConfig, SlamLocalizer
from pymunk_bot.localization.base import LocalizerInputs
from pymunk_bot.localization.metrics import ate, map_scores, rpe
from pymunk_bot.localization.se2 import wrap
from pymunk_bot.localization.trial import make_context, run_trial
from pymunk_bot.maps.rasterize import scenario_grid
from pymunk_bot.engine.simulation import Simulation
from bench import localization_worlds as worlds

# The settings of scenarios/mcl_office.yaml and global_localization.yaml.
TRACKING = MclConfig(sigma_hit=0.05, update_min_d=0.05, update_min_a=0.05)
GLOBAL = MclConfig(initial="global", max_particles=5000, update_min_d=0.1, update_min_a=0.1,
                   recovery_alpha_slow=0.001, recovery_alpha_fast=0.1)
MAX_TIME = 120.0  # [s] of simulated time per run
GLOBAL_TIME = 20.0  # [s]


def _world(name: str, seed: int, start_index: int = 0):
    if name == "office":
        start, route = worlds.route_from(worlds.OFFICE_ROUTE, (1.0, 1.0), start_index)
        sim = Simulation.from_dict(worlds.office_scenario(seed, start=start))
        return sim, scenario_grid(sim.config, 0.05), route
    start, route = worlds.route_from(worlds.ROS_ROUTE, worlds.ROS_START, start_index)
    data, grid = worlds.ros_map_world(seed, start=start)
    return Simulation.from_dict(data), grid, route


def _odometry_error(sim) -> float:
    r = sim.robots["r1"]
    return float(np.hypot(*(r.odometry.pose[:2] - r.pose[:2])))


def run_mcl(world: str, seed: int) -> dict:
    sim, grid, route = _world(world, seed)
    trial = run_trial(sim, MclLocalizer(TRACKING, make_context(sim, "r1", seed, grid)),
                      route, MAX_TIME)
    e = trial.errors()
    return {"rmse": e["rmse"], "heading_rmse_deg": float(np.rad2deg(e["heading_rmse"])),
            "max_error": e["max_error"], "odometry_error": _odometry_error(sim),
            "collisions": trial.collisions,
            "passed": e["rmse"] <= 0.05 and e["heading_rmse"] <= np.deg2rad(2.0)}


def run_global(world: str, seed: int) -> dict:
    sim, grid, route = _world(world, seed, start_index=seed)
    trial = run_trial(sim, MclLocalizer(GLOBAL, make_context(sim, "r1", seed, grid)),
                      route, GLOBAL_TIME, drive_on="truth")
    t, truth, est = trial.arrays()
    ok = (np.hypot(*(truth[:, :2] - est[:, :2]).T) <= 0.3) & (
        np.abs(wrap(truth[:, 2] - est[:, 2])) <= np.deg2rad(10.0))
    bad = np.flatnonzero(~ok)
    settled = 0.0 if bad.size == 0 else (float(t[bad[-1] + 1]) if bad[-1] + 1 < t.size else float("inf"))
    return {"time_to_localize": settled, "passed": settled <= 15.0}


def run_ekf(world: str, seed: int) -> dict:
    sim, grid, route = _world(world, seed)
    nees: list[float] = []

    def record(sim, loc):
        r = sim.robots["r1"]
        if abs(r.lidar.latest.time - sim.time) < 1e-9:
            e = loc.pose - r.pose
            e[2] = wrap(e[2])
            nees.append(float(e @ np.linalg.solve(loc.covariance, e)))

    trial = run_trial(sim, EkfLocalizer(EkfConfig(), make_context(sim, "r1", seed, grid)), route,
                      MAX_TIME, on_step=record)
    values = np.asarray(nees)
    inside = float(np.mean((values >= chi2.ppf(0.025, 3)) & (values <= chi2.ppf(0.975, 3))))
    e = trial.errors()
    return {"rmse": e["rmse"], "heading_rmse_deg": float(np.rad2deg(e["heading_rmse"])),
            "nees_in_band": inside, "nees_mean": float(values.mean()),
            "nees_below_upper": float(np.mean(values <= chi2.ppf(0.975, 3))),
            "passed": e["rmse"] <= 0.05 and inside >= 0.9}


def run_slam(world: str, seed: int) -> dict:
    sim, grid, route = _world(world, seed)
    loc = SlamLocalizer(SlamConfig(), make_context(sim, "r1", seed, None))
    started = time.perf_counter()
    trial = run_trial(sim, loc, route, MAX_TIME)
    wall = time.perf_counter() - started
    _, truth, est = trial.arrays()
    a = ate(truth, est)
    truth_map = scenario_grid(sim.config, 0.05) if world == "office" else grid
    scores = map_scores(loc.grid, truth_map)
    return {"ate_rmse": a["rmse"], "ate_max": a["max"], "rpe_1m": rpe(truth, est)["trans"]["rmse"],
            "map_precision": scores["precision"], "map_recall": scores["recall"],
            "loop_closures": len(loc.loop_closures), "keyframes": len(loc.keyframes),
            "real_time_factor": trial.sim_time / wall, "odometry_error": _odometry_error(sim),
            "passed": a["rmse"] <= 0.05 and scores["precision"] >= 0.95 and wall < trial.sim_time}


def mcl_update_cost(particles: int, beams: int = 60, repeats: int = 15) -> float:
    """Median CPU seconds of one MCL update (motion + 60-beam likelihood + KLD resampling)."""
    sim, grid, _ = _world("office", 0)
    config = MclConfig(particles=particles, min_particles=particles, max_particles=particles,
                       max_beams=beams, update_min_d=0.0, update_min_a=0.0)
    loc = MclLocalizer(config, make_context(sim, "r1", 0, grid))
    robot = sim.robots["r1"]
    scan = robot.lidar.latest
    odom = robot.odometry.pose.copy()
    loc.update(LocalizerInputs(scan.time, odom, scan))
    times = []
    gc.disable()
    try:
        for k in range(repeats):
            odom = odom + np.array([0.01, 0.0, 0.001])
            fresh = type(scan)(scan.ranges, scan.angles, scan.min_range, scan.max_range,
                               scan.offset, float(k + 1))
            started = time.thread_time()
            loc.update(LocalizerInputs(float(k + 1), odom, fresh))
            times.append(time.thread_time() - started)
    finally:
        gc.enable()
    return statistics.median(times)


def _summary(rows: list[dict], keys: list[str]) -> dict:
    out: dict[str, Any] = {"passed": f"{sum(r['passed'] for r in rows)}/{len(rows)}"}
    for k in keys:
        values = [r[k] for r in rows]
        out[k] = {"median": float(np.median(values)), "worst": float(max(values))}
    return out


def run_all(seeds: int = 10, quick: bool = False) -> dict:
    """Every figure of the bench (``quick``: 2 seeds); for ``pymunk-bot bench``."""
    seeds = 2 if quick else seeds
    result: dict[str, Any] = {"seeds": seeds}
    for world in ("office", "ros_map"):
        mcl = [run_mcl(world, s) for s in range(seeds)]
        glob = [run_global(world, s) for s in range(seeds)]
        ekf = [run_ekf(world, s) for s in range(seeds)]
        slam = [run_slam(world, s) for s in range(seeds)]
        result[world] = {
            "mcl": _summary(mcl, ["rmse", "heading_rmse_deg", "odometry_error"]),
            "global": _summary(glob, ["time_to_localize"]),
            "ekf": _summary(ekf, ["rmse", "heading_rmse_deg", "nees_in_band", "nees_mean"]),
            "slam": _summary(slam, ["ate_rmse", "rpe_1m", "map_precision", "real_time_factor",
                                    "loop_closures"]),
        }
        # "worst" of a fraction or a speed is its minimum
        for key in ("nees_in_band",):
            result[world]["ekf"][key]["worst"] = float(min(r[key] for r in ekf))
        for key in ("map_precision", "real_time_factor"):
            result[world]["slam"][key]["worst"] = float(min(r[key] for r in slam))
    result["mcl_update_ms"] = {str(n): 1e3 * mcl_update_cost(n, repeats=5 if quick else 15)
                               for n in (500, 5000)}
    return result


def main() -> None:
    import json

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", help="write the figures as JSON here")
    parser.add_argument("--robustness", action="store_true",
                        help="run the benchmark of the defaults on unseen worlds instead "
                             "(localization_robustness.py; --seeds, --quick and --out apply)")
    args = parser.parse_args()
    if args.robustness:
        from bench import localization_robustness

        localization_robustness.main(["--seeds", str(args.seeds)] + ["--quick"] * args.quick
                                     + (["--out", args.out] if args.out else []))
        return
    result = run_all(args.seeds, args.quick)
    print(json.dumps(result, indent=1))
    if args.out:
        from pymunk_bot.outcomes.results import write_json
        write_json(args.out, result)


if __name__ == "__main__":
    main()
