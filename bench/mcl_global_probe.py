"""Why a global start does or does not converge, per MCL filter update (issue 36).

    python -m bench.mcl_global_probe FAMILY SEED [--profile typical] [--settings JSON] [--every N]
    e.g. python -m bench.mcl_global_probe warehouse_orca30 12

One ``mcl_global`` run of the robustness benchmark (its world, LiDAR and odometry; the same run,
as the probe draws no random numbers). A line per filter update:

- ``t``: time [s]; ``err``, ``err_h``: the filter's estimate off the truth [m, deg];
  ``loc``: the filter says ``localized``;
- ``clw``: the heaviest cluster's share of the belief; ``spr``, ``spr_h``: its spread (root of
  the trace of its (x, y) covariance [m], heading std [deg]);
- ``near``, ``near_w``: particles within 0.3 m / 10 deg of the truth and their share of the
  weight after this scan (before resampling);
- ``used``, ``left``, ``weighed``: the used returns, those left out (moving or short), the rest;
- ``fit_est``, ``fit_true``: the share of the weighed returns within ``sigma_hit`` of the map
  from the estimate and from the truth;
- ``lpz_true``, ``lpz_best``: the weighed returns' mean log ``pz`` at the truth and at the best
  particle;
- ``walkers``: used returns ending within WALKER_HIT of a walker's centre;
- ``seeded``: particles the scan search (posesearch.py) put on the poses it found (-1: no
  search); ``twins``: those within 1 m of the estimate at another heading (the aisle turned
  round); ``gain``: the best found pose's mean log ``pz`` over the estimate's, both polished;
  ``alike``: places (2 m bins over 1 m from the truth) among the found poses that fit the scan as
  well as the truth does, polished alike (within ``RESEED_MARGIN``).

At the end, a JSON summary of the run (how often and how much the search seeded, the seeds'
gains, the median count of look-alike places, when it said ``localized``, for how long on a
wrong pose, when it converged by the benchmark's rule, and how far the robot had driven, in
truth, by the benchmark's 20 s).
"""
from __future__ import annotations

import math
import sys
from contextlib import contextmanager
from typing import Any, Callable, Iterator, NoReturn

import numpy as np

from bench.localization_robustness import (FAMILIES, GLOBAL_HEADING, GLOBAL_POSITION, GLOBAL_TIME,
                                           MAX_SEEDS,
                                           MAX_TIME, PEOPLE_FAMILIES, lidar_for, odometry_for,
                                           settings_option, world_for)
from pymunk_bot.localization.se2 import transform_points, wrap

WALKER_HIT = 0.35  # [m] a return within this of a walker's centre ended on that walker
TWIN_REACH = 1.0  # [m] a seed this close to the estimate at another heading is its twin
PLACE_BIN = 2.0  # [m] look-alike poses are counted per place of this size
HEADER = (" t      err  err_h loc  clw   spr  spr_h  near near_w used left weighed fit_est "
          "fit_true lpz_true lpz_best walkers seeded twins   gain alike")


def _refuse(problem: str) -> NoReturn:
    print(f"mcl_global_probe: {problem}", file=sys.stderr)
    raise SystemExit(2)


def _mean_log_pz(mcl, poses: np.ndarray, points: np.ndarray, max_range: float) -> np.ndarray:
    """Per pose, the mean log pz of ``points`` (robot frame) in ``mcl``'s likelihood field."""
    c = mcl.config
    if points.shape[0] == 0:
        return np.zeros(poses.shape[0])
    d = mcl.field.distance(transform_points(poses, points))
    return np.log(c.z_hit * np.exp(-d * d / (2.0 * c.sigma_hit ** 2)) + c.z_rand / max_range).mean(axis=1)


def _near(poses: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Which ``poses`` are within the benchmark's convergence bounds of ``truth``."""
    return ((np.hypot(poses[:, 0] - truth[0], poses[:, 1] - truth[1]) <= GLOBAL_POSITION)
            & (np.abs(wrap(poses[:, 2] - truth[2])) <= GLOBAL_HEADING))


def _fit(mcl, pose: np.ndarray, points: np.ndarray) -> float:
    """Share of ``points`` within ``sigma_hit`` of the map from ``pose`` (nan: none)."""
    if points.shape[0] == 0:
        return math.nan
    return float(np.mean(mcl.field.distance(transform_points(pose, points)) <= mcl.config.sigma_hit))


def _on_walkers(truth: np.ndarray, points: np.ndarray, walkers: list) -> int:
    """Returns (robot frame ``points``) that ended on a walker, seen from the true pose."""
    if not walkers or points.shape[0] == 0:
        return 0
    world = transform_points(truth, points)
    centres = np.array([tuple(w.body.position) for w in walkers])
    gap = np.hypot(world[:, None, 0] - centres[None, :, 0], world[:, None, 1] - centres[None, :, 1])
    return int(np.count_nonzero(gap.min(axis=1) <= WALKER_HIT))


@contextmanager
def _watched(robot, seen: dict[str, Any]) -> Iterator[None]:
    """Record into ``seen``, while inside, what the ``robot``'s MCL weighs and seeds at each
    update (its methods and mcl.py's ``search`` / ``beam_log_pz`` wrapped; restored on leaving)."""
    import pymunk_bot.localization.mcl as mcl_module

    mcl = robot.localizer

    def truth() -> np.ndarray:
        return np.array(robot.pose, dtype=float)

    weigh, reseed_once = mcl.scan_likelihood, mcl._reseed_from_scan
    find, score_of = mcl_module.search, mcl_module.beam_log_pz

    def scan_likelihood(scan, points=None):
        seen.update(points=None if points is None else np.array(points),
                    particles=mcl.particles.copy(), prior=mcl.weights.copy())
        seen["likelihood"] = np.array(weigh(scan, points))
        return seen["likelihood"]

    def reseed(scan, points, margin):
        before, old = mcl.reseeded, mcl.particles.copy()
        reseed_once(scan, points, margin)
        seen["seeded"] = mcl.reseeded - before
        seeds = mcl.particles[np.any(mcl.particles != old, axis=1)]
        est = mcl._filter_pose
        seen["twins"] = int(np.count_nonzero(
            (np.hypot(seeds[:, 0] - est[0], seeds[:, 1] - est[1]) <= TWIN_REACH)
            & (np.abs(wrap(seeds[:, 2] - est[2])) > GLOBAL_HEADING)))
        seen["seeds_at_truth"] = int(_near(seeds, truth()).sum())

    def search(field, points, *args, **kwargs):
        found, score = find(field, points, *args, **kwargs)
        seen["found_best"] = float(score[0]) if score.size else math.nan
        c, here = mcl.config, truth()
        polished = mcl_module.refine(field, here[None], points)
        z_rand = c.z_rand / robot.lidar.latest.max_range  # the scan being weighed
        at_truth = score_of(field, polished, points, c.sigma_hit, c.z_hit, z_rand)[0]
        far = np.hypot(found[:, 0] - here[0], found[:, 1] - here[1]) > TWIN_REACH
        alike = found[far & (score >= at_truth - mcl_module.RESEED_MARGIN)]
        seen["alike"] = len({(round(x / PLACE_BIN), round(y / PLACE_BIN)) for x, y, _ in alike})
        return found, score

    def beam_log_pz(*args, **kwargs):  # in mcl.py only the polished estimate is scored so
        score = score_of(*args, **kwargs)
        seen["here"] = float(score[0])
        return score

    mcl.scan_likelihood, mcl._reseed_from_scan = scan_likelihood, reseed
    mcl_module.search, mcl_module.beam_log_pz = search, beam_log_pz
    try:
        yield
    finally:
        mcl_module.search, mcl_module.beam_log_pz = find, score_of
        del mcl.scan_likelihood, mcl._reseed_from_scan


def _row(sim, robot, mcl, walkers: list, seen: dict[str, Any]) -> dict[str, Any]:
    """The figures of the update just done (see the module docstring)."""
    scan = robot.lidar.latest
    truth = np.array(robot.pose, dtype=float)
    est = np.asarray(mcl._filter_pose, dtype=float)
    used = mcl.used_points(scan)
    weighed = seen.get("points")
    weighed = used if weighed is None else weighed
    post = seen["prior"] * seen["likelihood"]
    post = post / post.sum() if post.sum() > 0 else post
    near = _near(seen["particles"], truth)
    lpz = _mean_log_pz(mcl, np.vstack([truth[None], seen["particles"]]), weighed, scan.max_range)
    cov = mcl.covariance
    return {"t": sim.time, "err": float(np.hypot(*(est[:2] - truth[:2]))),
            "err_h": math.degrees(abs(wrap(est[2] - truth[2]))), "localized": bool(mcl.localized),
            "cluster": mcl.cluster_weight, "spread": math.sqrt(max(cov[0, 0] + cov[1, 1], 0.0)),
            "spread_h": math.degrees(math.sqrt(max(cov[2, 2], 0.0))),
            "near": int(near.sum()), "near_w": float(post[near].sum()),
            "used": used.shape[0], "weighed": weighed.shape[0],
            "fit_est": _fit(mcl, est, weighed), "fit_true": _fit(mcl, truth, weighed),
            "lpz_true": float(lpz[0]), "lpz_best": float(lpz[1:].max()),
            "walkers": _on_walkers(truth, used, walkers), "seeded": seen.get("seeded", -1),
            "twins": seen.get("twins", 0), "seeds_at_truth": seen.get("seeds_at_truth", 0),
            "gain": seen.get("found_best", math.nan) - seen.get("here", math.nan),
            "alike": seen.get("alike", -1)}


def _line(row: dict[str, Any]) -> str:
    return (f"{row['t']:5.1f} {row['err']:6.2f} {row['err_h']:6.1f}  {'Y' if row['localized'] else '.'} "
            f"{row['cluster']:5.2f} {row['spread']:5.2f} {row['spread_h']:6.1f} {row['near']:5d} "
            f"{row['near_w']:6.3f} {row['used']:4d} {row['used'] - row['weighed']:4d} "
            f"{row['weighed']:7d} {row['fit_est']:7.2f} {row['fit_true']:8.2f} {row['lpz_true']:8.3f} "
            f"{row['lpz_best']:8.3f} {row['walkers']:7d} {row['seeded']:6d} {row['twins']:5d} "
            f"{row['gain']:6.3f} {row['alike']:5d}")


def probe(family: str, seed: int, profile: str = "typical", settings: dict | None = None,
          every: int = 1, out: Callable[[str], None] = print) -> dict[str, Any]:
    """Run one global start, print a line per ``every``-th filter update (and at each change of
    ``localized``) with ``out``, and return the run's summary (:func:`summarize`)."""
    from pymunk_bot.engine.simulation import Simulation

    try:
        data = world_for(family, seed)
    except ValueError as exc:
        _refuse(f"{family} seed {seed}: {exc}")
    if data is None:
        _refuse(f"the {family} map is not here")
    robot = data["robots"][0]
    robot.update(lidar=lidar_for(seed), odometry=odometry_for(profile, seed),
                 localization={"type": "mcl", "initial": "global", **(settings or {})})
    data["seed"] = seed
    data.setdefault("world", {})["duration"] = MAX_TIME
    sim = Simulation.from_dict(data)
    r = sim.robots["r1"]
    mcl = r.localizer
    walkers = [o for o in sim.world.obstacles if getattr(o.config, "type", "") == "pedestrian"]
    seen: dict[str, Any] = {}
    rows: list[dict[str, Any]] = []
    out(HEADER)
    path, last = 0.0, np.array(r.pose[:2], dtype=float)  # [m] the true path so far
    with _watched(r, seen):
        updates = mcl.updates
        while sim.time < MAX_TIME and not r.goal_reached:
            seen.clear()
            sim.step()
            here = np.array(r.pose[:2], dtype=float)
            path, last = path + float(np.hypot(*(here - last))), here
            if mcl.updates == updates:
                continue
            updates = mcl.updates
            rows.append(_row(sim, r, mcl, walkers, seen) | {"path": path})
            flipped = len(rows) > 1 and rows[-1]["localized"] != rows[-2]["localized"]
            if (len(rows) - 1) % every == 0 or flipped:
                out(_line(rows[-1]))
    return summarize(rows)


def summarize(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The run's figures from the per-update rows (times in s, gains per return)."""
    if not rows:
        return {"updates": 0}
    t = np.array([r["t"] for r in rows])
    said = np.array([r["localized"] for r in rows])
    off = np.array([r["err"] > GLOBAL_POSITION or r["err_h"] > math.degrees(GLOBAL_HEADING)
                    for r in rows])
    bad = np.flatnonzero(off)
    converged = (t[0] if bad.size == 0 else t[bad[-1] + 1] if bad[-1] + 1 < t.size else math.inf)
    seeding = [r for r in rows if r["seeded"] > 0]
    alike = [r["alike"] for r in rows if r["alike"] >= 0]
    by_20 = [r["path"] for r in rows if r["t"] <= GLOBAL_TIME]
    return {"updates": len(rows),
            "converged_at": float(converged),
            "first_localized": float(t[np.argmax(said)]) if said.any() else math.inf,
            "localized_while_off": float(np.diff(np.append(t, t[-1]))[said & off].sum()),
            "path_by_20s": by_20[-1] if by_20 else 0.0,
            "median_used": float(np.median([r["used"] for r in rows])),
            "median_weighed": float(np.median([r["weighed"] for r in rows])),
            "median_fit_true": float(np.nanmedian([r["fit_true"] for r in rows])),
            "share_with_particle_at_truth": float(np.mean([r["near"] > 0 for r in rows])),
            "truth_ahead_of_best": float(np.mean([r["lpz_true"] >= r["lpz_best"] for r in rows])),
            "updates_seeding": len(seeding),
            "seeded_particles": sum(r["seeded"] for r in seeding),
            "seeding_gain_quartiles": [round(float(q), 3) for q in np.percentile(
                [r["gain"] for r in seeding] or [math.nan], [25, 50, 75])],
            "seeds_at_truth": sum(r["seeds_at_truth"] for r in rows),
            "gains_seeding_at_truth": [round(r["gain"], 3) for r in seeding if r["seeds_at_truth"]][:40],
            "twin_seeds": sum(r["twins"] for r in rows),
            "look_alike_places_median": float(np.median(alike)) if alike else math.nan}


def main(argv: list[str] | None = None) -> None:
    """The command line: ``python -m bench.mcl_global_probe``."""
    import argparse
    import json

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("family", choices=FAMILIES + PEOPLE_FAMILIES)
    parser.add_argument("seed", type=int)
    parser.add_argument("--profile", default="typical", choices=("perfect", "typical", "uncalibrated"))
    parser.add_argument("--settings", default="{}", metavar="JSON", help="extra MCL keys")
    parser.add_argument("--every", type=int, default=1, help="a line every N filter updates")
    args = parser.parse_args(argv)
    if not 0 <= args.seed < MAX_SEEDS:
        parser.error(f"seed must be 0..{MAX_SEEDS - 1} (got {args.seed})")
    if args.every < 1:
        parser.error(f"--every must be >= 1 (got {args.every})")
    settings = settings_option(parser, args.settings, "MCL")
    result = probe(args.family, args.seed, args.profile, settings, args.every)
    print(json.dumps({k: round(v, 3) if isinstance(v, float) else v for k, v in result.items()}))


if __name__ == "__main__":
    main()
