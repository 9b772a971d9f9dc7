"""Replaying SLAM on recorded runs of the localization robustness benchmark.

    python -m bench.slam_replay record [--localizers slam,slam_revisit] [--families depot,...]
        [--profiles typical,uncalibrated] [--seeds N] --out DIR
    python -m bench.slam_replay replay DIR [--settings JSON] [--workers K] [--out results.json]
    python -m bench.slam_replay compare A.json B.json
    e.g. record --localizers slam_revisit --families warehouse --seeds 20 --out rec/, then
    replay rec/ --out base.json, change slam.py, replay rec/ --out new.json, compare base.json
    new.json

Online, a SLAM robot drives on its own estimate: a change to SLAM changes the route it takes,
and two versions' pass counts differ by chance as much as by the change. ``record`` runs the
benchmark's runs (``run_one``, seeds 0..N-1) once and keeps SLAM's input stream of each (every
tick with a fresh LiDAR scan: the time, the odometry, the scan and the robot's true pose), one
file a run, ``{localizer}_{family}_{profile}_{seed}.pkl``, printing the benchmark's line of each.
``replay`` runs SLAM as the code stands now (``--settings``: its config keys overridden) on
exactly those inputs: per run the ATE beside the online one, the keyframes, loop closures,
false closures, the map's precision and pass/FAIL by the benchmark's SLAM criteria (ATE <= 5
cm, map precision >= 0.9, no false closure, slam_revisit: a closure), all but collisions and
reaching the goal, which a replay cannot know; per group (localizer/family/profile) the passes
and the median ATE. ``compare`` sets two ``replay --out`` files side by side per group and
lists the runs whose verdict differs.

A replay is deterministic: the same recording and code give the same figures, and with the
code a recording was made with, exactly the online run's keyframes, ATE, closures and map
(SLAM takes keyframes, and tracks moving returns, only at fresh scans; between them it only
predicts its pose from the odometry, which the next fresh scan predicts anew: slam.py
``update``). A replay takes about 1 s (a depot or clutter run) to 4 s (a warehouse revisiting
tour), without the simulation, physics and navigation. What it cannot show: where a changed
SLAM would have driven the robot (the route is the recorded one); confirm a change online in
the end.

Only the static worlds (FAMILIES): among people the benchmark scores the map against the
walkers' paths, which are not recorded. The recordings are pickles, made for this tool only:
replay only files you or your colleagues recorded (unpickling runs code a file names).
"""
from __future__ import annotations

import argparse
import json
import os
import pickle
import re
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, NoReturn

import numpy as np

from bench.localization_robustness import (FAMILIES, MAX_SEEDS, SLAM_PROFILES, SLAM_RUNS, Outcome,
                                           run_one, score_slam, settings_option)
from pymunk_bot.config.localization import SlamConfig
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.robots.readings import LaserScan, RobotSpec

if TYPE_CHECKING:
    from pymunk_bot.planning.map import MapInfo

MAGIC = "pymunk-bot bench.slam_replay recording"  # the first pickle of every recording file
FORMAT = 1  # bumped when Recording changes incompatibly
ROBOT = "r1"  # the benchmark's one robot
FRESH = 1e-9  # [s] a scan is fresh when taken this near the update's time (as slam.py tests)
NAME = re.compile(r"(?P<localizer>slam|slam_revisit)_(?P<family>[a-z0-9]+)_(?P<profile>[a-z]+)_(?P<seed>\d+)\.pkl")


class RecordingError(ValueError):
    """A file that is not a usable recording (the message names it)."""


class RunFailed(RuntimeError):
    """A run that could not run (``run_one``'s outcome has an error): nothing to record."""

    def __init__(self, outcome: Outcome) -> None:
        super().__init__(outcome.line())
        self.outcome = outcome


