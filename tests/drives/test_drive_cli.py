"""Bad input about drives, footprints and movers is one line and exit 2 from the command line.

Every bad file goes to ONE `pymunk-bot validate` process (one line per file, exit 2): the same
check as a process per file, at an eighth of the CPU (issue 35: the suite's cost)."""
from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
import yaml
from command import pymunk_bot

REPO = Path(__file__).resolve().parents[2]


def base(robot: dict, obstacles: list | None = None) -> dict:
    return {"name": "t", "world": {"size": [8.0, 6.0]}, "obstacles": obstacles or [],
            "robots": [{"name": "r", "pose": [1.0, 1.0, 0.0], **robot}]}


BAD = [
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
]


@pytest.fixture(scope="module")
def validated(tmp_path_factory) -> tuple[subprocess.CompletedProcess, list[Path]]:
    """One `validate` process over every case of BAD, and the files in their order."""
    folder = tmp_path_factory.mktemp("bad")
    paths = []
    for i, (robot, obstacles, _) in enumerate(BAD):
        paths.append(folder / f"case{i}.yaml")
        paths[-1].write_text(yaml.safe_dump(base(robot, obstacles)))
    proc = pymunk_bot("validate", *paths, cwd=REPO)
    return proc, paths


@pytest.mark.parametrize("case", range(len(BAD)), ids=[message for *_, message in BAD])
def test_bad_input_is_one_line_and_exit_2(validated, case):
    proc, paths = validated
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    lines = [line for line in proc.stderr.splitlines() if f"{paths[case]}:" in line]
    assert len(lines) == 1 and BAD[case][2] in lines[0], proc.stderr
    assert len(proc.stderr.strip().splitlines()) == len(BAD)  # one line per file, no more


@pytest.mark.parametrize("robot, message", [
    # A LiDAR, or the check that avoid needs one would answer first.
    ({"drive": "omni", "lidar": {}, "controller": {"type": "avoid"}, "goal": {"position": [5, 5]}},
     "robots[0].controller: avoid drives diff robots only (this one is omni)"),
    ({"drive": "ackermann", "controller": {"type": "wheels", "left": 1.0, "right": 1.0}},
     "robots[0].controller: wheels drives diff robots only (this one is ackermann)"),
])
def test_diff_only_controllers_on_other_drives_are_bad_input(tmp_path, capsys, robot, message):
    from pymunk_bot.cli import main

    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(base(robot)))
    assert main(["run", str(path), "--headless", "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
