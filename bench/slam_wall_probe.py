"""What SLAM's wall landmarks see, against the truth, in revisiting runs (issue 36).

    python -m bench.slam_wall_probe FAMILY PROFILE SEED [--settings JSON]
    python -m bench.slam_wall_probe FAMILY PROFILE SEEDS --offline [--variants JSON]

The first form runs ``slam_revisit`` with ``wall_landmarks`` on and, per landmark, prints each
observation: its keyframe, where along the wall (s, m) it saw which stretch, its direction's
error against the TRUE keyframe heading (the landmark's mean taken out) and its stated std,
and the direction of the scenario map's occupied cells under that stretch (the wall as it is
there). Then the final graph is optimized again offline: without the walls, with them, with
each observation's direction replaced by one that agrees at the true headings, without each
landmark and with it alone: which landmark pulls the headings, by how much.

The second runs seeds 0 .. SEEDS-1 with the walls seen but kept out of the graph (the
default's runs) and prints each final graph's ATE [cm] optimized again offline without walls,
with them, and with walls.py's constants set as each of VARIANTS says (``--variants``: more,
as JSON: {"name": {"CONSTANT": value}}).
"""
from __future__ import annotations

import copy
import json
import math
import sys

import numpy as np

from bench.localization_robustness import run_one
from pymunk_bot.localization.posegraph import optimize
from pymunk_bot.localization.se2 import transform_points
from pymunk_bot.localization import walls as walls_module


def _map_direction(occupied_xy: np.ndarray, ends: np.ndarray, reach: float = 0.15):
    """The direction (mod pi) [rad] of the map's occupied cells within ``reach`` of the
    segment ``ends`` (2, 2) [m], their count and the largest gap along it [m]."""
    start, end = ends
    length = float(np.hypot(*(end - start)))
    along = (end - start) / max(length, 1e-12)
    across = np.array([-along[1], along[0]])
    rel = occupied_xy - start
    t, a = rel @ along, rel @ across
    on = (np.abs(a) <= reach) & (t >= -0.1) & (t <= length + 0.1)
    pts = occupied_xy[on]
    if pts.shape[0] < 5:
        return math.nan, int(pts.shape[0]), math.nan
    centred = pts - pts.mean(axis=0)
    _, vectors = np.linalg.eigh(centred.T @ centred)
    direction = math.atan2(vectors[1, 1], vectors[0, 1]) % math.pi
    ts = np.sort(t[on])
    return direction, int(pts.shape[0]), float(np.diff(ts).max()) if ts.size > 1 else math.nan


def _ate(poses: np.ndarray, truth: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((poses[:, :2] - truth[:, :2]) ** 2, axis=1))))