@dataclass
class Recording:
    """SLAM's input stream of one benchmark run, and what the online run scored."""

    localizer: str  # slam or slam_revisit
    family: str
    profile: str
    seed: int
    config: SlamConfig  # the run's SLAM config
    robot: RobotSpec  # the localizer context's fields, as the run built them
    start_pose: np.ndarray  # [x, y, theta] [m, m, rad]
    arena: tuple[float, float]  # [m]
    origin: tuple[float, float]  # [m]
    lidar_offset: tuple[float, float, float]  # [m, m, rad]
    times: np.ndarray  # (n,) [s] every tick with a fresh scan
    odometry: np.ndarray  # (n, 3) [m, m, rad] the odometry's pose at those ticks
    scans: list[LaserScan]  # (n) the fresh scans
    # (n, 3) [m, m, rad] the true pose at those ticks, as the benchmark reads it (_InputRecorder)
    truth: np.ndarray
    true_map: MapInfo  # the scenario's fixed obstacles, for the map's precision
    online: Outcome  # the online run's figures
    online_keyframes: np.ndarray  # (k, 3) [m, m, rad] SLAM's final keyframe poses online

    @property
    def name(self) -> str:
        return f"{self.localizer}_{self.family}_{self.profile}_{self.seed}"


@dataclass
class ReplayResult:
    """One replay's figures (JSON-ready: ``asdict``)."""

    localizer: str
    family: str
    profile: str
    seed: int
    keyframes: int
    keyframes_online: int
    ate: float  # [m] RMSE of the final keyframe positions against the truth, as the benchmark's
    ate_online: float  # [m] the online run's
    closures: int  # accepted loop closures
    closures_rejected: int  # candidates whose verification failed
    false_closures: int  # accepted closures off the truth (metrics.false_closures)
    map_precision: float  # share of the built map's occupied cells on the true map
    passed: bool  # the benchmark's SLAM criteria, collisions and the goal left out
    passed_online: bool  # the online run's verdict (collisions included)
    seconds: float  # [s] wall time of the replay

    @property
    def group(self) -> str:
        return f"{self.localizer}/{self.family}/{self.profile}"

    def line(self) -> str:
        return (f"{'ok  ' if self.passed else 'FAIL'} {self.localizer:12s} {self.family:10s} "
                f"{self.profile:12s} seed {self.seed:2d}: ATE {100 * self.ate:.2f} cm (online "
                f"{100 * self.ate_online:.2f} cm), {self.keyframes} keyframes (online "
                f"{self.keyframes_online}), loop closures {self.closures} ({self.false_closures} "
                f"false, {self.closures_rejected} rejected), map precision "
                f"{self.map_precision:.3f}, {self.seconds:.1f} s")


# ---------------------------------------------------------------------- recording
class _InputRecorder:
    """A simulation observer: after every tick the robot's odometry, scan and true pose, when
    the scan is fresh; ``attach`` calls ``on_reset`` first, for the update the simulation
    makes as it is built (t = 0). An observer runs after the localizers in the same tick with
    nothing moved in between, so it reads exactly the inputs SLAM was given, and the true
    pose at the scan's time, as run_one reads each keyframe's."""

    def __init__(self) -> None:
        self.times: list[float] = []
        self.odometry: list[np.ndarray] = []
        self.scans: list[LaserScan] = []
        self.truth: list[np.ndarray] = []

    def on_reset(self, sim: Any) -> None:
        for rows in (self.times, self.odometry, self.scans, self.truth):
            rows.clear()
        self._read(sim)

    def __call__(self, sim: Any) -> None:
        self._read(sim)

    def _read(self, sim: Any) -> None:
        robot = sim.robots[ROBOT]
        lidar = robot.sensor("lidar")
        scan = lidar.latest if lidar is not None else None
        now = sim.time
        if scan is None or abs(scan.time - now) >= FRESH:
            return
        self.times.append(now)
        self.odometry.append(np.array(robot.odometry.pose, dtype=float))
        self.scans.append(scan)
        self.truth.append(np.array(robot.pose, dtype=float))


