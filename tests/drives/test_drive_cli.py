"""Bad input about drives, footprints and movers is one line and exit 2 from the command line."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from bounds import HANG_GUARD

REPO = Path(__file__).resolve().parents[2]


def validate(tmp_path: Path, data: dict) -> subprocess.CompletedProcess:
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    return subprocess.run([sys.executable, "-m", "pymunk_bot", "validate", str(path)],
                          capture_output=True, text=True, cwd=REPO, timeout=HANG_GUARD)


def base(robot: dict, obstacles: list | None = None) -> dict:
    return {"name": "t", "world": {"size": [8.0, 6.0]}, "obstacles": obstacles or [],
            "robots": [{"name": "r", "pose": [1.0, 1.0, 0.0], **robot}]}


@pytest.mark.parametrize("robot, obstacles, message", [
    ({"controller": {"type": "velocity", "v": 0.5, "vy": 0.2}}, None,
     "robots[0].controller.vy: the diff drive cannot move sideways"),
    ({"drive": "ackermann", "controller": {"type": "velocity", "vy": 0.2}}, None,
     "robots[0].controller.vy: the ackermann drive cannot move sideways"),
    ({}, [{"type": "box", "center": [3, 3], "size": [0.4, 0.4],
           "motion": {"path": [[3, 3], [9, 3]], "speed": 1.0}}],
     "obstacles[0].motion.path[1]: (9, 3) takes the obstacle out of the arena"),
    ({"drive": "ackermann", "max_steer": 2.0}, None, "robots[0].max_steer: "),
    ({"drive": "omni", "wheels": "tracks"}, None, "robots[0].wheels: "),
    ({"footprint": {"type": "polygon", "points": [[0, 0], [1, 1], [1, 0], [0, 1]]}}, None,
     "robots[0].footprint.points: degenerate polygon: edges cross each other"),
    ({"footprint": {"type": "box", "size": [3.0, 0.4]}}, None,
     "robots[0].pose: robot's footprint at (1, 1) is not inside the arena"),
    ({"drive": "omni", "track_width": 0.3}, None, "robots[0].track_width: unknown key"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, robot, obstacles, message):
    proc = validate(tmp_path, base(robot, obstacles))
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("robot, message", [
    # A LiDAR, or the check that avoid needs one would answer first.
    ({"drive": "omni", "lidar": {}, "controller": {"type": "avoid"}, "goal": {"position": [5, 5]}},
     "robots[0].controller: avoid drives diff robots only (this one is omni)"),
    ({"drive": "ackermann", "controller": {"type": "wheels", "left": 1.0, "right": 1.0}},
     "robots[0].controller: wheels drives diff robots only (this one is ackermann)"),
])
def test_diff_only_controllers_on_other_drives_are_bad_input(tmp_path, robot, message):
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(base(robot)))
    proc = subprocess.run([sys.executable, "-m", "pymunk_bot", "run", str(path), "--headless",
                           "--duration", "0.1"], capture_output=True, text=True, cwd=REPO,
                          timeout=HANG_GUARD)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr
