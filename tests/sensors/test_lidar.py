"""LiDAR: what it sees, its beam layout, rate, errors and determinism."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot, wheels

from pymunk_bot.robots.readings import LaserScan
from pymunk_bot.sensors.lidar import beam_angles

ARENA = (10.0, 8.0)


def ray_to_arena_wall(x: float, y: float, angle: float, size=ARENA) -> float:
    """Distance from (x, y) inside the arena along ``angle`` to its boundary."""
    c, s = math.cos(angle), math.sin(angle)
    hits = []
    if c > 1e-12:
        hits.append((size[0] - x) / c)
    if c < -1e-12:
        hits.append(-x / c)
    if s > 1e-12:
        hits.append((size[1] - y) / s)
    if s < -1e-12:
        hits.append(-y / s)
    return min(hits)


def ray_to_polygon(origin, angle: float, vertices: np.ndarray) -> float:
    """Distance along a ray to a convex polygon's outline (inf if missed)."""
    o = np.asarray(origin, dtype=float)
    d = np.array([math.cos(angle), math.sin(angle)])
    best = math.inf
    for a, b in zip(vertices, np.roll(vertices, -1, axis=0)):
        e = b - a
        den = d[0] * e[1] - d[1] * e[0]
        if abs(den) < 1e-15:
            continue
        w = a - o
        t = (w[0] * e[1] - w[1] * e[0]) / den
        u = (w[0] * d[1] - w[1] * d[0]) / den
        if t >= 0 and 0 <= u <= 1:
            best = min(best, t)
    return best


# ------------------------------------------------------------------ geometry


@pytest.mark.parametrize("pose,offset", [
    ([3.0, 2.5, 0.0], [0.0, 0.0, 0.0]),
    ([6.2, 5.1, 0.7], [0.0, 0.0, 0.0]),
    ([4.0, 3.0, -2.3], [0.12, -0.05, 0.4]),  # rotated robot, sensor mounted off-centre
])
def test_ranges_are_distances_to_the_walls(make_sim, pose, offset):
    lidar = {"beams": 72, "max_range": 20.0, "offset": offset}
    sim = make_sim([robot(pose, lidar=lidar)], size=ARENA)
    r = sim.robots["r"]
    x, y, theta = pose
    c, s = math.cos(theta), math.sin(theta)
    sx, sy = x + c * offset[0] - s * offset[1], y + s * offset[0] + c * offset[1]
    assert r.lidar.origin() == pytest.approx((sx, sy), abs=1e-12)
    expected = [ray_to_arena_wall(sx, sy, theta + a) for a in r.lidar.angles]
    # Beams start inside the robot's own disc and pass through it: it is invisible to itself.
    assert r.lidar.scan() == pytest.approx(expected, abs=1e-9)
    assert r.lidar.ranges == pytest.approx(expected, abs=1e-9)  # the scan taken at t = 0


def test_max_range_and_min_range(make_sim):
    near_wall = robot([0.25, 4.0, 0.0], lidar={"beams": 4, "max_range": 5.0, "min_range": 0.3})
    sim = make_sim([near_wall], size=ARENA)
    back, down, ahead, up = sim.robots["r"].lidar.scan()  # beams at -pi, -pi/2, 0, pi/2
    assert ahead == 5.0  # the far wall (9.75 m) is out of range: no return reads max_range
    assert back == 5.0  # the wall behind (0.25 m) is closer than min_range: no return either
    assert (down, up) == pytest.approx((4.0, 4.0))
    sim = make_sim([{**near_wall, "lidar": {"beams": 4, "min_range": 0.2}}], size=ARENA)
    assert sim.robots["r"].lidar.scan()[0] == pytest.approx(0.25)


def test_other_robots_are_visible_and_own_body_is_not(make_sim):
    a = robot([2.0, 4.0, 0.0], name="a", radius=0.2, lidar={"beams": 4})
    b = robot([5.0, 4.0, math.pi], name="b", radius=0.3, lidar={"beams": 4})
    sim = make_sim([a, b], size=ARENA)
    assert sim.robots["a"].lidar.scan()[2] == pytest.approx(3.0 - 0.3)
    assert sim.robots["b"].lidar.scan()[2] == pytest.approx(3.0 - 0.2)
    assert sim.robots["b"].lidar.scan()[0] == pytest.approx(5.0)  # behind b: the far wall


