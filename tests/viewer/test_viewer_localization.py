"""Localization in the views: the built map, particles, ellipse and estimate are drawn (and
toggled by m, k, v, e); the run log keeps them for replay; `plot --kind localization`."""
from __future__ import annotations

import numpy as np
import pygame
import pytest

from viewer_helpers import Harness, build, near
from pymunk_bot.cli import main
from pymunk_bot.outcomes.runlog import RunLogger, load_log
from pymunk_bot.viewer import palette as pal
from pymunk_bot.viewer.sources import ReplaySource

LIDAR = {"beams": 180, "max_range": 6.0, "noise_std": 0.01, "rate": 10.0}
BOX = [{"type": "box", "center": [3.0, 1.5], "size": [0.4, 0.4]}]


def _sim(**localization):
    robot = {"name": "r1", "pose": [1.0, 1.0, 0.0], "lidar": LIDAR,
             "controller": {"type": "velocity", "v": 0.2, "omega": 0.5},
             # AMCL's sum likelihood keeps the cloud wide enough to see beside the robot (the
             # default product pulls it under the robot's disc within a second)
             "localization": {"type": "mcl", "initial_std": [0.3, 0.3, 0.3], "max_particles": 300,
                              "min_particles": 300, "laser_model_type": "likelihood_field",
                              **localization},
             "mapping": {"resolution": 0.05}}
    return build([robot], BOX)


def _changed(h, key, unicode) -> int:
    """Pixels that change when a layer is toggled off."""
    before = pygame.surfarray.array3d(h.draw()).copy()
    h.key(key, unicode)
    after = pygame.surfarray.array3d(h.draw())
    h.key(key, unicode)  # back on
    return int(np.any(before != after, axis=-1).sum())


def test_each_layer_draws_something_and_its_key_toggles_it():
    sim = _sim()
    sim.run(1.0)
    h = Harness(sim, size=(640, 480))
    for key, char in ((pygame.K_m, "m"), (pygame.K_k, "k"), (pygame.K_v, "v"), (pygame.K_e, "e")):
        assert _changed(h, key, char) > 20, char
    # The map: a cell seen free carries the robot's tint; with the layer off, the bare floor.
    h.key(pygame.K_l, "l")  # no LiDAR rays across the floor
    h.key(pygame.K_g, "g")  # nor grid lines
    h.draw()
    tinted = h.pixel((2.13, 0.63))
    assert not near(tinted, pal.FLOOR, tol=3)
    h.key(pygame.K_m, "m")
    h.draw()
    assert near(h.pixel((2.13, 0.63)), pal.FLOOR, tol=3)
    # Unknown cells stay transparent: behind the box, the floor shows.
    h.key(pygame.K_m, "m")
    h.draw()
    assert near(h.pixel((3.43, 1.57)), pal.FLOOR, tol=3)


def test_the_run_log_keeps_estimate_particles_and_map_for_replay(tmp_path):
    sim = _sim()
    logger = RunLogger().attach(sim)
    sim.run(1.5)
    path = tmp_path / "run.npz"
    logger.save(path)
    log = load_log(path)
    track = log.localization["r1"]
    robot = sim.robots["r1"]
    assert track.estimate.shape == (len(log.time), 3)
    np.testing.assert_allclose(track.estimate[-1], robot.localizer.pose)
    np.testing.assert_allclose(track.covariance[-1], robot.localizer.covariance)
    assert 6 <= len(track.particle_time) <= 9  # every 0.2 s over 1.5 s
    cloud = track.cloud_at(log.time[-1])
    assert cloud.shape == (300, 3)
    # the final map is the mapper's, cell for cell
    np.testing.assert_array_equal(track.map_at(log.time[-1]).data, robot.mapper.grid.data)
    assert track.map_at(0.5).data.shape == robot.mapper.grid.data.shape
    # replay shows them: the frame differs when the localization layers are off
    h = Harness(ReplaySource(log), size=(640, 480))
    h.viewer.source.seek(len(log.time))
    assert _changed(h, pygame.K_k, "k") > 20 and _changed(h, pygame.K_m, "m") > 20


def test_plot_localization_draws_error_panels(tmp_path, capsys):
    sim = _sim()
    logger = RunLogger().attach(sim)
    sim.run(1.0)
    logger.save(tmp_path / "run.npz")
    out = tmp_path / "loc.png"
    assert main(["plot", str(tmp_path / "run.npz"), "--kind", "localization", "-o", str(out)]) == 0
    assert out.stat().st_size > 10_000
    plain = build([{"name": "r1", "pose": [1.0, 1.0, 0.0]}])
    logger = RunLogger().attach(plain)
    plain.run(0.2)
    logger.save(tmp_path / "plain.npz")
    assert main(["plot", str(tmp_path / "plain.npz"), "--kind", "localization",
                 "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "has a localizer" in err
