"""Speed benchmarks (`pymunk-bot bench [--quick] [--only NAME]`): ratios measured in one run,
in CPU time where two things are compared, never timed unit tests.

Each section prints its figures, then one line per target: PASS, MISS, or SKIP (with why). A
section that fails outright is reported as ERROR and the others still run.
"""
from __future__ import annotations

import importlib.util
import time
import traceback
from typing import Callable

Verdict = tuple[str, "bool | None"]  # (target, passed; None: skipped or informational)


def _simulation(quick: bool) -> list[Verdict]:
    from bench import simulation
    print("60 s of simulated time, median of repeats (CPU time)")
    rows = simulation.main(repeats=2 if quick else 5)[:2]  # one robot, no sensors: two worlds
    return [(f"{r['case']}, no sensors: <= {simulation.TARGET_RATIO:g}x the CPU of a bare pymunk "
             f"loop doing the same physics (got {r['overhead']:.2f}x)",
             r["overhead"] <= simulation.TARGET_RATIO) for r in rows]


def _lidar(quick: bool) -> list[Verdict]:
    from bench import lidar
    print("microseconds per ray, 360-beam scans: RayCaster against segment_query_first")
    rows = lidar.main()
    worst = min(rows, key=lambda r: r["speedup"])
    return [(f"LiDAR: >= {lidar.TARGET:g}x segment_query_first in every world (least "
             f"{worst['speedup']:.1f}x, {worst['world']})", worst["speedup"] >= lidar.TARGET),
            ("LiDAR: identical to segment_query_first (largest difference "
             f"{max(r['max_abs_diff_m'] for r in rows):.1e} m)",
             all(r["max_abs_diff_m"] == 0.0 for r in rows))]


def _movers(quick: bool) -> list[Verdict]:
    from bench import movers
    print("pedestrians and scripted obstacles: microseconds per step (one LiDAR robot)")
    movers.main(repeats=1 if quick else 3)
    return []


def _contacts(quick: bool) -> list[Verdict]:
    from bench import contacts
    verdicts: list[Verdict] = []
    for every, slower in ((False, False), (True, False), (False, True)):
        summary = contacts.main(100 if quick else 1000, every=every, slower=slower)
        how = ", every substep" if every else ", below top speed" if slower else ""
        verdicts += [(f"{summary.trials} trials{how}: 0 crossings", summary.crossings == 0),
                     (f"{summary.trials} trials{how}: penetration <= 1 cm",
                      summary.max_penetration <= 0.01)]
    return verdicts


def _fleet(quick: bool) -> list[Verdict]:
    from bench import fleet
    result = fleet.run(quick)
    fleet.report(result)
    o = result["overhead_1000"]
    verdicts = [(f"1000 robots, no sensors: <= {o['target']:g}x bare space.step "
                 f"(got {o['ratio']:.1f}x)", o["passed"])]
    for key in ("lidar32_1000", "lidar360_100"):
        r = result[key]
        verdicts.append((f"{r['robots']} robots, {r['beams']}-beam LiDAR: >= {r['target']:g}x the "
                         f"speed of a hand-written loop on the same Space (got "
                         f"{r['speed_ratio']:.2f}x; {r['real_time_factor']:.2f}x real time)",
                         r["passed"]))
    b, r = result["build_10000"], result["swarm_10000"]
    verdicts += [(f"10,000 robots: built in <= {b['build_target']:.2f}x the CPU of building them "
                  f"by hand (got {b['build_ratio']:.2f}x, {b['build_cpu_s']:.1f} s)",
                  b["build_passed"]),
                 (f"10,000 robots, no sensors, from t = {r['from_s']:g} s: >= {r['target']:g}x the "
                  f"speed of the bare step (got {r['speed_ratio']:.2f}x; "
                  f"{r['real_time_factor']:.2f}x real time)", r["passed"])]
    return verdicts


def _learning_loop(quick: bool) -> list[Verdict]:
    from bench import learning_loop
    result = learning_loop.run(quick)
    learning_loop.report(result)
    target = result["target"]
    return [(f"learning loop, random commands: >= {target:g}x bare pymunk (got "
             f"{result['ratio']:.2f}x)", result["passed"])]


