"""Sensors through the command line: noisy runs are reproducible, bad parameters exit 2."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from pymunk_bot import cli
from bounds import HANG_GUARD

NOISY = {
    "name": "noisy_sensors",
    "seed": 5,
    "world": {"size": [8.0, 6.0], "duration": 6.0},
    "obstacles": [{"type": "box", "center": [4.0, 1.5], "size": [0.6, 0.6]}],
    "robots": [{
        "name": "r1", "pose": [1.0, 3.0, 0.0],
        "lidar": {"beams": 90, "noise_std": 0.02, "dropout": 0.05},
        "odometry": {"wheel_noise_std": 0.01, "left_scale_error": 0.005, "encoder_resolution": 0.001},
        "imu": {"gyro_noise_std": 0.01, "accel_noise_std": 0.05, "gyro_bias_walk": 0.001},
        "controller": {"type": "go_to_goal"},
        "goal": {"position": [7.0, 3.0]},
    }],
}


def write(tmp_path: Path, data: dict, name: str = "scenario.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def run(path: Path, out: Path, *extra: str) -> dict:
    status = cli.main(["run", str(path), "--headless", "--out", str(out), *extra])
    assert status in (0, 1)
    return json.loads(out.read_text())


def without_timing(result: dict) -> dict:
    return {k: v for k, v in result.items() if k not in ("wall_time", "real_time_factor")}


def test_noisy_run_reports_a_reproducible_odometry_error(tmp_path, capsys):
    path = write(tmp_path, NOISY)
    first = run(path, tmp_path / "a.json")
    second = run(path, tmp_path / "b.json")
    other_seed = run(path, tmp_path / "c.json", "--seed", "6")
    error = first["robots"]["r1"]["odometry_error"]
    assert error > 0.0
    assert without_timing(first) == without_timing(second)
    assert other_seed["robots"]["r1"]["odometry_error"] != error
    assert first["robots"]["r1"]["distance"] > 3.0  # it drove somewhere


def test_the_installed_command_runs_a_noisy_scenario(tmp_path):
    path, out = write(tmp_path, NOISY), tmp_path / "result.json"
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    command = [sys.executable, "-m", "pymunk_bot", "run", str(path), "--headless", "--out", str(out)]
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=HANG_GUARD)
    assert done.returncode in (0, 1), done.stderr
    assert json.loads(out.read_text())["robots"]["r1"]["odometry_error"] > 0.0


BAD = [
    ("lidar", {"beams": -5}, "robots[0].lidar.beams: must be > 0"),
    ("lidar", {"beams": 0}, "robots[0].lidar.beams: must be > 0"),
    ("lidar", {"beams": 2.5}, "robots[0].lidar.beams: must be an integer"),
    ("lidar", {"fov": 7.0}, "robots[0].lidar.fov: must be in (0, 2*pi]"),
    ("lidar", {"fov": 0.0}, "robots[0].lidar.fov: must be in (0, 2*pi]"),
    ("lidar", {"rate": 0.0}, "robots[0].lidar.rate: must be > 0"),
    ("lidar", {"rate": -10.0}, "robots[0].lidar.rate: must be > 0"),
    ("lidar", {"max_range": -1.0}, "robots[0].lidar.max_range: must be > 0"),
    ("lidar", {"min_range": -0.1}, "robots[0].lidar.min_range: must be >= 0"),
    ("lidar", {"min_range": 8.0, "max_range": 8.0}, "robots[0].lidar.min_range: must be < max_range"),
    ("lidar", {"noise_std": -0.01}, "robots[0].lidar.noise_std: must be >= 0"),
    ("lidar", {"noise_std": float("nan")}, "robots[0].lidar.noise_std: must be a finite number"),
    ("lidar", {"dropout": 1.0}, "robots[0].lidar.dropout: must be < 1"),
    ("lidar", {"dropout": -0.1}, "robots[0].lidar.dropout: must be >= 0"),
    ("lidar", {"offset": [0.1, 0.0]}, "robots[0].lidar.offset"),
    ("lidar", {"beam": 90}, "robots[0].lidar.beam: unknown key (did you mean 'beams'?)"),
    ("odometry", {"wheel_noise_std": -1.0}, "robots[0].odometry.wheel_noise_std: must be >= 0"),
    ("odometry", {"encoder_resolution": -0.001}, "robots[0].odometry.encoder_resolution: must be >= 0"),
    ("odometry", {"track_width_error": -1.0}, "robots[0].odometry.track_width_error: must be > -1"),
    ("odometry", {"left_scale_error": -2.0}, "robots[0].odometry.left_scale_error: must be > -1"),
    ("imu", {"rate": 0.0}, "robots[0].imu.rate: must be > 0"),
    ("imu", {"gyro_noise_std": -0.1}, "robots[0].imu.gyro_noise_std: must be >= 0"),
    ("imu", {"accel_bias": [0.1]}, "robots[0].imu.accel_bias"),
    ("imu", {"gyro_bias_walk": -1.0}, "robots[0].imu.gyro_bias_walk: must be >= 0"),
    ("imu", {"accel_noise": 0.1}, "robots[0].imu.accel_noise: unknown key"),
]


@pytest.mark.parametrize("section,keys,message", BAD, ids=[f"{s}.{next(iter(k))}" for s, k, _ in BAD])
def test_bad_sensor_parameters_exit_2_with_the_key_path(tmp_path, capsys, section, keys, message):
    data = json.loads(json.dumps(NOISY))  # a deep copy
    data["robots"][0][section] = {**data["robots"][0].get(section, {}), **keys}
    path = write(tmp_path, data)
    assert cli.main(["run", str(path), "--headless"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {path}: ") and message in err
    assert "\n" not in err and "Traceback" not in err