def probe(family: str, profile: str, seed: int, settings: dict | None = None) -> None:
    """Print the figures of the module docstring."""
    seen: list[tuple[int, list]] = []  # (keyframe, walls accepted in order)
    original = walls_module.WallLandmarks.observe

    def recording(self, keyframe, keyframes, walls):
        seen.append((keyframe, [w for w in walls if w.variance <= walls_module.MAX_WALL_STD ** 2]))
        return original(self, keyframe, keyframes, walls)

    captured = {}

    def on_finish(sim, truth):
        captured["slam"] = sim.robots["r1"].localizer
        captured["truth"] = truth
        from pymunk_bot.maps.rasterize import scenario_grid
        captured["grid"] = scenario_grid(sim.config, 0.05)

    walls_module.WallLandmarks.observe = recording
    try:
        out = run_one("slam_revisit", family, profile, seed,
                      {"wall_landmarks": True, **(settings or {})}, on_finish=on_finish)
    finally:
        walls_module.WallLandmarks.observe = original
    print(out.line())
    slam, truth, grid = captured["slam"], captured["truth"], captured["grid"]
    final = np.asarray(slam.keyframes)[:truth.shape[0]]
    xs, ys = grid.cell_centers()
    occ = grid.occupied()
    rr, cc = np.nonzero(occ)
    occupied_xy = np.column_stack([xs[cc], ys[rr]])
    lm = slam.walls
    walls_of = {k: w for k, w in seen}
    # per observation, in observe's order
    index_in_keyframe: dict[int, int] = {}
    rows = []
    for node, landmark, direction, variance in zip(lm._node, lm._landmark, lm._direction, lm._variance):
        i = index_in_keyframe.get(node, 0)
        index_in_keyframe[node] = i + 1
        wall = walls_of[node][i]
        ends = transform_points(truth[node], wall.ends) if node < truth.shape[0] else None
        rows.append((node, landmark, direction, variance, ends, wall.length))
    shared = [l for l, kf in enumerate(lm._keyframes) if len(kf) > 1]
    print(f"landmarks {len(lm)}, seen again {len(shared)}, observations {lm.observations}")
    for l in shared:
        obs = [r for r in rows if r[1] == l and r[4] is not None]
        if len(obs) < 2:
            continue
        true_dir = np.array([truth[r[0], 2] + r[2] for r in obs])
        mean = 0.5 * math.atan2(np.sin(2 * true_dir).sum(), np.cos(2 * true_dir).sum())
        res = walls_module.half_turn(true_dir - mean)
        all_ends = np.concatenate([r[4] for r in obs])
        along = np.array([math.cos(mean), math.sin(mean)])
        s = all_ends @ along
        whole = np.array([all_ends[np.argmin(s)], all_ends[np.argmax(s)]])
        map_dir, npts, gap = _map_direction(occupied_xy, whole)
        print(f"landmark {l}: {len(obs)} obs, keyframes {obs[0][0]}-{obs[-1][0]}, extent "
              f"{s.min():.1f}..{s.max():.1f} m, from ({whole[0,0]:.1f},{whole[0,1]:.1f}) to "
              f"({whole[1,0]:.1f},{whole[1,1]:.1f}); residual at truth RMS "
              f"{math.degrees(np.sqrt(np.mean(res**2))):.2f} deg, range "
              f"{math.degrees(res.min()):+.2f}..{math.degrees(res.max()):+.2f}; stated std median "
              f"{math.degrees(np.median(np.sqrt([r[3] for r in obs]))):.2f}; map dir - mean "
              f"{math.degrees(walls_module.half_turn(map_dir - mean)):+.2f} deg ({npts} cells, max gap {gap:.2f} m)")
        for r, e in zip(obs, res):
            centre = r[4].mean(axis=0) @ along
            sa, sb = sorted(r[4] @ along)
            md, n, g = _map_direction(occupied_xy, r[4])
            print(f"   kf {r[0]:4d} s {sa:6.2f}..{sb:6.2f} (len {r[5]:.2f})  err {math.degrees(e):+.2f}  "
                  f"std {math.degrees(math.sqrt(r[3])):.2f}  map part - mean "
                  f"{math.degrees(walls_module.half_turn(md - mean)):+.2f} (cells {n}, gap {g:.2f})  "
                  f"final heading err {math.degrees(math.remainder(final[r[0], 2] - truth[r[0], 2], math.tau)):+.2f}")
    # offline: the final graph again
    poses = np.asarray(slam.keyframes)
    n = truth.shape[0]
    factors = lm.factors(poses)
    without, _ = optimize(poses, slam.edges)
    withw, _ = optimize(poses, slam.edges, walls=factors)

    def heading_rms(p):
        return math.degrees(float(np.sqrt(np.mean(walls_module.half_turn(p[:n, 2] - truth[:, 2]) ** 2))))

    print(f"final graph again: no walls ATE {100*_ate(without[:n], truth):.2f} cm heading {heading_rms(without):.2f} deg;"
          f" walls ATE {100*_ate(withw[:n], truth):.2f} cm heading {heading_rms(withw):.2f} deg")
    if factors is None:
        return
    # each observation as a wall that is one straight line would give it: its landmark's
    # mean direction at the true headings, seen from the true heading
    node = np.asarray(lm._node)
    landmark = np.asarray(lm._landmark)
    seen = node < n
    world = truth[np.minimum(node, n - 1), 2] + np.asarray(lm._direction)
    mean = 0.5 * np.arctan2(np.bincount(landmark[seen], np.sin(2 * world[seen]), len(lm)),
                            np.bincount(landmark[seen], np.cos(2 * world[seen]), len(lm)))
    ideal = copy.deepcopy(lm)
    ideal._direction = [float(mean[l] - truth[k, 2]) if k < n else d
                        for k, l, d in zip(lm._node, lm._landmark, lm._direction)]
    p, _ = optimize(poses, slam.edges, walls=ideal.factors(poses))
    print(f"  walls whose observations agree at the truth (each landmark's mean kept): ATE "
          f"{100*_ate(p[:n], truth):.2f} cm heading {heading_rms(p):.2f} deg")
    for l in shared:
        fewer = _without(lm, l)
        p, _ = optimize(poses, slam.edges, walls=fewer.factors(poses))
        print(f"  without landmark {l}: ATE {100*_ate(p[:n], truth):.2f} cm heading {heading_rms(p):.2f} deg")
        only = _without(lm, *[m for m in shared if m != l])
        p, _ = optimize(poses, slam.edges, walls=only.factors(poses))
        print(f"  landmark {l} alone: ATE {100*_ate(p[:n], truth):.2f} cm heading {heading_rms(p):.2f} deg")