def _irsim(quick: bool) -> list[Verdict]:
    from bench import irsim
    result = irsim.run(quick)
    irsim.report(result)
    target = f"10 robots x 360 beams: >= {irsim.TARGET:g}x IR-SIM {irsim.IRSIM_VERSION}"
    if "skipped" in result:
        return [(f"{target} (skipped: {result['skipped']})", None)]
    return [(f"{target} (got {result['ratio']:.1f}x)", result["passed"])]


def _crowds(quick: bool) -> list[Verdict]:
    from bench import crowds
    print("crowd navigation: a LiDAR robot among pedestrians, the pedestrian policies, and a "
          "1,000-episode benchmark (estimated from a sample, CPU time)")
    result = crowds.main(quick=True)  # under a minute; `python -m ...crowds` for the full sample
    env, episodes = result["env"], result["episodes"]
    return [(f"1 robot, 360-beam LiDAR, 20 pedestrians: >= {crowds.ENV_TARGET:g}x the env steps "
             f"per CPU second of the same scene by hand on bare pymunk (got {env['ratio']:.2f}x)",
             env["ratio"] >= crowds.ENV_TARGET),
            (f"{crowds.EPISODES} 30 s episodes: an average one <= {crowds.EPISODE_TARGET:g}x the "
             f"CPU of 30 s of that loop (got {episodes['ratio']:.2f}x; about "
             f"{episodes['estimate_s']:.0f} s on {crowds.CORES} cores here)",
             episodes["ratio"] <= crowds.EPISODE_TARGET)]


def _maps(quick: bool) -> list[Verdict]:
    from bench import maps
    print("build time; LiDAR on a map world vs the same world as boxes")
    maps.main(quick=quick)
    return []


def _localization(quick: bool) -> list[Verdict]:
    from bench import localization
    result = localization.run_all(quick=True)  # the full run (10 seeds) is its own command
    verdicts: list[Verdict] = []
    for world in ("office", "ros_map"):
        mcl, glob = result[world]["mcl"], result[world]["global"]
        print(f"  {world}: mcl rmse {mcl['rmse']['worst'] * 100:.1f} cm, heading "
              f"{mcl['heading_rmse_deg']['worst']:.2f} deg; global localization "
              f"{glob['time_to_localize']['worst']:.1f} s; ekf rmse "
              f"{result[world]['ekf']['rmse']['worst'] * 100:.1f} cm; slam ATE "
              f"{result[world]['slam']['ate_rmse']['worst'] * 100:.1f} cm "
              f"(worst of {result['seeds']} seeds)")
        verdicts += [(f"{world}: mcl rmse <= 5 cm", mcl["rmse"]["worst"] <= 0.05),
                     (f"{world}: mcl heading rmse <= 2 deg", mcl["heading_rmse_deg"]["worst"] <= 2.0),
                     (f"{world}: global localization <= 15 s",
                      glob["time_to_localize"]["worst"] <= 15.0)]
    print("  mcl update: " + ", ".join(f"{n} particles {ms:.1f} ms"
                                       for n, ms in result["mcl_update_ms"].items()))
    return verdicts


def _localization_robustness(quick: bool) -> list[Verdict]:
    from bench import localization_robustness as robustness
    seeds = robustness.QUICK_SEEDS if quick else 10
    print(f"defaults on unseen worlds: mcl, ekf, global mcl, kidnapped mcl, slam, slam on revisiting "
          f"tours (loop closures); generated "
          f"offices, clutter, the warehouse map; {seeds} seeds; failures listed")
    outcomes = robustness.run(seeds=seeds, verbose=False)
    for key, row in robustness.summary(outcomes).items():
        print(f"  {key}: {row}")
    return robustness.verdicts(outcomes)