def record_run(localizer: str, family: str, profile: str, seed: int) -> Recording | None:
    """Run the benchmark's run (``run_one``: ``localizer`` slam or slam_revisit, a static
    ``family``, a SLAM ``profile``) and record SLAM's input stream; None when the world is
    unavailable (the warehouse map absent). ValueError for a name the benchmark has no run
    of; RunFailed when the run could not run."""
    from pymunk_bot.localization.slam import SlamLocalizer

    _check_choice("localizer", localizer, SLAM_RUNS)
    _check_choice("family", family, FAMILIES)
    _check_choice("profile", profile, SLAM_PROFILES)
    recorder = _InputRecorder()
    ends: dict[str, Any] = {}

    def finished(sim: Any, keyframe_truth: np.ndarray) -> None:
        from pymunk_bot.planning.map import MapInfo

        # what scenario_grid rasterizes (a ScenarioConfig's class is built at run time: it
        # does not pickle)
        ends["slam"] = sim.robots[ROBOT].localizer
        ends["true_map"] = MapInfo.from_scenario(sim.config).without_movable()

    out = run_one(localizer, family, profile, seed, on_finish=finished,
                  on_start=lambda sim: sim.attach(recorder))
    if out is None:
        return None
    if out.error:
        raise RunFailed(out)
    slam = ends["slam"]
    assert isinstance(slam, SlamLocalizer)
    c = slam.context
    recording = Recording(
        localizer, family, profile, seed, slam.config, c.robot,
        np.array(c.start_pose, dtype=float), c.arena, c.origin, c.lidar_offset,
        np.array(recorder.times, dtype=float), np.array(recorder.odometry, dtype=float).reshape(-1, 3),
        recorder.scans, np.array(recorder.truth, dtype=float).reshape(-1, 3), ends["true_map"], out,
        np.array(slam.keyframes, dtype=float).reshape(-1, 3))
    return recording


def save(recording: Recording, directory: str | Path) -> Path:
    """Write ``recording`` into ``directory`` (atomically) as ``{name}.pkl``; its path."""
    from pymunk_bot.outcomes.results import write_atomic

    path = Path(directory) / f"{recording.name}.pkl"
    header = {"magic": MAGIC, "format": FORMAT, "name": recording.name}
    write_atomic(path, pickle.dumps(header, protocol=pickle.HIGHEST_PROTOCOL)
                 + pickle.dumps(recording, protocol=pickle.HIGHEST_PROTOCOL))
    return path


def check_header(path: str | Path) -> str:
    """The recording name in the header of the file at ``path`` (a cheap check, the stream is
    not read); RecordingError if it is not one of this tool's recordings."""
    try:
        with open(path, "rb") as f:
            header = pickle.load(f)
    except Exception as exc:  # anything unpickling a stranger's file raises
        raise RecordingError(f"{path}: not a slam_replay recording ({type(exc).__name__})") from None
    if not (isinstance(header, dict) and header.get("magic") == MAGIC):
        raise RecordingError(f"{path}: not a slam_replay recording")
    if header.get("format") != FORMAT:
        raise RecordingError(f"{path}: a recording of format {header.get('format')}, this tool "
                             f"reads {FORMAT}: record it again")
    return str(header.get("name"))


def load(path: str | Path) -> Recording:
    """The recording in the file at ``path``; RecordingError if it is not one."""
    check_header(path)
    try:
        with open(path, "rb") as f:
            pickle.load(f)  # the header
            recording = pickle.load(f)
    except Exception as exc:
        raise RecordingError(f"{path}: a damaged recording ({type(exc).__name__}: {exc})"
                             .splitlines()[0]) from None
    if not isinstance(recording, Recording):
        raise RecordingError(f"{path}: not a slam_replay recording")
    return recording


# ---------------------------------------------------------------------- replaying
def slam_config(base: SlamConfig, settings: dict | None) -> SlamConfig:
    """``base`` with ``settings`` (SLAM config keys) over it, validated; ValueError (one line)
    for an unknown key or a value out of bounds."""
    from pydantic import ValidationError

    if not settings:
        return base
    unknown = sorted(set(settings) - set(SlamConfig.model_fields))
    if unknown:
        raise ValueError(f"unknown SLAM key(s) {', '.join(unknown)}; valid: "
                         f"{', '.join(k for k in SlamConfig.model_fields if k != 'type')}")
    try:
        return SlamConfig.model_validate({**base.model_dump(), **settings})
    except ValidationError as exc:
        first = exc.errors()[0]
        raise ValueError(f"{'.'.join(map(str, first['loc']))}: {first['msg']}") from None