def _without(landmarks, *dropped: int):
    """A copy of ``landmarks`` (walls.WallLandmarks) with the landmarks ``dropped`` unseen."""
    out = copy.deepcopy(landmarks)
    keep = [i for i, l in enumerate(out._landmark) if l not in dropped]
    for name in ("_node", "_landmark", "_direction", "_variance"):
        setattr(out, name, [getattr(out, name)[i] for i in keep])
    for l in dropped:
        out._keyframes[l] = set()
    return out


# The wall models the final graph is optimized again with: walls.py's constants that its
# factors read (WALL_VARIANCE_SCALE, WALL_KERNEL), as each variant sets them.
VARIANTS: dict[str, dict[str, float]] = {"walls": {}, "variance_x20": {"WALL_VARIANCE_SCALE": 20.0}}


def offline(family: str, profile: str, seed: int) -> dict:
    """A run with the walls seen but kept out of the graph (the default's run), its final
    graph then optimized again offline: without walls, with one direction per wall, with
    stretches (ATE [cm])."""
    original = walls_module.WallLandmarks.factors
    captured = {}

    def on_finish(sim, truth):
        captured["slam"] = sim.robots["r1"].localizer
        captured["truth"] = truth

    walls_module.WallLandmarks.factors = lambda self, keyframes: None
    try:
        run_one("slam_revisit", family, profile, seed, {"wall_landmarks": True}, on_finish=on_finish)
    finally:
        walls_module.WallLandmarks.factors = original
    slam, truth = captured["slam"], captured["truth"]
    n = truth.shape[0]
    poses = np.asarray(slam.keyframes)
    figures = {"default": 100 * _ate(poses[:n], truth)}
    figures["again"] = 100 * _ate(optimize(poses, slam.edges)[0][:n], truth)
    for name, constants in VARIANTS.items():
        kept = {k: getattr(walls_module, k) for k in constants}
        for k, v in constants.items():
            setattr(walls_module, k, v)
        try:
            factors = slam.walls.factors(poses)
        finally:
            for k, v in kept.items():
                setattr(walls_module, k, v)
        figures[name] = 100 * _ate(optimize(poses, slam.edges, walls=factors)[0][:n], truth)
    return figures


def main(argv: list[str] | None = None) -> None:
    """The command line of the module docstring."""
    args = sys.argv[1:] if argv is None else argv
    settings = {}
    if "--settings" in args:
        i = args.index("--settings")
        settings = json.loads(args[i + 1])
        args = args[:i] + args[i + 2:]
    if "--variants" in args:
        i = args.index("--variants")
        VARIANTS.update(json.loads(args[i + 1]))
        args = args[:i] + args[i + 2:]
    if "--offline" in args:
        args.remove("--offline")
        family, profile = args[0], args[1]
        for seed in range(int(args[2])):
            figures = offline(family, profile, seed)
            print(family, profile, seed, "  ".join(f"{k} {v:.2f}" for k, v in figures.items()), flush=True)
        return
    family, profile, seed = args[0], args[1], int(args[2])
    probe(family, profile, seed, settings)


if __name__ == "__main__":
    main()
