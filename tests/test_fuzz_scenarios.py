"""Every class of bad input gets exit 2 and one line naming the file, the key path and the
problem: no traceback, no hang, no silent success (issue 9). Hand-written cases of each class,
hypothesis over values, a few real subprocesses, and the large seeded run (slow)."""
from __future__ import annotations

import copy
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from bounds import HANG_GUARD, children_cpu
from hypothesis import strategies as st

from pymunk_bot.cli import main

REPO = Path(__file__).resolve().parent.parent
BASE = {
    "name": "fuzz",
    "world": {"size": [10.0, 6.0], "duration": 2.0},
    "obstacles": [{"type": "box", "center": [5.0, 3.0], "size": [1.0, 1.0]}],
    "robots": [{"name": "r1", "pose": [1.0, 3.0, 0.0], "lidar": {"beams": 36},
                "controller": {"type": "go_to_goal"}, "goal": {"position": [9.0, 5.0]}}],
    "expect": {"r1": {"goal_reached": True}},
}
TIME_BOUND = 3.0  # [s] per bad file, validation and all


def edited(**changes) -> dict:
    """BASE with changes given as 'a.b.0.c' -> value (None deletes the key)."""
    data = copy.deepcopy(BASE)
    for path, value in changes.items():
        parts = [int(p) if p.isdigit() else p for p in path.split("__")]
        node = data
        for part in parts[:-1]:
            node = node[part]
        if value is None:
            del node[parts[-1]]
        else:
            node[parts[-1]] = value
    return data


def answer(tmp_path: Path, capsys, content: str | dict, command: str = "validate"):
    path = tmp_path / "case.yaml"
    path.write_text(content if isinstance(content, str) else yaml.safe_dump(content))
    argv = [command, str(path)] + (["--headless", "--duration", "0.5"] if command == "run" else [])
    started = time.process_time()  # CPU time: a loaded machine does not fail it
    code = main(argv)
    elapsed = time.process_time() - started
    out, err = capsys.readouterr()
    return code, out, err, elapsed


def assert_bad_input(tmp_path, capsys, content, key_path: str, problem: str,
                     commands=("validate", "run")) -> None:
    for command in commands:
        code, _, err, elapsed = answer(tmp_path, capsys, content, command)
        lines = [line for line in err.splitlines() if not line.startswith("warning: ")]
        assert code == 2, (command, err)
        assert len(lines) == 1 and lines[0].startswith("error: "), err
        assert "Traceback" not in err
        assert f": {key_path}: " in lines[0] if key_path else True, lines[0]
        assert problem in lines[0], lines[0]
        assert elapsed < TIME_BOUND, f"{command} took {elapsed:.1f} s"


BIG_POLYGON = [[5.0 + 2.0 * __import__("math").cos(k * 0.00314), 3.0 + 2.0 *
                __import__("math").sin(k * 0.00314)] for k in range(2001)]

