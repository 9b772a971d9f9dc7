"""Issue 36: SLAM's line fits keep a wall's two faces apart.

A generated office's walls are 10 cm thick and the robot sees them from both rooms. Fitted as
one cloud, the fits near such a wall took both faces into one neighbourhood: the line lay
between them and a scan of one face could be paired with the other. Each fit is now of the
face its scans saw, and a point is paired only with a face towards the sensor
(icp.Reference.surfaces' ``facing``).
"""
from __future__ import annotations

import numpy as np

from bench.localization_robustness import run_one
from pymunk_bot.localization.icp import Reference, icp
from pymunk_bot.localization.se2 import transform_points


def _face(x0: float, x1: float, y: float, n: int) -> np.ndarray:
    return np.column_stack([np.linspace(x0, x1, n), np.full(n, y)])


def test_a_scan_of_one_face_of_a_thin_wall_is_matched_to_that_face():
    rng = np.random.default_rng(5)
    # A 10 cm wall along x (faces y = +-0.05) seen from both sides, and a wall across it in
    # the +y room that pins x.
    top, bottom = _face(-3.0, 2.95, 0.05, 300), _face(-3.0, 2.95, -0.05, 300)
    across = np.column_stack([np.full(150, 2.95), np.linspace(0.05, 3.0, 150)])
    cloud = np.vstack([top, across, bottom]) + rng.normal(0.0, 0.01, (750, 2))
    sensors = np.vstack([np.tile([0.0, 1.0], (450, 1)), np.tile([0.0, -1.0], (300, 1))])
    towards = sensors - cloud
    facing = towards / np.linalg.norm(towards, axis=1, keepdims=True)
    truth = np.array([0.3, 0.8, 0.0])  # in the +y room, 0.75 m from the wall's face
    seen = np.vstack([_face(-2.0, 2.9, 0.05, 120),
                      np.column_stack([np.full(60, 2.95), np.linspace(0.1, 2.5, 60)])])
    scan = transform_points(np.array([-0.3, -0.8, 0.0]), seen) + rng.normal(0.0, 0.01, seen.shape)
    guess = truth + np.array([0.03, -0.03, np.radians(0.5)])

    faces = Reference.surfaces(cloud, facing=facing)
    assert faces.oriented
    # every fit near the wall lies on one face, its normal towards the room that saw it
    on_wall = np.abs(faces.points[:, 0]) < 2.5
    assert np.all(np.abs(np.abs(faces.points[on_wall, 1]) - 0.05) < 0.02)
    assert np.all(np.sign(faces.normals[on_wall, 1]) == np.sign(faces.points[on_wall, 1]))
    match = icp(faces, scan, guess)
    assert match.ok
    assert np.hypot(*(match.pose[:2] - truth[:2])) < 0.005
    assert abs(np.degrees(match.pose[2])) < 0.1

    # Both faces in one fit: the scan slid towards the other face (56 mm across).
    plain = icp(Reference.surfaces(cloud), scan, guess)
    assert abs(plain.pose[1] - truth[1]) > 0.02


def test_slam_keeps_to_5_cm_in_the_office_whose_walls_it_saw_from_both_sides():
    # Office seed 18 (270 beams, 3.5 m, 5 Hz, 2.5 cm noise) passes from room to room: 8.1 cm
    # and map precision 0.83 with both faces in one fit, 0.6 cm and 0.999 now.
    out = run_one("slam", "office", "typical", 18)
    assert out is not None and not out.error
    assert out.ate <= 0.05, out.line()
    assert out.map_precision >= 0.9, out.line()
