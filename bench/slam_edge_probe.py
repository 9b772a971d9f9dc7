"""Are SLAM's chain edges as sure as they say? Revisiting runs of the robustness benchmark
(issue 36).

    python -m bench.slam_edge_probe FAMILY PROFILE SEED [SEED ...]
    e.g. python -m bench.slam_edge_probe warehouse uncalibrated 1 5 12 16

For every chain edge (keyframe to keyframe, not loop closures) at the end of each run: its
error, the measured step minus the true one in the new keyframe's frame (along the robot's
heading, across it, and the heading), against the std the edge states, both the scan match's
own and with slam.EDGE_FLOOR added. An honest std gives an RMS of error over std near 1;
far below 1 the edge is looser than its match is.
"""
from __future__ import annotations

import json
import sys
from typing import NoReturn

import numpy as np

from bench.localization_robustness import FAMILIES, MAX_SEEDS, run_one
from pymunk_bot.localization.se2 import between, wrap

MAX_RUNS = 20  # seeds per call (each run is a few CPU seconds)


def _refuse(problem: str) -> NoReturn:
    """One line on stderr, exit status 2."""
    print(f"slam_edge_probe: {problem}", file=sys.stderr)
    raise SystemExit(2)


def chain_edge_errors(family: str, profile: str, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Of one revisiting run's chain edges: their errors (n, 3) [m, m, rad] (along, across,
    heading, in the new keyframe's frame) and the information they hold (n, 3, 3)."""
    from pymunk_bot.localization.slam import SlamLocalizer

    got: dict = {}
    out = run_one("slam_revisit", family, profile, seed,
                  on_finish=lambda sim, truth: got.update(slam=sim.robots["r1"].localizer, truth=truth))
    if out is None:
        _refuse(f"the {family} map is not here")
    slam, truth = got["slam"], got["truth"]
    assert isinstance(slam, SlamLocalizer)
    errors, information = [], []
    for edge in slam.edges:
        if edge.robust > 0.0 or edge.j >= truth.shape[0]:
            continue  # a loop closure, or a keyframe after the tour's end
        error = np.asarray(edge.z, dtype=float) - between(truth[edge.i], truth[edge.j])
        c, s = np.cos(edge.z[2]), np.sin(edge.z[2])  # i's frame -> j's, as posegraph.edge_terms
        errors.append([c * error[0] + s * error[1], -s * error[0] + c * error[1], wrap(error[2])])
        information.append(edge.information)
    return np.array(errors).reshape(-1, 3), np.array(information).reshape(-1, 3, 3)


def probe(family: str, profile: str, seeds: list[int]) -> dict[str, object]:
    """The summary over the runs' chain edges ([mm] and [deg])."""
    from pymunk_bot.localization.slam import EDGE_FLOOR

    runs = [chain_edge_errors(family, profile, seed) for seed in seeds]
    errors = np.concatenate([e for e, _ in runs])
    if not errors.shape[0]:
        _refuse(f"{family} {profile} seeds {seeds}: no chain edge")
    stated = np.linalg.inv(np.concatenate([i for _, i in runs]))  # with the floor, j's frame
    # The floor's position part is the same every way, so it comes off in any frame.
    own = np.sqrt(np.maximum(np.diagonal(stated - EDGE_FLOOR, axis1=1, axis2=2), 1e-18))
    floored = np.sqrt(np.diagonal(stated, axis1=1, axis2=2))
    scale = np.array([1000.0, 1000.0, np.degrees(1.0)])

    def three(values: np.ndarray) -> list[float]:
        return [round(float(v), 3) for v in values]

    return {"edges": int(errors.shape[0]), "floor_mm_mm_deg": three(np.sqrt(np.diag(EDGE_FLOOR)) * scale),
            "error_rms_mm_mm_deg": three(np.sqrt(np.mean(errors ** 2, axis=0)) * scale),
            "own_std_median_mm_mm_deg": three(np.median(own, axis=0) * scale),
            "floored_std_median_mm_mm_deg": three(np.median(floored, axis=0) * scale),
            "error_over_own_std_rms": three(np.sqrt(np.mean((errors / own) ** 2, axis=0))),
            "error_over_floored_std_rms": three(np.sqrt(np.mean((errors / floored) ** 2, axis=0)))}


def main(argv: list[str] | None = None) -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("family", choices=FAMILIES)
    parser.add_argument("profile", choices=("perfect", "typical", "uncalibrated"))
    parser.add_argument("seeds", type=int, nargs="+")
    args = parser.parse_args(argv)
    if len(args.seeds) > MAX_RUNS:
        parser.error(f"at most {MAX_RUNS} seeds (got {len(args.seeds)})")
    bad = [s for s in args.seeds if not 0 <= s < MAX_SEEDS]
    if bad:
        parser.error(f"seeds must be 0..{MAX_SEEDS - 1} (got {bad})")
    print(json.dumps(probe(args.family, args.profile, args.seeds)))


if __name__ == "__main__":
    main()
