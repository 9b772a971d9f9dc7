"""Plots of a run log: the PNG shows the trajectory where it happened, in the robot's colour."""
from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

from pymunk_bot.cli import main
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.viewer.plots import DPI, make_figure, save_plot
from pymunk_bot.outcomes.runlog import RunLogger, load_log
from pymunk_bot.viewer import palette as pal
from viewer_helpers import build, near, wheels


@pytest.fixture(scope="module")
def log():
    sim = build([{"name": "r", "pose": [0.5, 0.8, 0.3], "controller": wheels(0.5, 0.55),
                  "lidar": {"beams": 30, "max_range": 3.0},
                  "odometry": {"right_scale_error": 0.08}}], size=(5.0, 3.0))
    logger = RunLogger().attach(sim)
    sim.run(4.0)
    return logger.log()


def test_map_shows_the_true_path_in_the_robots_colour(tmp_path, log):
    fig = make_figure(log, "map")
    fig.canvas.draw()
    ax = fig.axes[0]
    out = tmp_path / "map.png"
    save_plot(log, out, "map")
    image = iio.imread(out)
    width, height = fig.get_size_inches() * DPI
    assert image.shape[:2] == (round(height), round(width))
    colour = pal.robot_colour(0)
    # Points along the true path (not the start and end circles).
    true = log.pose[:, 0, :2]
    for k in (40, 100, 160):
        px, py = ax.transData.transform(true[k])
        row, col = int(round(height - py)), int(round(px))
        patch = image[row - 3:row + 4, col - 3:col + 4, :3].reshape(-1, 3)  # the 2 px line, rounding
        assert any(near(c, colour, 20) for c in patch), k
    # Odometry drifted away from the truth; its dashed line is elsewhere.
    assert np.hypot(*(log.odometry[-1, 0, :2] - true[-1])) > 0.1


@pytest.mark.parametrize("kind", ["all", "speed", "ranges"])
def test_every_kind_writes_an_image(tmp_path, log, kind):
    out = tmp_path / f"{kind}.png"
    save_plot(log, out, kind)
    image = iio.imread(out)
    assert image.shape[0] > 300 and image.shape[1] > 600
    # Not blank: the robot's colour appears (the lines of the plot).
    colour = np.array(pal.robot_colour(0))
    assert (np.abs(image[..., :3].astype(int) - colour).max(axis=-1) < 20).sum() > 200


def test_unknown_robot_is_a_one_line_error(log):
    with pytest.raises(ScenarioError, match="no robot 'zz'"):
        make_figure(log, "map", robot="zz")


def test_cli_log_plot_and_replay_to_video(tmp_path, capsys):
    run_log = tmp_path / "run.npz"
    assert main(["run", "--headless", "--duration", "2", "--log", str(run_log)]) in (0, 1)
    log = load_log(run_log)
    assert log.time.shape == (121,)
    assert main(["plot", str(run_log)]) == 0
    assert (tmp_path / "run.png").stat().st_size > 10_000
    assert main(["plot", str(run_log), "--kind", "ranges", "-o", str(tmp_path / "r.svg")]) == 0
    assert (tmp_path / "r.svg").read_text().lstrip().startswith("<?xml")
    assert main(["replay", str(run_log), "--record", str(tmp_path / "replay.gif"), "--fps", "5",
                 "--size", "80x48"]) == 0
    assert iio.imread(tmp_path / "replay.gif", index=None).shape == (11, 48, 80, 3)
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "missing.npz")]) == 2
    assert main(["plot", str(run_log), "-o", str(tmp_path / "x.jpg")]) == 2
    assert main(["replay", str(run_log)]) == 2  # no display here: says to record instead
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3
    assert "file not found" in err[0] and "unsupported" in err[1] and "--record" in err[2]