def replay(recording: Recording, settings: dict | None = None) -> ReplayResult:
    """SLAM, as the code stands, on ``recording``'s input stream (``settings``: SLAM config
    keys over the recorded config), scored as the benchmark scores a SLAM run."""
    from pymunk_bot.localization.base import LocalizerContext, LocalizerInputs
    from pymunk_bot.localization.metrics import map_scores
    from pymunk_bot.localization.slam import SlamLocalizer
    from pymunk_bot.maps.rasterize import grid_from_map

    r = recording
    started = time.perf_counter()
    # SLAM draws no random numbers: the stream only fills the context.
    context = LocalizerContext(robot=r.robot, start_pose=r.start_pose.copy(),
                               rng=np.random.default_rng(0), arena=r.arena, origin=r.origin,
                               lidar_offset=r.lidar_offset)
    slam = SlamLocalizer(slam_config(r.config, settings), context)
    at_keyframes: list[np.ndarray] = []  # the true pose at each keyframe
    for now, odometry, scan, truth in zip(r.times, r.odometry, r.scans, r.truth):
        slam.update(LocalizerInputs(float(now), odometry, scan))
        while len(at_keyframes) < len(slam.keyframes):
            at_keyframes.append(truth)
    built: OccupancyGrid = slam.grid
    # The benchmark's own scoring and verdict, on an outcome without a collision; the map as
    # its _score_map scores it in a world without people (scenario_grid's raster)
    scored = Outcome(r.localizer, r.family, r.profile, r.seed,
                     map_precision=map_scores(built, grid_from_map(r.true_map, built.resolution))["precision"])
    score_slam(scored, slam, np.asarray(at_keyframes))
    return ReplayResult(r.localizer, r.family, r.profile, r.seed, len(slam.keyframes),
                        r.online_keyframes.shape[0], scored.ate, r.online.ate, scored.closures,
                        scored.closures_rejected, scored.false_closures,
                        float(scored.map_precision), scored.success, r.online.success,
                        time.perf_counter() - started)


def _replay_file(job: tuple[str, dict | None]) -> ReplayResult | str:
    """A worker's job: the replay of the recording at ``job[0]``, or the problem with it."""
    path, settings = job
    try:
        return replay(load(path), settings)
    except RecordingError as exc:
        return str(exc)


def recordings_in(directory: str | Path) -> list[Path]:
    """The recordings (``*.pkl``) in ``directory``, by localizer, family, profile and seed,
    each header checked; RecordingError when there is none or one is not a recording."""
    folder = Path(directory)
    if not folder.is_dir():
        raise RecordingError(f"{directory}: {'not a' if folder.exists() else 'no such'} directory")
    paths = list(folder.glob("*.pkl"))
    if not paths:
        raise RecordingError(f"{directory}: no recordings (*.pkl) in it")

    def order(path: Path) -> tuple:
        found = NAME.fullmatch(path.name)
        return (0, found["localizer"], found["family"], found["profile"], int(found["seed"])) \
            if found else (1, path.name, "", "", 0)

    paths.sort(key=order)
    for path in paths:
        check_header(path)
    return paths


def summary_lines(results: list[ReplayResult]) -> list[str]:
    """Per group (localizer/family/profile): passes of runs and the median ATE."""
    lines = []
    for group, runs in _groups(results).items():
        lines.append(f"{group}: {sum(r.passed for r in runs)}/{len(runs)} pass, median ATE "
                     f"{100 * float(np.median([r.ate for r in runs])):.2f} cm")
    return lines


def _groups(results: list[ReplayResult]) -> dict[str, list[ReplayResult]]:
    groups: dict[str, list[ReplayResult]] = {}
    for r in results:
        groups.setdefault(r.group, []).append(r)
    return groups


# ---------------------------------------------------------------------- command line
def _refuse(problem: str) -> NoReturn:
    """One line on stderr, exit status 2."""
    print(f"slam_replay: {problem}", file=sys.stderr)
    raise SystemExit(2)


