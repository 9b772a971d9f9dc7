"""Every kind of bad scenario input gets exit status 2 and one precise line, never a traceback."""
from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from command import pymunk_bot

GOOD = """\
name: good
world:
  size: [10.0, 5.0]
obstacles:
  - {type: box, center: [5.0, 2.5], size: [1.0, 1.0]}
  - {type: polygon, points: [[7, 1], [8, 1], [8, 2], [7.5, 1.5], [7, 2]]}
robots:
  - name: r1
    pose: [1.0, 2.5, 0.0]
    lidar: {beams: 90}
    controller: {type: go_to_goal}
    goal: {position: [9.0, 4.0]}
expect:
  r1: {goal_reached: true}
"""


def validate(tmp_path: Path, text: str) -> tuple[int, str]:
    path = tmp_path / "s.yaml"
    path.write_text(textwrap.dedent(text))
    from pymunk_bot.cli import main
    import contextlib
    import io
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        status = main(["validate", str(path)])
    return status, err.getvalue()


def test_good_scenario_validates(tmp_path):
    assert validate(tmp_path, GOOD) == (0, "")


CASES = [
    # (replace this, with this, expected key path, words expected in the message)
    ("beams: 90", "beams: -5", "robots[0].lidar.beams", "must be > 0 (got -5)"),
    ("beams: 90", "beams: 90, fov: 7.0", "robots[0].lidar.fov", "(0, 2*pi]"),
    ("beams: 90", "beams: 90, rate: 0", "robots[0].lidar.rate", "must be > 0"),
    ("beams: 90", "beams: 90, min_range: 9, max_range: 8", "robots[0].lidar.min_range",
     "must be < max_range"),
    ("beams: 90", "beams: 90, noise_std: -0.1", "robots[0].lidar.noise_std", "must be >= 0"),
    ("beams: 90", "beams: 90.5", "robots[0].lidar.beams", "must be an integer"),
    ("beams: 90", "beams: 90, dropout: 1.5", "robots[0].lidar.dropout", "must be < 1"),
    ("beams: 90", "beems: 90", "robots[0].lidar.beems", "did you mean 'beams'"),
    ("size: [10.0, 5.0]", "size: [10.0, -5.0]", "world.size[1]", "must be >= 0.001 (got -5)"),
    ("size: [10.0, 5.0]", "size: [10.0, .nan]", "world.size[1]", "finite"),
    ("size: [10.0, 5.0]", "size: [10.0, .inf]", "world.size[1]", "finite"),
    ("size: [10.0, 5.0]", "size: [10.0]", "world.size", "must have 2 items (got 1)"),
    ("pose: [1.0, 2.5, 0.0]", "pose: [1.0, 2.5]", "robots[0].pose", "must have 3 items (got 2)"),
    ("pose: [1.0, 2.5, 0.0]", "pose: [1.0, 2.5, 0.0]\n    radius: 1.0e-150", "robots[0].radius",
     "must be >= 0.001"),
    ("size: [10.0, 5.0]", "size: [10.0, 5.0, 1.0]", "world.size", "at most 2 items"),
    ("size: [10.0, 5.0]", "size: ten", "world.size", "must be a list"),
    ("size: [10.0, 5.0]", "size: [10.0, 5.0]\n  dt: '0.1'", "world.dt", "must be a number"),
    ("world:", "wrld:", "wrld", "did you mean 'world'"),
    ("name: good", "name: Good Name", "name", "must match"),
    ("name: good\n", "", "name", "required key is missing"),
    ("pose: [1.0, 2.5, 0.0]", "pose: [0.1, 2.5, 0.0]", "robots[0].pose", "not inside the arena"),
    ("pose: [1.0, 2.5, 0.0]", "pose: [5.2, 2.5, 0.0]", "robots[0].pose", "inside obstacles[0]"),
    ("type: box, center", "type: boxx, center", "obstacles[0]", "did you mean 'box'"),
    ("size: [1.0, 1.0]}", "size: [1.0, 0.0]}", "obstacles[0].size[1]", "must be >= 0.001"),
    ("[[7, 1], [8, 1], [8, 2], [7.5, 1.5], [7, 2]]", "[[7, 1], [8, 1], [9, 1]]",
     "obstacles[1].points", "zero area"),
    ("[[7, 1], [8, 1], [8, 2], [7.5, 1.5], [7, 2]]", "[[7, 1], [8, 2], [8, 1], [7, 2]]",
     "obstacles[1].points", "edges cross"),
    ("[[7, 1], [8, 1], [8, 2], [7.5, 1.5], [7, 2]]", "[[7, 1], [8, 1]]",
     "obstacles[1].points", "at least 3 items"),
    ("controller: {type: go_to_goal}", "controller: {type: go_to_gaol}", "robots[0].controller",
     "did you mean 'go_to_goal'"),
    ("position: [9.0, 4.0]", "position: [19.0, 4.0]", "robots[0].goal.position", "outside the arena"),
    ("r1: {goal_reached: true}", "r2: {goal_reached: true}", "expect.r2", "no robot named 'r2'"),
    ("r1: {goal_reached: true}", "r1: {goal_reached: yes please}", "expect.r1.goal_reached",
     "true or false"),
]


@pytest.mark.parametrize("old,new,path,words", CASES, ids=[c[2] + ":" + c[3] for c in CASES])
def test_bad_input_names_file_key_path_and_problem(tmp_path, old, new, path, words):
    assert old in GOOD
    status, err = validate(tmp_path, GOOD.replace(old, new, 1))
    assert status == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"error: {tmp_path / 's.yaml'}: {path}: "), lines[0]
    assert words in lines[0]
    assert "(line " in lines[0]


def test_duplicate_robot_names(tmp_path):
    text = GOOD.replace("expect:", "  - {name: r1, pose: [2.0, 1.0, 0.0]}\nexpect:")
    status, err = validate(tmp_path, text)
    assert status == 2 and "robots[1].name: duplicate robot name 'r1'" in err


def test_yaml_syntax_error_reports_the_line(tmp_path):
    status, err = validate(tmp_path, GOOD.replace("size: [10.0, 5.0]", "size: [10.0, 5.0"))
    assert status == 2 and "YAML syntax error" in err and "(line " in err


def test_duplicate_yaml_key_is_an_error(tmp_path):
    status, err = validate(tmp_path, GOOD.replace("  size: [10.0, 5.0]", "  size: [10.0, 5.0]\n  size: [3, 3]"))
    assert status == 2 and "duplicate key 'size'" in err


def test_empty_file_and_non_mapping(tmp_path):
    assert validate(tmp_path, "")[0] == 2
    status, err = validate(tmp_path, "- just\n- a list\n")
    assert status == 2 and "must be a YAML mapping" in err


def test_missing_file_via_run_is_exit_2_without_traceback(tmp_path):
    proc = pymunk_bot("run", str(tmp_path / "nope.yaml"), "--headless")
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"error: {tmp_path / 'nope.yaml'}: file not found"
    assert "Traceback" not in proc.stderr + proc.stdout


def test_unknown_shipped_name_suggests_one():
    proc = pymunk_bot("run", "push_crat", "--headless")
    assert proc.returncode == 2 and "did you mean 'push_crate'" in proc.stderr


def test_bad_command_line_option_is_exit_2():
    proc = pymunk_bot("run", "--duration", "abc")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