CASES = {
    # YAML: bounded before pydantic sees anything
    "deep nesting": ("name: x\nz: " + "[" * 600 + "]" * 600 + "\n", "", "nested too deeply"),
    "alias bomb": ("a: &a [1,1,1,1,1,1,1,1,1,1]\nb: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a]\n"
                   "c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b]\nd: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c]\n"
                   "e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d,*d]\nf: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e,*e]\n",
                   "", "aliases expand"),
    "list as key": ("name: x\n[1, 2]: 3\n", "", "a key must be a plain word"),
    "mapping as key": ("name: x\n? {a: 1}\n: 3\n", "", "a key must be a plain word"),
    "float abc": ("name: x\nseed: !!float abc\n", "", "cannot read 'abc' as float"),
    "huge int": ("name: x\nseed: " + "9" * 5000 + "\n", "", "cannot read"),
    # bounds on counts, with the limit in the message
    "beams": (edited(robots__0__lidar__beams=10**9), "robots[0].lidar.beams", "<= 4096"),
    "dwa samples": (edited(robots__0__controller={"type": "avoid", "dwa": {"time_samples": 10**6}}),
                    "robots[0].controller.dwa.time_samples", "<= 100"),
    "grid cells": (edited(world__size=[2000.0, 2000.0],
                          robots__0__controller={"type": "navigate", "resolution": 0.01}),
                   "robots[0].controller.resolution", "at most 4000000"),
    "obstacles": (edited(obstacles=[{"type": "circle", "center": [8.0, 1.0], "radius": 0.1}] * 5000),
                  "obstacles", "at most 2000"),
    "polygon points": (edited(obstacles=[{"type": "polygon", "points": BIG_POLYGON}]),
                       "obstacles[0].points", "at most 2000"),
    "waypoints": (edited(robots__0__controller={"type": "waypoints", "points": [[2, 2]] * 5000}),
                  "robots[0].controller.points", "at most 1000"),
    # physical ranges
    "k_alpha": (edited(robots__0__controller={"type": "go_to_goal", "k_alpha": 1.7e308}),
                "robots[0].controller.k_alpha", "<= 1000"),
    "wheel noise": (edited(robots__0__odometry={"wheel_noise_std": 1e300}),
                    "robots[0].odometry.wheel_noise_std", "<= 1000"),
    "encoder resolution": (edited(robots__0__odometry={"encoder_resolution": 1e-310}),
                           "robots[0].odometry.encoder_resolution", ">= 1e-09"),
    "scale error": (edited(robots__0__odometry={"left_scale_error": 1.7e308}),
                    "robots[0].odometry.left_scale_error", "<= 10"),
    "lookahead": (edited(robots__0__controller={"type": "waypoints", "points": [[2, 2]],
                                                "pursuit": {"lookahead": 1e300}}),
                  "robots[0].controller.pursuit.lookahead", "<= 100"),
    "coordinate 1e154": (edited(obstacles__0__center=[1e154, 3.0]), "obstacles[0].center[0]",
                         "<= 1e+06"),
    "duration": (edited(world__duration=1e300), "world.duration", "<= 86400"),
    # outside the arena
    "obstacle outside": (edited(obstacles__0__center=[50.0, 3.0]), "obstacles[0]",
                         "outside the arena"),
    "waypoint outside": (edited(robots__0__controller={"type": "waypoints",
                                                       "points": [[2, 2], [500, 2]]}),
                         "robots[0].controller.points[1]", "outside the arena"),
    "goal outside": (edited(robots__0__goal={"position": [90.0, 2.0]}),
                     "robots[0].goal.position", "outside the arena"),
    # meaning known from the file
    "avoid without lidar": (edited(robots__0__lidar=None, robots__0__controller={"type": "avoid"}),
                            "robots[0].controller", "LiDAR"),
    "navigate without lidar among robots": (
        edited(robots=[{"name": "r1", "pose": [1.0, 3.0, 0.0], "goal": {"position": [9.0, 5.0]},
                        "controller": {"type": "navigate"}}, {"name": "r2", "pose": [1.0, 1.0, 0.0]}]),
        "robots[0].controller", "needs a 'lidar'"),
    "go_to_goal without goal": (edited(robots__0__goal=None, expect={}), "robots[0].controller",
                                "needs a goal"),
    "navigate into obstacle": (edited(robots__0__controller={"type": "navigate",
                                                             "goal": [5.0, 3.0]}),
                               "robots[0].controller.goal", "cannot reach it"),
    "end_in empty": (edited(expect={"r1": {"end_in": []}}), "expect.r1.end_in",
                     "at least 3 items"),
    "abstract class": (edited(robots__0__controller={
        "type": "python", "class_path": "pymunk_bot.controllers:Controller"}),
        "robots[0].controller.class_path", "no compute(observation) method of its own"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_each_class_of_bad_input_is_one_line_exit_2(tmp_path, capsys, name):
    content, key_path, problem = CASES[name]
    assert_bad_input(tmp_path, capsys, content, key_path, problem)


def test_merge_keys_are_accepted_like_safe_load(tmp_path, capsys):
    text = ("name: merged\nworld: {size: [6.0, 4.0]}\nrobots:\n"
            "  - &r {name: r1, pose: [1.0, 1.0, 0.0]}\n  - <<: *r\n    name: r2\n"
            "    pose: [3.0, 1.0, 0.0]\n")
    code, out, err, _ = answer(tmp_path, capsys, text)
    assert code == 0 and "ok:" in out, err


def test_error_lists_are_not_cut_short(tmp_path, capsys):
    data = edited(robots__0__goal={"positon": [2.0, 2.0]})
    code, _, err, _ = answer(tmp_path, capsys, data)
    assert code == 2 and "valid keys: position, tolerance" in err and "(and" not in err


def test_angles_in_degrees_warn_and_the_run_goes_on(tmp_path, capsys):
    code, out, err, _ = answer(tmp_path, capsys, edited(robots__0__pose=[1.0, 3.0, 90.0]), "run")
    assert code in (0, 1) and "simulated" in out
    warning = [line for line in err.splitlines() if line.startswith("warning: ")]
    assert len(warning) == 1 and "robots[0].pose[2]" in warning[0] and "degrees" in warning[0]


def test_a_polygon_of_1000_points_validates_fast(tmp_path, capsys):
    import math
    points = [[5.0 + (2.0 + 0.3 * math.sin(7 * t)) * math.cos(t),
               3.0 + (2.0 + 0.3 * math.sin(7 * t)) * math.sin(t)]
              for t in (2 * math.pi * k / 1000 for k in range(1000))]
    data = edited(obstacles=[{"type": "polygon", "points": points}],
                  robots__0__pose=[0.5, 0.5, 0.0], robots__0__goal={"position": [9.5, 0.5]})
    code, _, err, elapsed = answer(tmp_path, capsys, data)
    assert code == 0, err
    assert elapsed < 1.0


# ------------------------------------------------------------------ hypothesis over values

PATHS = [("world", "size", 0), ("world", "dt"), ("world", "duration"), ("seed",),
         ("obstacles", 0, "center", 0), ("obstacles", 0, "angle"), ("robots", 0, "pose", 2),
         ("robots", 0, "radius"), ("robots", 0, "lidar", "beams"), ("robots", 0, "lidar", "rate"),
         ("robots", 0, "goal", "position", 1), ("robots", 0, "max_wheel_speed"),
         ("expect", "r1", "within"), ("robots", 0, "controller", "k_rho")]
VALUES = st.one_of(st.none(), st.booleans(), st.integers(-2**80, 2**80),
                   st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=6),
                   st.lists(st.integers(), max_size=3))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(path=st.sampled_from(PATHS), value=VALUES)
def test_any_value_anywhere_gets_a_clean_answer(tmp_path, capsys, path, value):
    data = copy.deepcopy(BASE)
    node = data
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value
    code, _, err, elapsed = answer(tmp_path, capsys, data, "run")
    assert "Traceback" not in err
    assert code in (0, 1, 2) and elapsed < TIME_BOUND
    if code == 2:
        lines = [line for line in err.splitlines() if not line.startswith("warning: ")]
        assert len(lines) == 1 and lines[0].startswith(f"error: {tmp_path / 'case.yaml'}: ")


# ------------------------------------------------------------------ real processes


def cli(*args: str, cwd: Path = REPO, timeout: float = HANG_GUARD) -> subprocess.CompletedProcess:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-m", "pymunk_bot", *args], capture_output=True,
                          text=True, cwd=cwd, env=env, timeout=timeout)


def test_validate_on_a_fifo_and_dev_zero_returns_at_once(tmp_path):
    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)
    spent = children_cpu()
    proc = cli("validate", str(fifo), "/dev/zero")  # a blocked read would hang: HANG_GUARD
    spent = children_cpu() - spent
    assert proc.returncode == 2
    assert spent < 20.0, f"took {spent:.1f} s of CPU"  # reading /dev/zero on would take more
    lines = proc.stderr.splitlines()
    assert len(lines) == 2 and all("not a regular file" in line for line in lines)


def test_a_20_mb_file_is_refused_without_reading_it_all(tmp_path):
    big = tmp_path / "big.yaml"
    big.write_bytes(b"name: x\n" + b"#" * 20_000_000)
    spent = children_cpu()
    proc = cli("validate", str(big))
    spent = children_cpu() - spent
    assert spent < 20.0, f"took {spent:.1f} s of CPU"  # startup and imports, no parsing of 20 MB
    assert proc.returncode == 2 and "file too large" in proc.stderr and "1 MiB" in proc.stderr


@pytest.mark.slow
def test_seeded_mutations_get_no_tracebacks_and_no_hangs():
    from bench.fuzz import fuzz

    counts = fuzz(files=1000, seed=0, timeout=120.0)  # [s] per file: a hang, not load
    for command, counter in counts.items():
        assert counter["traceback"] == 0 and counter["hang"] == 0, (command, counter)
        assert counter["bad-message"] == 0, (command, counter)
