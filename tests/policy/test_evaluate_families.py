"""`pymunk-bot evaluate --generate office,maze,clutter --maps MAP.yaml`: one table (and plot)
of a policy's contact-free success per world family."""
from __future__ import annotations

import csv
import json

import pytest

pytest.importorskip("gymnasium")

from command import pymunk_bot  # noqa: E402
from test_evaluate_cli import homing  # noqa: E402

FAMILIES = ("--generate", "office,maze,clutter", "--maps", "maps/office.yaml",
            "--random-start", "--random-goal", "--world-seeds", "1000000:2000000")


def test_several_families_give_one_row_each_with_intervals(tmp_path):
    policy, scenario = homing(tmp_path)
    out = pymunk_bot("evaluate", policy, scenario, *FAMILIES, "--episodes", "3", "--json",
                     "--out", tmp_path / "e.csv", "--plot", tmp_path / "families.png")
    assert out.returncode == 0, out.stderr
    table = json.loads(out.stdout)["families"]
    assert list(table) == ["office", "maze", "clutter", "office map"]
    for summary in table.values():
        assert summary["episodes"] == 3
        success = summary["success"]
        assert 0.0 <= success["low"] <= success["rate"] <= success["high"] <= 1.0
    rows = list(csv.DictReader((tmp_path / "e.csv").open()))
    assert [r["family"] for r in rows] == [f for f in table for _ in range(3)]
    assert [int(r["seed"]) for r in rows] == [0, 1, 2] * 4  # the same seeds in each family
    assert (tmp_path / "families.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # The text table: a header, then one line per family with its rate and interval.
    text = pymunk_bot("evaluate", policy, scenario, *FAMILIES, "--episodes", "3")
    lines = text.stdout.strip().splitlines()
    assert lines[0].startswith("family") and "contact-free success (95 % CI)" in lines[0]
    for line, (name, summary) in zip(lines[1:], table.items()):
        assert line.startswith(name)
        assert f"{summary['success']['rate']:.1%}" in line
        assert f"{summary['success']['low']:.1%} - {summary['success']['high']:.1%}" in line
    assert len(lines) == 5


def test_one_kind_keeps_the_single_summary(tmp_path):
    policy, scenario = homing(tmp_path)
    out = pymunk_bot("evaluate", policy, scenario, "--generate", "clutter", "--episodes", "2",
                     "--random-start", "--random-goal", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["episodes"] == 2  # not a table


@pytest.mark.parametrize("options, message", [
    (("--generate", "office,forest"), "argument --generate: 'forest' is not one: give maze, "
                                      "clutter, office"),
    (("--generate", "maze,maze"), "a kind is repeated"),
    (("--maps", "nowhere.yaml"), "error: --maps: no such map file: nowhere.yaml"),
    (("--maps", "maps/office.pgm"), "error: --maps: must be a ROS map file (.yaml)"),
    (("--generate", "maze", "--plot", "p.txt"), "error: --plot: p.txt: unsupported file type"),
])
def test_bad_families_are_one_line_exit_2(tmp_path, options, message):
    policy, scenario = homing(tmp_path)
    out = pymunk_bot("evaluate", policy, scenario, "--episodes", "2", *options, cwd=tmp_path)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and message in lines[0], lines
    assert not (tmp_path / "p.txt").exists()


@pytest.mark.parametrize("n", [3, 7, 200])
def test_wilson_interval_holds_a_rate_of_zero_or_one(n):
    from pymunk_bot.envs.evaluation import wilson

    assert wilson(0, n)[0] == 0.0 and wilson(n, n)[1] == 1.0  # were 5.6e-17 above 0 for n = 3
    assert wilson(0, n)[1] > 0.0 and wilson(n, n)[0] < 1.0