def _learning(quick: bool) -> list[Verdict]:
    if importlib.util.find_spec("gymnasium") is None:
        return [("learning environments (skipped: gymnasium is not installed; "
                 "pip install 'pymunk-bot[rl]')", None)]
    from bench import learning
    result = learning.run(quick)
    verdicts: list[Verdict] = [
        (f"one env: >= {learning.ENV_TARGET:g}x bare pymunk (got {result['env_ratio']:.2f}x)",
         result["env_ratio"] >= learning.ENV_TARGET),
        (f"16 envs as a vector env: >= {learning.VECTOR_TARGET:g}x 16 separate envs "
         f"(got {result['vector_16_ratio']:.2f}x)",
         result["vector_16_ratio"] >= learning.VECTOR_TARGET),
        (f"16 envs as a vector env, random actions: >= {learning.VECTOR_RATE_RATIO:.2f}x the "
         f"env steps per CPU second of one env's loop on bare pymunk (got "
         f"{result['vector_16_random_rate_ratio']:.2f}x, {result['vector_16_random_rate']:,.0f} "
         "env steps/s)",
         result["vector_16_random_rate_ratio"] >= learning.VECTOR_RATE_RATIO)]
    if "process_scaling" in result:
        verdicts.append((f"process sweep, 2 workers: >= {learning.SCALING_TARGET:g}x serial (got "
                         f"{result['process_scaling']:.2f}x)",
                         result["process_scaling"] >= learning.SCALING_TARGET))
    return verdicts


def _fuzz(quick: bool) -> list[Verdict]:
    from bench import fuzz
    files = 30 if quick else 1000
    counts = fuzz.fuzz(files=files)
    bad = {k: sum(c[k] for c in counts.values()) for k in ("traceback", "hang", "bad-message")}
    for command, counter in counts.items():
        print(f"  {command:<8} ok {counter['ok']}, exit-2 {counter['exit-2']}, "
              f"bad message {counter['bad-message']}, tracebacks {counter['traceback']}, "
              f"hangs {counter['hang']}")
    return [(f"{files} mutated scenarios: 0 tracebacks, 0 hangs, 0 bad messages", not any(bad.values()))]


# name -> (title, section); the order they run in (names.py lists the names for the CLI)
SECTIONS: dict[str, tuple[str, Callable[[bool], list[Verdict]]]] = {
    "simulation": ("Simulation speed", _simulation),
    "lidar": ("LiDAR ray casting", _lidar),
    "contacts": ("Contacts that hold", _contacts),
    "fleet": ("Swarms", _fleet),
    "learning_loop": ("Learning loop against bare pymunk", _learning_loop),
    "irsim": ("Against IR-SIM", _irsim),
    "movers": ("Pedestrians and scripted obstacles", _movers),
    "crowds": ("Crowd navigation", _crowds),
    "maps": ("Maps", _maps),
    "localization": ("Localization (quick)", _localization),
    "localization_robustness": ("Localization with defaults on unseen worlds",
                                _localization_robustness),
    "learning": ("Learning environments and sweeps", _learning),
    "fuzz": ("Fuzzing the command line", _fuzz),
}


def _mark(passed: bool | None) -> str:
    return "SKIP" if passed is None else ("PASS" if passed else "MISS")


def run_all(quick: bool = False, only: list[str] | None = None) -> dict[str, list[Verdict]]:
    """Run the sections (``only``: these names), print each with its targets; returns the
    verdicts by section."""
    unknown = sorted(set(only or []) - set(SECTIONS))
    if unknown:
        raise ValueError(f"unknown bench section(s) {', '.join(unknown)}; "
                         f"valid: {', '.join(SECTIONS)}")
    verdicts: dict[str, list[Verdict]] = {}
    for name, (title, section) in SECTIONS.items():
        if only and name not in only:
            continue
        print(f"== {title} [{name}]")
        started = time.perf_counter()
        try:
            verdicts[name] = section(quick)
        except Exception as exc:  # one broken section must not hide the others' figures
            traceback.print_exc()
            verdicts[name] = [(f"section failed: {type(exc).__name__}: {exc}", False)]
        for target, passed in verdicts[name]:
            print(f"  {_mark(passed)}  {target}")
        print(f"  ({time.perf_counter() - started:.0f} s)\n")
    print("== Summary")
    for name, rows in verdicts.items():
        for target, passed in rows:
            print(f"  {_mark(passed)}  [{name}] {target}")
    return verdicts
