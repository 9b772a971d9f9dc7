"""`convert` between .npz and .mcap, `replay`/`plot` of MCAP, and the command line around them."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from builders import robot, scenario, wheels
from foxglove_helpers import read_mcap

from pymunk_bot import Simulation
from pymunk_bot.cli import main
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.foxglove.convert import convert
from pymunk_bot.foxglove.mcap_log import McapLogger
from pymunk_bot.foxglove.reader import load_mcap
from pymunk_bot.outcomes.runlog import RunLogger, load_log
from pymunk_bot.viewer.sources import ReplaySource

PER_STEP = ("time", "pose", "odometry", "command", "wheel_speeds", "velocity", "collisions",
            "goal", "goal_tolerance", "goal_reached", "teleop", "obstacle_pose")


def run_both(tmp_path, duration=1.5):
    """One run logged as .npz and .mcap at once."""
    sim = Simulation.from_dict(scenario(
        [robot([1.0, 1.0, 0.3], name="a", controller=wheels(0.6, 0.5),
               lidar={"beams": 36, "max_range": 3.0, "rate": 5.0, "offset": [0.05, 0, 0.2]},
               goal={"position": [3.0, 2.0]}),
         robot([3.0, 0.5, 0.0], name="b")],
        [{"type": "box", "center": [2.0, 2.0], "size": [0.3, 0.3], "movable": True}],
        size=(4.0, 3.0)), seed=5)
    npz = RunLogger().attach(sim)
    mcap = McapLogger(tmp_path / "run.mcap").attach(sim)
    sim.run(duration)
    npz.save(tmp_path / "run.npz")
    mcap.save()
    return load_log(tmp_path / "run.npz")


def assert_same_log(a, b):
    for name in PER_STEP:
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert a.robot_names == b.robot_names
    for robot_name, scans in a.scans.items():
        other = b.scans[robot_name]
        assert np.array_equal(scans.ranges, other.ranges)
        assert np.array_equal(scans.time, other.time) and np.array_equal(scans.pose, other.pose)
        assert np.allclose(scans.angles, other.angles, atol=1e-12)
        assert np.array_equal(scans.offset, other.offset)


def test_an_mcap_reads_back_as_the_npz_log(tmp_path):
    npz = run_both(tmp_path)
    assert_same_log(npz, load_mcap(tmp_path / "run.mcap"))


def test_npz_converts_to_mcap_with_the_same_channels_and_back(tmp_path):
    npz = run_both(tmp_path)
    convert(tmp_path / "run.npz", tmp_path / "converted.mcap")
    summary, messages = read_mcap(tmp_path / "converted.mcap")
    live = read_mcap(tmp_path / "run.mcap")[0]
    topics = {c.topic for c in summary.channels.values()}
    assert topics == {c.topic for c in live.channels.values()}
    scans = messages["/a/scan"]
    assert len(scans) == len(npz.scans["a"].time) == 8  # 5 Hz over 1.5 s, and t = 0
    assert all(np.array_equal(np.float32(m.ranges), npz.scans["a"].ranges[k])
               for k, (_, _, m) in enumerate(scans))
    assert_same_log(npz, load_mcap(tmp_path / "converted.mcap"))
    convert(tmp_path / "converted.mcap", tmp_path / "again.npz")
    assert_same_log(npz, load_log(tmp_path / "again.npz"))


def test_replay_plays_an_mcap(tmp_path):
    run_both(tmp_path)
    source = ReplaySource(load_mcap(tmp_path / "run.mcap"))
    while not source.at_end:
        source.step()
    scene = source.scene()
    assert [r.name for r in scene.robots] == ["a", "b"]
    assert scene.robots[0].scan_points is not None and len(scene.robots[0].scan_points) == 36


def test_bad_files_are_one_line_errors(tmp_path):
    (tmp_path / "junk.mcap").write_bytes(b"not an mcap file")
    with pytest.raises(ScenarioError, match="not a readable MCAP"):
        load_mcap(tmp_path / "junk.mcap")
    with pytest.raises(ScenarioError, match="file not found"):
        load_mcap(tmp_path / "missing.mcap")
    from foxglove.mcap import MCAPWriteOptions  # noqa: F401  (an MCAP, but not ours)
    import foxglove

    with foxglove.open_mcap(tmp_path / "other.mcap", context=foxglove.Context()):
        pass
    with pytest.raises(ScenarioError, match="not an MCAP written by pymunk-bot"):
        load_mcap(tmp_path / "other.mcap")


def test_command_line(tmp_path, capsys):
    out = tmp_path / "run.mcap"
    assert main(["run", "--headless", "--duration", "0.5", "--log", str(out)]) in (0, 1)
    assert "wrote" in capsys.readouterr().out and out.exists()
    assert read_mcap(out)[0].statistics.channel_message_counts
    assert main(["convert", str(out), str(tmp_path / "run.npz")]) == 0
    assert main(["convert", str(tmp_path / "run.npz"), str(tmp_path / "back.mcap")]) == 0
    assert main(["convert", str(tmp_path / "nope.npz"), str(tmp_path / "x.mcap")]) == 2
    assert main(["convert", str(out), str(tmp_path / "x.txt")]) == 2
    assert main(["run", "--headless", "--duration", "0.1", "--speed", "2"]) == 2
    assert main(["run", "--headless", "--duration", "0.1", "--foxglove", "--speed", "-1"]) == 2
    err = capsys.readouterr().err
    assert "--speed: only applies with --foxglove" in err and "must be > 0" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["back.mcap", "run.mcap", "run.npz"]


def test_the_core_does_not_import_foxglove():
    code = ("import sys, pymunk_bot, pymunk_bot.cli, pymunk_bot.outcomes.runlog;"
            "pymunk_bot.cli.build_parser();"
            "print(any(m in sys.modules for m in ('foxglove', 'mcap', 'google.protobuf')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
