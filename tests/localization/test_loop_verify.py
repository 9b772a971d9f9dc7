"""Issue 36: a loop closure is accepted only where the scan says where the robot is, and
nowhere else (localization/loopverify.py).

An aisle between racks whose uprights repeat every 0.6 m: a 3.5 m scan fits every 0.6 m
along it alike, and the ICP, started from an estimate 25 cm off, settles on whichever
upright is nearest with a stated std of a few centimetres. Such a closure would pin the map
at a wrong place (warehouse, uncalibrated, revisiting, seed 18: 40 cm along the aisle); it is
refused. The same aisle with an end wall in sight is one place: accepted, at the truth.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.localization.icp import Reference, seen_from
from pymunk_bot.localization import loopverify
from pymunk_bot.localization.slam import EDGE_FLOOR

RANGE = 3.5  # [m] the LiDAR's
SPACING = 0.6  # [m] between a rack's uprights


def _aisle(end_wall: bool) -> np.ndarray:
    """End points of an aisle along x, 2 m wide (racks' faces y = +-1), uprights 15 cm deep
    every SPACING; ``end_wall``: a wall across it at x = 3 m (and nothing beyond)."""
    x = np.arange(-12.0, 12.0, 0.02)
    points = [np.column_stack([x, np.full_like(x, side)]) for side in (-1.0, 1.0)]
    depth = np.linspace(0.0, 0.15, 8)
    for upright in np.arange(-12.0, 12.0, SPACING):
        for side in (-1.0, 1.0):
            points.append(np.column_stack([np.full_like(depth, upright), side * (1.0 - depth)]))
    cloud = np.vstack(points)
    if end_wall:
        cloud = cloud[cloud[:, 0] <= 3.0]
        y = np.arange(-1.0, 1.0, 0.02)
        cloud = np.vstack([cloud, np.column_stack([np.full_like(y, 3.0), y])])
    return cloud


def _scan(world: np.ndarray, pose: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The end points within RANGE of ``pose`` [x, y, theta], robot frame, 1 cm of noise."""
    seen = world[np.hypot(*(world - pose[:2]).T) <= RANGE]
    c, s = np.cos(pose[2]), np.sin(pose[2])
    local = (seen - pose[:2]) @ np.array([[c, -s], [s, c]])
    return local + rng.normal(0.0, 0.01, local.shape)


def _closure(end_wall: bool):
    rng = np.random.default_rng(3)
    world = _aisle(end_wall)
    sensor = np.zeros(2)
    old_poses = [np.array([x, 0.0, 0.0]) for x in (-0.4, -0.2, 0.0, 0.2, 0.4)]
    points, facing = zip(*(seen_from(p, _scan(world, p, rng), sensor) for p in old_poses))
    reference = Reference.surfaces(np.concatenate(points), weighed=False,
                                   facing=np.concatenate(facing))
    truth = np.array([0.1, 0.05, 0.0])
    scan = _scan(world, truth, rng)
    estimate = truth + np.array([0.25, 0.0, 0.0])  # the chain's drift along the aisle
    accumulated = np.diag([0.3, 0.3, np.radians(1.0)]) ** 2
    return truth, loopverify.verify_closure(reference, scan, estimate, accumulated, EDGE_FLOOR,
                                            iterations=20, max_pair=0.3, huber=0.05, min_inliers=0.7,
                                            sensor=sensor)


def test_a_closure_in_an_aisle_whose_uprights_repeat_is_refused(monkeypatch):
    _, match = _closure(end_wall=False)
    assert match is None
    # Every other test passes it: it fits, states a std of 1.6 cm along the aisle, and the
    # chain's 30 cm explain its correction; but it lies 27 cm from the truth.
    monkeypatch.setattr(loopverify, "ambiguous", lambda *args, **kwargs: False)
    truth, match = _closure(end_wall=False)
    assert match is not None
    assert np.hypot(*(match.pose[:2] - truth[:2])) > 0.2


def test_a_closure_where_the_aisle_ends_in_sight_is_accepted_at_the_truth():
    truth, match = _closure(end_wall=True)
    assert match is not None
    assert np.hypot(*(match.pose[:2] - truth[:2])) < 0.02
