"""The compiled scan helpers against plain numpy references written out here: the nearest
beam to a bearing, the distance to a scan's surface, the clearance of arcs to returns, and the
clusters of a scan."""
from __future__ import annotations

import numpy as np
import pytest

from pymunk_bot.controllers.navigate import nearest_beams
from pymunk_bot.planning.dwa import arc_distances
from pymunk_bot.planning.tracking import (CLUSTER_GAP, CLUSTER_SIZE, distance_to_polyline,
                                          small_clusters)


@pytest.mark.parametrize("kind", ["uniform", "random", "closed", "unordered"])
def test_nearest_beams_are_the_brute_force_ones(kind):
    rng = np.random.default_rng(1)
    angles = {"uniform": np.linspace(-np.pi, np.pi, 360, endpoint=False),
              "random": np.sort(rng.uniform(-1.0, 2.0, 50)),
              "closed": np.linspace(-np.pi, np.pi, 37),  # first and last beams coincide
              "unordered": rng.uniform(-np.pi, np.pi, 40)}[kind]
    bearing = np.concatenate([rng.uniform(-8.0, 8.0, 500), angles + 1e-12, angles - np.pi])
    diff = np.abs((bearing[:, None] - angles[None, :] + np.pi) % (2 * np.pi) - np.pi)
    beam, off = nearest_beams(bearing, angles)
    np.testing.assert_array_equal(beam, diff.argmin(axis=1))
    np.testing.assert_array_equal(off, diff.min(axis=1))


def test_distance_to_a_scans_surface_joins_only_close_neighbours():
    rng = np.random.default_rng(2)
    angle = np.sort(rng.uniform(-np.pi, np.pi, 200))
    radius = 2.0 + np.repeat(rng.uniform(0.0, 2.0, 20), 10)  # steps: some joints are gaps
    scan = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    points = rng.uniform(-4.0, 4.0, size=(60, 2))
    a, b = scan[:-1], scan[1:]
    joined = np.hypot(*(b - a).T) <= CLUSTER_GAP
    a = np.concatenate([a[joined], scan])
    b = np.concatenate([b[joined], scan])
    ab = b - a
    u = np.clip(((points[:, None] - a[None]) * ab[None]).sum(axis=2)
                / np.maximum((ab * ab).sum(axis=1), 1e-12)[None], 0.0, 1.0)
    want = np.hypot(*(points[:, None] - (a[None] + u[..., None] * ab[None])).transpose(2, 0, 1))
    np.testing.assert_allclose(distance_to_polyline(points, scan, CLUSTER_GAP),
                               want.min(axis=1), atol=1e-12)


def test_arc_clearances_see_static_and_moving_returns():
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-1.0, 1.0, size=(2, 30, 12))
    points = rng.uniform(-2.0, 2.0, size=(80, 2))
    moving_x, moving_y = rng.uniform(-2.0, 2.0, size=(2, 12, 5))
    static = np.sqrt((x[..., None] - points[:, 0]) ** 2
                     + (y[..., None] - points[:, 1]) ** 2).min(axis=2)
    moving = np.sqrt((x[..., None] - moving_x[None]) ** 2
                     + (y[..., None] - moving_y[None]) ** 2).min(axis=2)
    np.testing.assert_array_equal(arc_distances(x, y, points, moving_x, moving_y),
                                  np.minimum(static, moving))


def test_small_clusters_are_the_scans_compact_runs_wrapping_round():
    angle = np.linspace(-np.pi, np.pi, 180, endpoint=False)
    radius = np.full(180, 3.0)
    radius[40:46] = 1.0  # a small thing: a compact run of 6 returns
    radius[100:102] = 1.5  # too few returns
    radius[:3] = radius[-3:] = 2.0  # a small thing across the scan's ends
    points = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    world = points + (10.0, 20.0)
    members, centres = small_clusters(points, world)
    found = sorted(sorted(m.tolist()) for m in members)
    assert [0, 1, 2, 177, 178, 179] in found and list(range(40, 46)) in found
    assert not any(100 in m for m in found)
    for m, centre in zip(members, centres):
        assert np.hypot(*(points[m] - points[m].mean(axis=0)).T).max() <= CLUSTER_SIZE
        np.testing.assert_allclose(centre, world[m].mean(axis=0))