def test_obstacles_of_every_kind_are_seen(make_sim):
    notched = [[7, 3], [9, 3], [9, 5], [7, 5], [7, 4.5], [8, 4.5], [8, 3.5], [7, 3.5]]  # concave
    obstacles = [
        {"type": "box", "center": [0.8, 4.0], "size": [0.4, 1.0]},
        {"type": "circle", "center": [2.0, 7.0], "radius": 0.5},
        {"type": "wall", "start": [0.5, 1.0], "end": [3.5, 1.0], "thickness": 0.1},
        {"type": "polygon", "points": notched},
    ]
    sim = make_sim([robot([2.0, 4.0, 0.0], lidar={"beams": 4})], obstacles, size=ARENA)
    behind, below, ahead, above = sim.robots["r"].lidar.scan()
    assert behind == pytest.approx(2.0 - 1.0)  # box face
    assert above == pytest.approx(7.0 - 0.5 - 4.0)  # circle
    assert below == pytest.approx(4.0 - 1.05)  # the wall's upper face
    assert ahead == pytest.approx(8.0 - 2.0)  # into the polygon's notch, to its inner end


def test_a_pushed_box_is_seen_where_it_went(make_sim):
    crate = {"type": "box", "center": [3.0, 4.0], "size": [0.4, 0.4], "movable": True, "mass": 1.0}
    sim = make_sim([robot([2.0, 4.0, 0.0], lidar={"beams": 4, "rate": 60.0},
                          controller=wheels(0.8, 0.8))], [crate], size=ARENA)
    r = sim.robots["r"]
    sim.run(4.0)
    r.set_wheel_speeds(-0.5, -0.5)  # back off so there is a gap to measure
    sim.run(1.5)
    box = sim.world.obstacles[0]
    assert box.body.position.x > 4.5  # pushed well away from where it started
    corners = np.array([tuple(box.body.local_to_world(v)) for v in box.shapes[0].get_vertices()])
    expected = ray_to_polygon(r.lidar.origin(), r.pose[2], corners)
    assert expected > 0.5
    assert r.lidar.scan()[2] == pytest.approx(expected, abs=1e-9)
    assert r.lidar.ranges[2] == pytest.approx(expected, abs=1e-9)  # the periodic scan, after the tick


# ------------------------------------------------------------------ layout