class _Parser(argparse.ArgumentParser):
    """Bad arguments: one line (``_refuse``), not argparse's usage block."""

    def error(self, message: str) -> NoReturn:
        command = self.prog.split()[1:]  # a subcommand's parser: "slam_replay record"
        _refuse(f"{command[0]}: {message}" if command else message)


def _names(parser: argparse.ArgumentParser, option: str, text: str, valid: tuple[str, ...]) -> list[str]:
    names = [n for n in text.split(",") if n]
    bad = [n for n in names if n not in valid]
    if bad or not names:
        parser.error(f"{option}: unknown {', '.join(bad) or 'empty list'}; valid: {', '.join(valid)}")
    return names


def _check_choice(what: str, name: str, valid: tuple[str, ...]) -> None:
    if name not in valid:
        raise ValueError(f"unknown {what} {name}; valid: {', '.join(valid)}")


def _record(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    localizers = _names(parser, "--localizers", args.localizers, SLAM_RUNS)
    families = _names(parser, "--families", args.families, FAMILIES)
    profiles = _names(parser, "--profiles", args.profiles, SLAM_PROFILES)
    if not 1 <= args.seeds <= MAX_SEEDS:
        parser.error(f"--seeds must be 1..{MAX_SEEDS} (got {args.seeds})")
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        parser.error(f"--out {out}: {exc.strerror}")
    failed = 0
    for localizer in localizers:
        for family in families:
            for profile in profiles:
                for seed in range(args.seeds):
                    try:
                        recording = record_run(localizer, family, profile, seed)
                    except RunFailed as exc:
                        failed += 1
                        print(f"FAIL {exc} (not recorded)", flush=True)
                        continue
                    if recording is None:
                        print(f"skip {localizer} {family} {profile} seed {seed}: the world is "
                              f"not here", flush=True)
                        continue
                    try:
                        path = save(recording, out)
                    except OSError as exc:
                        _refuse(str(exc))
                    online = recording.online
                    print(f"{'ok   ' if online.success else 'FAIL '}{online.line()} -> {path}",
                          flush=True)
    return 1 if failed else 0


def _replay(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    settings = settings_option(parser, args.settings, "SLAM")
    try:
        slam_config(SlamConfig(), settings)  # a bad key refused before anything runs
    except ValueError as exc:
        parser.error(f"--settings: {exc}")
    if not 1 <= args.workers <= (os.cpu_count() or 1) * 4:
        parser.error(f"--workers must be 1..{(os.cpu_count() or 1) * 4} (got {args.workers})")
    try:
        paths = recordings_in(args.directory)
    except RecordingError as exc:
        _refuse(str(exc))
    jobs = [(str(p), settings or None) for p in paths]
    results: list[ReplayResult] = []
    if args.workers == 1:
        answers: Iterator[ReplayResult | str] = map(_replay_file, jobs)
        pool = None
    else:
        import multiprocessing

        pool = multiprocessing.Pool(min(args.workers, len(jobs)))
        answers = pool.imap(_replay_file, jobs)  # in order, as they finish
    try:
        for answer in answers:
            if isinstance(answer, str):
                _refuse(answer)
            results.append(answer)
            print(answer.line(), flush=True)
    finally:
        if pool is not None:
            pool.terminate()
    for line in summary_lines(results):
        print(line)
    if args.out:
        from pymunk_bot.outcomes.results import write_json
        try:
            write_json(args.out, {"settings": settings, "runs": [asdict(r) for r in results]})
        except OSError as exc:
            _refuse(str(exc))
    return 0


def read_results(path: str | Path) -> list[ReplayResult]:
    """The runs of a ``replay --out`` file; ValueError (one line) if it is not one."""
    try:
        data = json.loads(Path(path).read_text())
    except OSError as exc:
        raise ValueError(f"{path}: {exc.strerror}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not JSON ({exc})") from None
    try:
        runs = [ReplayResult(**run) for run in data["runs"]]
        for run in runs:  # the figures compare_lines formats
            float(run.ate), int(run.seed), int(run.closures), int(run.false_closures)
    except (TypeError, KeyError, ValueError):
        raise ValueError(f"{path}: not a slam_replay result (replay --out)") from None
    return runs


def compare_lines(a: list[ReplayResult], b: list[ReplayResult]) -> list[str]:
    """Per group, passes and median ATE of ``a`` and ``b`` side by side; then the runs whose
    verdict differs, and the runs only one of them has."""
    ga, gb = _groups(a), _groups(b)
    lines = [f"{'group':36s} {'A passes':>9s} {'A median ATE':>13s}   {'B passes':>9s} "
             f"{'B median ATE':>13s}"]
    for group in sorted(set(ga) | set(gb)):
        cells = []
        for runs in (ga.get(group, []), gb.get(group, [])):
            cells.append((f"{sum(r.passed for r in runs)}/{len(runs)}",
                          f"{100 * float(np.median([r.ate for r in runs])):.2f} cm" if runs else "-"))
        lines.append(f"{group:36s} {cells[0][0]:>9s} {cells[0][1]:>13s}   {cells[1][0]:>9s} "
                     f"{cells[1][1]:>13s}")
    ka, kb = {_run_key(r): r for r in a}, {_run_key(r): r for r in b}
    for k in sorted(set(ka) & set(kb)):
        ra, rb = ka[k], kb[k]
        if ra.passed != rb.passed:
            lines.append(f"differs: {ra.localizer} {ra.family} {ra.profile} seed {ra.seed}: "
                         f"A {'ok' if ra.passed else 'FAIL'} (ATE {100 * ra.ate:.2f} cm, "
                         f"{ra.closures} closures, {ra.false_closures} false), B "
                         f"{'ok' if rb.passed else 'FAIL'} (ATE {100 * rb.ate:.2f} cm, "
                         f"{rb.closures} closures, {rb.false_closures} false)")
    for side, only in (("A", set(ka) - set(kb)), ("B", set(kb) - set(ka))):
        if only:
            lines.append(f"only in {side}: {len(only)} run(s), e.g. "
                         f"{' '.join(map(str, sorted(only)[0]))}")
    return lines


def _run_key(r: ReplayResult) -> tuple[str, str, str, int]:
    return (r.localizer, r.family, r.profile, r.seed)


def _compare(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    try:
        a, b = read_results(args.a), read_results(args.b)
    except ValueError as exc:
        _refuse(str(exc))
    for line in compare_lines(a, b):
        print(line)
    return 0


def main(argv: list[str] | None = None) -> int:
    """The command line: ``python -m bench.slam_replay record|replay|compare ...``."""
    parser = _Parser(prog="slam_replay", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    rec = commands.add_parser("record", help="run benchmark runs and record SLAM's inputs")
    rec.add_argument("--localizers", default=",".join(SLAM_RUNS))
    rec.add_argument("--families", default=",".join(FAMILIES))
    rec.add_argument("--profiles", default=",".join(SLAM_PROFILES))
    rec.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 per world and profile")
    rec.add_argument("--out", required=True, metavar="DIR", help="one .pkl per run written here")
    rep = commands.add_parser("replay", help="replay SLAM on every recording in DIR")
    rep.add_argument("directory", metavar="DIR")
    rep.add_argument("--settings", default="{}", metavar="JSON",
                     help='SLAM config keys over the recorded ones, e.g. \'{"keyframe_d": 0.3}\'')
    rep.add_argument("--workers", type=int, default=1, help="replays at once (processes)")
    rep.add_argument("--out", metavar="JSON", help="write every run's figures here")
    cmp = commands.add_parser("compare", help="two replay --out files side by side")
    cmp.add_argument("a", metavar="A.json")
    cmp.add_argument("b", metavar="B.json")
    args = parser.parse_args(argv)
    command = {"record": _record, "replay": _replay, "compare": _compare}[args.command]
    sub = {"record": rec, "replay": rep, "compare": cmp}[args.command]
    return command(sub, args)


if __name__ == "__main__":
    # Through the module's importable name, not __main__: recordings pickle Recording, and
    # a file must name a class that bench.slam_replay (tests, other tools, workers) can load.
    from bench.slam_replay import main as _main
    raise SystemExit(_main())