@pytest.mark.parametrize("beams", [1, 2, 5, 360, 361])
def test_full_circle_has_equal_steps_and_no_duplicate_at_pi(beams):
    angles = beam_angles(beams, 2 * math.pi)
    step = 2 * math.pi / beams
    assert len(angles) == beams
    assert np.allclose(np.diff(angles), step)
    assert angles[-1] - angles[0] == pytest.approx(2 * math.pi - step)  # the circle closes once
    assert angles[beams // 2] == 0.0  # a beam straight ahead
    assert angles.min() >= -math.pi - 1e-12 and angles.max() < math.pi
    wrapped = np.round(np.mod(angles, 2 * math.pi), 9) % round(2 * math.pi, 9)
    assert len(np.unique(wrapped)) == beams


@pytest.mark.parametrize("beams,fov", [(1, 1.0), (2, 1.0), (181, math.pi), (270, 4.7)])
def test_partial_fov_is_centred_on_the_heading_with_beams_at_both_ends(beams, fov):
    angles = beam_angles(beams, fov)
    assert len(angles) == beams
    if beams == 1:
        assert angles[0] == 0.0
        return
    assert (angles[0], angles[-1]) == pytest.approx((-fov / 2, fov / 2))
    assert np.allclose(np.diff(angles), fov / (beams - 1))
    assert angles + angles[::-1] == pytest.approx(np.zeros(beams), abs=1e-12)


def test_sensor_angles_include_the_mounting_yaw(make_sim):
    lidar = {"beams": 3, "fov": 1.0, "offset": [0.0, 0.0, 0.5]}
    sim = make_sim([robot([5, 4, 0.0], lidar=lidar)], size=ARENA)
    assert sim.robots["r"].lidar.angles == pytest.approx([0.0, 0.5, 1.0])


# ------------------------------------------------------------------ timing


def test_scans_at_the_sensor_rate_from_t0(make_sim):
    sim = make_sim([robot([5, 4, 0.0], lidar={"beams": 8, "rate": 10.0},
                          controller=wheels(0.5, 0.7))], size=ARENA)
    r = sim.robots["r"]
    assert r.lidar.latest.time == 0.0  # controllers have a scan from the start
    changed_at = []
    previous = r.lidar.latest
    for _ in range(60):
        sim.step()
        if r.lidar.latest is not previous:
            changed_at.append(sim.steps)
            assert r.lidar.latest.time == pytest.approx(sim.time)
            assert not np.array_equal(r.lidar.latest.ranges, previous.ranges)  # it moved
            previous = r.lidar.latest
    assert changed_at == [6, 12, 18, 24, 30, 36, 42, 48, 54, 60]  # every 6th tick of 60 Hz


@pytest.mark.parametrize("rate,expected_steps", [
    (7.0, [9, 18, 26, 35, 43, 52, 60]),  # first tick at or after k/7 s, no drift
    (200.0, list(range(1, 61))),  # faster than the physics: once per tick
])
def test_rates_that_do_not_divide_the_tick(make_sim, rate, expected_steps):
    sim = make_sim([robot([5, 4, 0.0], lidar={"beams": 8, "rate": rate})], size=ARENA)
    r = sim.robots["r"]
    steps = []
    for _ in range(60):
        before = r.lidar.latest
        sim.step()
        if r.lidar.latest is not before:
            steps.append(sim.steps)
    assert steps == expected_steps


def test_controllers_see_the_latest_scan(make_sim):
    sim = make_sim([robot([5, 4, 0.0], lidar={"beams": 8})], size=ARENA)
    sim.run(0.25)
    scan = sim.observe(sim.robots["r"]).scan
    assert isinstance(scan, LaserScan)
    assert scan is sim.robots["r"].lidar.latest and scan.time == pytest.approx(0.2)
    with pytest.raises(ValueError):
        scan.ranges[0] = 1.0  # shared with every reader: read-only


# ------------------------------------------------------------------ errors


def test_range_noise_has_the_configured_mean_and_spread(make_sim):
    noise = 0.05
    sim = make_sim([robot([5, 4, 0.3], lidar={"beams": 2000, "noise_std": noise})], size=ARENA)
    lidar = sim.robots["r"].lidar
    true = lidar.true_ranges()
    errors = np.concatenate([lidar.scan() - true for _ in range(10)])  # 20,000 beams
    assert abs(errors.mean()) < 4 * noise / math.sqrt(errors.size)
    assert errors.std() == pytest.approx(noise, rel=0.03)


def test_noisy_ranges_stay_within_the_limits(make_sim):
    lidar = {"beams": 720, "noise_std": 0.5, "min_range": 0.3, "max_range": 4.0}
    sim = make_sim([robot([1.0, 4.0, 0.0], lidar=lidar)], size=ARENA)
    ranges = np.concatenate([sim.robots["r"].lidar.scan() for _ in range(10)])
    assert ranges.min() == 0.3 and ranges.max() == 4.0  # clipped, both limits reached


def test_dropout_removes_the_configured_share_of_returns(make_sim):
    p = 0.2
    sim = make_sim([robot([5, 4, 0.0], lidar={"beams": 3600, "dropout": p})], size=ARENA)
    lidar = sim.robots["r"].lidar
    true = lidar.true_ranges()
    assert true.max() < lidar.config.max_range  # every beam has a return without dropout
    ranges = np.concatenate([lidar.scan() for _ in range(5)])
    dropped = ranges == lidar.config.max_range
    assert dropped.mean() == pytest.approx(p, abs=4 * math.sqrt(p * (1 - p) / ranges.size))
    kept = ~dropped
    assert np.array_equal(ranges[kept], np.tile(true, 5)[kept])  # the rest are untouched


def test_scans_are_seeded_and_on_demand_scans_do_not_disturb_them(make_sim):
    def periodic_scans(seed, extra_scans):
        sim = make_sim([robot([5, 4, 0.0], lidar={"beams": 90, "noise_std": 0.02, "dropout": 0.1},
                              controller=wheels(0.3, 0.4))], seed=seed, size=ARENA)
        lidar, scans = sim.robots["r"].lidar, []
        for _ in range(30):
            sim.step()
            for _ in range(extra_scans):
                lidar.scan()
            scans.append(lidar.ranges.copy())
        return np.array(scans)

    a = periodic_scans(4, 0)
    assert np.array_equal(a, periodic_scans(4, 0))
    assert np.array_equal(a, periodic_scans(4, 2))
    assert not np.array_equal(a, periodic_scans(5, 0))


def test_reset_frees_the_old_world(make_sim):
    """Training loops reset thousands of times: LiDAR must not keep old worlds alive."""
    import gc
    import weakref

    sim = make_sim([robot([5, 4, 0.0], lidar={"beams": 8}), robot([2, 2, 0.0], name="b", lidar={})],
                   size=ARENA)
    old_space = weakref.ref(sim.space)
    sim.run(0.2)
    sim.reset()
    gc.collect()
    assert old_space() is None
    assert sim.robots["r"].lidar.scan() == pytest.approx(sim.robots["r"].lidar.true_ranges())
