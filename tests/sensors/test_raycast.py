"""RayCaster must return what pymunk's segment_query_first returns, ray for ray."""
from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pymunk.autogeometry import convex_decomposition

from pymunk_bot.sensors.raycast import RayCaster, reference_cast

TOL = 1e-6  # [m]
FAN = np.linspace(-math.pi, math.pi, 360, endpoint=False)


# ---------------------------------------------------------------------------- world builders
def box(body: pymunk.Body, cx: float, cy: float, w: float, h: float, angle: float = 0.0) -> pymunk.Poly:
    c, s = math.cos(angle), math.sin(angle)
    return pymunk.Poly(body, [(-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2)],
                       pymunk.Transform(a=c, b=s, c=-s, d=c, tx=cx, ty=cy))


def arena(width: float, height: float, wall: float = 0.3) -> pymunk.Space:
    """Empty space with four static wall boxes just outside [0, width] x [0, height]."""
    space = pymunk.Space()
    sb = space.static_body
    space.add(box(sb, width / 2, -wall / 2, width + 2 * wall, wall),
              box(sb, width / 2, height + wall / 2, width + 2 * wall, wall),
              box(sb, -wall / 2, height / 2, wall, height),
              box(sb, width + wall / 2, height / 2, wall, height))
    return space


def add_robot(space: pymunk.Space, x: float, y: float, group: int, radius: float = 0.2) -> pymunk.Body:
    body = pymunk.Body(1.0, pymunk.moment_for_circle(1.0, 0.0, radius))
    body.position = (x, y)
    shape = pymunk.Circle(body, radius)
    shape.filter = pymunk.ShapeFilter(group=group)
    space.add(body, shape)
    return body


def mixed_world(seed: int, size: float = 12.0) -> tuple[pymunk.Space, list[pymunk.Body]]:
    """Every shape kind the simulator uses, static and moving, plus robots with groups."""
    rng = np.random.default_rng(seed)
    space = arena(size, size)
    sb = space.static_body
    for _ in range(25):  # boxes, half of them rotated
        angle = rng.uniform(0, math.pi) if rng.random() < 0.5 else 0.0
        space.add(box(sb, *rng.uniform(0, size, 2), *rng.uniform(0.1, 1.2, 2), angle))
    for _ in range(4):  # static circles (the offset places them)
        space.add(pymunk.Circle(sb, rng.uniform(0.05, 0.6), tuple(rng.uniform(0, size, 2))))
    for _ in range(4):  # thin and thick segments (a thick segment is a capsule)
        a = rng.uniform(0, size, 2)
        radius = float(rng.choice([0.0, 0.02, 0.3]))
        space.add(pymunk.Segment(sb, tuple(a), tuple(a + rng.uniform(-3, 3, 2)), radius))
    outline = [(0, 0), (3, 0), (3, 3), (2, 3), (2, 1), (1, 1), (1, 3), (0, 3), (0, 0)]  # a U, CCW
    ox, oy = rng.uniform(0, size - 3, 2)
    for part in convex_decomposition(outline, 0.0):
        space.add(pymunk.Poly(sb, [(x + ox, y + oy) for x, y in part]))
    space.add(pymunk.Poly(sb, [(1, 1), (2, 1), (1.5, 1.8)], radius=0.15))  # rounded triangle
    movers = []
    for _ in range(6):  # pushable boxes, each with an offset circle too, kicked and stepped
        body = pymunk.Body(1.0, 1.0)
        body.position = tuple(rng.uniform(1, size - 1, 2))
        body.angle = rng.uniform(-math.pi, math.pi)
        space.add(body, box(body, 0.0, 0.0, *rng.uniform(0.2, 0.8, 2)),
                  pymunk.Circle(body, 0.1, (0.3, 0.1)))
        body.velocity = tuple(rng.uniform(-1, 1, 2))
        body.angular_velocity = rng.uniform(-3, 3)
        movers.append(body)
    robots = [add_robot(space, *rng.uniform(0.5, size - 0.5, 2), group=i + 1) for i in range(5)]
    for _ in range(7):
        space.step(0.05)
    return space, robots


def assert_same(space: pymunk.Space, caster: RayCaster, origin, angles, max_range,
                shape_filter=pymunk.ShapeFilter()) -> np.ndarray:
    want = reference_cast(space, origin, angles, max_range, shape_filter)
    got = caster.cast(origin, angles, max_range, shape_filter)
    assert got.dtype == np.float64 and got.shape == (len(angles),)
    bad = np.flatnonzero(np.abs(got - want) > TOL)
    assert bad.size == 0, (f"{bad.size} rays differ from pymunk, e.g. angle {angles[bad[0]]!r} "
                           f"from {origin}: pymunk {want[bad[0]]!r}, RayCaster {got[bad[0]]!r}")
    return got


# ---------------------------------------------------------------------------- sanity
def test_axis_aligned_walls_at_exact_distances():
    space = arena(10.0, 4.0)
    got = RayCaster(space).cast((1.0, 2.0), np.array([0.0, math.pi / 2, math.pi, -math.pi / 2]), 20.0)
    assert got == pytest.approx([9.0, 2.0, 1.0, 2.0], abs=1e-12)


def test_nothing_in_range_reads_max_range():
    space = arena(10.0, 4.0)
    assert np.all(RayCaster(space).cast((5.0, 2.0), FAN, 0.5) == 0.5)
    assert np.all(RayCaster(pymunk.Space()).cast((0.0, 0.0), FAN, 3.0) == 3.0)


def test_input_validation():
    caster = RayCaster(arena(4.0, 4.0))
    assert caster.cast((1.0, 1.0), np.array([]), 5.0).shape == (0,)
    for bad_range in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(ValueError):
            caster.cast((1.0, 1.0), FAN, bad_range)
    with pytest.raises(ValueError):
        caster.cast((1.0, 1.0), np.zeros((2, 3)), 5.0)
    with pytest.raises(ValueError):
        caster.cast((1.0, 1.0), np.array([0.0, math.nan]), 5.0)


# ---------------------------------------------------------------------------- equality with pymunk
@pytest.mark.parametrize("seed", range(12))
def test_random_mixed_worlds_match_pymunk(seed):
    space, robots = mixed_world(seed)
    caster = RayCaster(space)
    rng = np.random.default_rng(100 + seed)
    fans = [FAN, FAN + rng.uniform(0, 2 * math.pi),  # a fan that wraps past +pi
            rng.uniform(-20, 20, 200),                # unsorted, outside [-pi, pi)
            np.repeat(rng.uniform(-4, 4, 50), 2)]     # duplicates
    for k in range(48):
        origin = tuple(rng.uniform(0.05, 11.95, 2))
        shape_filter = pymunk.ShapeFilter()
        if k % 3 == 0:  # a robot's own view: its group hides itself, not the others
            who = int(rng.integers(len(robots)))
            origin, shape_filter = tuple(robots[who].position), pymunk.ShapeFilter(group=who + 1)
        max_range = float(rng.choice([0.3, 2.5, 10.0, 40.0]))
        assert_same(space, caster, origin, fans[k % 4], max_range, shape_filter)


@pytest.mark.parametrize("seed", range(6))
def test_origins_hugging_edges_match_pymunk(seed):
    """Origins a hair outside (or exactly on) polygon edges, where rounding decides."""
    space, _ = mixed_world(seed)
    caster = RayCaster(space)
    rng = np.random.default_rng(200 + seed)
    polys = [s for s in space.shapes if isinstance(s, pymunk.Poly)]
    for _ in range(80):
        poly = polys[int(rng.integers(len(polys)))]
        verts = [poly.body.local_to_world(v) for v in poly.get_vertices()]
        i = int(rng.integers(len(verts)))
        a, b = np.array(verts[i - 1]), np.array(verts[i])
        outward = np.array([(b - a)[1], -(b - a)[0]]) / np.linalg.norm(b - a)
        gap = float(rng.choice([0.0, 1e-12, 1e-9, 1e-6, 1e-3]))
        origin = tuple(a + rng.uniform(-0.2, 1.2) * (b - a) + (gap + poly.radius) * outward)
        angles = np.concatenate((FAN[::4], [math.atan2(*(np.array(v) - origin)[::-1]) for v in verts]))
        assert_same(space, caster, origin, angles, 6.0)


def test_origin_a_denormal_off_a_wall_matches_pymunk():
    """d / den underflows to -0.0, which Chipmunk accepts as a hit at alpha 0."""
    space = arena(12.0, 12.0)
    caster = RayCaster(space)
    for y in (5e-324, 1e-323, 1e-300, 0.0):
        got = assert_same(space, caster, (2.0, y), np.linspace(-math.pi, math.pi, 721), 5.0)
        assert y != 5e-324 or got[540] == 0.0  # straight up: d = 5e-324, den = -5, t = -0.0


def test_origins_ulps_from_extreme_vertices_match_pymunk():
    """A few ulps outside a rotated box's leftmost/rightmost/top/bottom vertex: on (within
    rounding) both the shape and its bounding box, where pymunk's box test decides."""
    space, _ = mixed_world(4)
    caster = RayCaster(space)
    boxes = [s for s in space.shapes
             if isinstance(s, pymunk.Poly) and s.body.body_type == pymunk.Body.STATIC]
    for poly in boxes[:20]:
        verts = [tuple(poly.body.local_to_world(v)) for v in poly.get_vertices()]
        for (x, y), (toward_x, toward_y) in [(min(verts), (-1, 0)), (max(verts), (1, 0)),
                                             (min(verts, key=lambda v: v[1]), (0, -1)),
                                             (max(verts, key=lambda v: v[1]), (0, 1))]:
            for ulps in (1, 2, 3):
                ox, oy = x, y
                for _ in range(ulps):
                    ox = math.nextafter(ox, math.inf * toward_x) if toward_x else ox
                    oy = math.nextafter(oy, math.inf * toward_y) if toward_y else oy
                assert_same(space, caster, (ox, oy), FAN, 25.0)


def test_origins_next_to_vertices_match_pymunk():
    """Within 1e-15..1e-9 m of a corner, rounding can make any nearby ray graze it."""
    space, _ = mixed_world(3)
    caster = RayCaster(space)
    rng = np.random.default_rng(300)
    polys = [s for s in space.shapes if isinstance(s, pymunk.Poly) and s.radius == 0.0]
    for _ in range(60):
        poly = polys[int(rng.integers(len(polys)))]
        vertex = np.array(poly.body.local_to_world(poly.get_vertices()[int(rng.integers(4))]))
        direction = rng.uniform(-math.pi, math.pi)
        offset = float(rng.choice([1e-15, 1e-13, 1e-11, 1e-9]))
        origin = tuple(vertex + offset * np.array([math.cos(direction), math.sin(direction)]))
        toward = direction + math.pi
        angles = np.concatenate((toward + np.linspace(-1.6, 1.6, 321), FAN[::8]))
        assert_same(space, caster, origin, angles, 5.0)


def test_grazing_rays_on_a_grid_match_pymunk():
    """Integer geometry, origins on box side lines, rays along edges and through corners."""
    space = pymunk.Space()
    sb = space.static_body
    for l, b, r, t in [(2, 2, 3, 3), (4, 1, 5, 4), (1, 5, 3, 6), (6, 6, 7, 7), (5, 2, 6, 3), (0, 0, 8, 0.5)]:
        space.add(pymunk.Poly(sb, [(l, b), (r, b), (r, t), (l, t)]))
    space.add(pymunk.Poly.create_box(sb, (1, 1)), pymunk.Segment(sb, (7, 1), (7, 4), 0.0),
              pymunk.Segment(sb, (0, 7), (3, 7), 0.25), pymunk.Circle(sb, 0.5, (4, 6)))
    caster = RayCaster(space)
    corners = [(x, y) for x in range(-1, 9) for y in range(-1, 9)]
    axes = [k * math.pi / 4 for k in range(-4, 4)] + [math.pi, 1e-17, -1e-17]
    for ox in np.arange(-1.0, 8.5, 0.5):
        for oy in np.arange(-1.0, 8.5, 0.5):
            origin = (float(ox), float(oy))
            toward = [math.atan2(y - oy, x - ox) for x, y in corners if (x, y) != origin]
            angles = np.array(axes + toward)
            for max_range in (10.0, 1.5, math.sqrt(2)):
                assert_same(space, caster, origin, angles, max_range)


def test_dense_world_match_pymunk():
    """1000 boxes and 50 robots: the nearest-first rings (occlusion culling) change no ray."""
    rng = np.random.default_rng(7)
    space = arena(20.0, 20.0)
    for _ in range(1000):
        angle = rng.uniform(0, math.pi) if rng.random() < 0.7 else 0.0
        space.add(box(space.static_body, *rng.uniform(0, 20, 2), *rng.uniform(0.2, 1.0, 2), angle))
    robots = [add_robot(space, *rng.uniform(0.5, 19.5, 2), group=i + 1) for i in range(50)]
    caster = RayCaster(space)
    for k in range(40):
        origin, shape_filter = tuple(rng.uniform(0, 20, 2)), pymunk.ShapeFilter()
        if k % 2:
            origin, shape_filter = tuple(robots[k].position), pymunk.ShapeFilter(group=k + 1)
        assert_same(space, caster, origin, FAN + k, float(rng.choice([3.0, 10.0, 30.0])), shape_filter)


# Coordinates on the walls and a hair (even a denormal) off them: where rounding decides.
EDGY = st.sampled_from([0.0, 5e-324, -5e-324, 1e-300, 1e-12, 6.0, 12.0])


@settings(max_examples=400, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(x=st.one_of(st.floats(-1.0, 13.0), EDGY), y=st.one_of(st.floats(-1.0, 13.0), EDGY),
       angles=st.lists(st.one_of(st.floats(-10.0, 10.0), st.sampled_from([0.0, math.pi / 2, math.pi])),
                       min_size=1, max_size=40),
       max_range=st.one_of(st.floats(1e-6, 30.0), st.sampled_from([6.0, 12.0])))
def test_any_rays_match_pymunk(x, y, angles, max_range):
    assert_same(HYPOTHESIS_WORLD[0], HYPOTHESIS_WORLD[1], (x, y), np.array(angles), max_range)


_space = mixed_world(99)[0]
HYPOTHESIS_WORLD = (_space, RayCaster(_space))


# ---------------------------------------------------------------------------- what rays see
def test_origin_inside_a_shape_reads_zero_like_pymunk():
    space = arena(10.0, 10.0)
    sb = space.static_body
    space.add(box(sb, 2.0, 2.0, 1.0, 1.0, 0.3), pymunk.Circle(sb, 0.5, (6.0, 2.0)),
              pymunk.Segment(sb, (2.0, 7.0), (5.0, 7.0), 0.3))
    caster = RayCaster(space)
    inside = [(2.0, 2.0), (6.1, 2.2), (3.0, 7.2), (2.0 + 0.5 * math.cos(0.3), 2.0 + 0.5 * math.sin(0.3)),
              (6.5, 2.0), (5.3, 7.0)]  # centres, and points exactly on the boundary
    for origin in inside:
        assert np.all(assert_same(space, caster, origin, FAN, 5.0) == 0.0), origin
    outside = (6.6, 2.0)
    assert np.all(assert_same(space, caster, outside, FAN, 5.0) > 0.0)


def test_robot_filter_hides_itself_but_not_others():
    space = arena(10.0, 10.0)
    me = add_robot(space, 5.0, 5.0, group=1)
    add_robot(space, 7.0, 5.0, group=2)
    caster = RayCaster(space)
    own = pymunk.ShapeFilter(group=1)
    got = assert_same(space, caster, tuple(me.position), np.array([0.0, math.pi]), 20.0, own)
    assert got == pytest.approx([2.0 - 0.2, 5.0], abs=1e-9)  # the other robot, the far wall
    # Without the group filter the ray starts inside the robot's own disc: zero, like pymunk.
    assert np.all(assert_same(space, caster, tuple(me.position), FAN, 20.0) == 0.0)


def test_categories_and_masks_follow_chipmunk_rule():
    space = arena(10.0, 10.0)
    glass = box(space.static_body, 6.0, 5.0, 0.2, 4.0)
    glass.filter = pymunk.ShapeFilter(categories=0b10, mask=0b01)  # hit only by category 1
    space.add(glass)
    caster = RayCaster(space)
    cases = {pymunk.ShapeFilter(): 0.9,                                # default collides with all
             pymunk.ShapeFilter(categories=0b01): 0.9,                 # shape mask admits category 1
             pymunk.ShapeFilter(categories=0b100): 5.0,                # shape mask rejects category 4
             pymunk.ShapeFilter(categories=0b01, mask=0b01): 5.0,      # query mask rejects category 2
             pymunk.ShapeFilter(group=3, categories=0b01): 0.9}
    for shape_filter, expected in cases.items():
        got = assert_same(space, caster, (5.0, 5.0), np.array([0.0]), 20.0, shape_filter)
        assert got[0] == pytest.approx(expected, abs=1e-9), shape_filter
    glass.filter = pymunk.ShapeFilter(group=3)  # same non-zero group as the query: invisible
    caster.invalidate()  # a filter change is not detected automatically
    got = assert_same(space, caster, (5.0, 5.0), np.array([0.0]), 20.0, pymunk.ShapeFilter(group=3))
    assert got[0] == pytest.approx(5.0, abs=1e-9)


def test_sensor_shapes_are_hit_like_pymunk():
    space = arena(10.0, 10.0)
    sensor = pymunk.Circle(space.static_body, 0.5, (7.0, 5.0))
    sensor.sensor = True
    space.add(sensor)
    got = assert_same(space, RayCaster(space), (5.0, 5.0), np.array([0.0]), 20.0)
    assert got[0] == pytest.approx(1.5, abs=1e-9)


def test_hit_exactly_at_max_range():
    space = arena(10.0, 4.0)
    caster = RayCaster(space)
    for max_range in (9.0, math.nextafter(9.0, 0.0), math.nextafter(9.0, 10.0), 8.5):
        got = assert_same(space, caster, (1.0, 2.0), np.array([0.0, 1e-3, -1e-3]), max_range)
        assert got[0] == pytest.approx(min(max_range, 9.0), abs=1e-12)


def test_thick_segments_and_rounded_polys():
    space = pymunk.Space()
    sb = space.static_body
    space.add(pymunk.Segment(sb, (2.0, -1.0), (2.0, 1.0), 0.25),
              pymunk.Poly(sb, [(-3.0, -1.0), (-2.0, -1.0), (-2.0, 1.0), (-3.0, 1.0)], radius=0.2))
    caster = RayCaster(space)
    got = assert_same(space, caster, (0.0, 0.0), np.array([0.0, math.pi]), 10.0)
    assert got == pytest.approx([1.75, 1.8], abs=1e-9)
    # Rays that pass the flat part and meet a rounded cap or corner.
    assert_same(space, caster, (0.0, 0.0), np.linspace(-0.8, 0.8, 2001), 10.0)
    assert_same(space, caster, (0.0, 0.0), np.linspace(math.pi - 0.8, math.pi + 0.8, 2001), 10.0)


# ---------------------------------------------------------------------------- changes between casts
def test_added_and_removed_shapes_are_seen():
    space = arena(10.0, 10.0)
    caster = RayCaster(space)
    east = np.array([0.0])
    assert caster.cast((5.0, 5.0), east, 20.0)[0] == pytest.approx(5.0)
    block = box(space.static_body, 7.0, 5.0, 1.0, 1.0)
    space.add(block)
    assert assert_same(space, caster, (5.0, 5.0), east, 20.0)[0] == pytest.approx(1.5)
    space.remove(block)
    assert assert_same(space, caster, (5.0, 5.0), east, 20.0)[0] == pytest.approx(5.0)
    # Remove one shape and add another in the same interval: the count stays the same.
    first, second = box(space.static_body, 8.0, 5.0, 1.0, 1.0), box(space.static_body, 6.0, 5.0, 1.0, 1.0)
    space.add(first)
    caster.cast((5.0, 5.0), east, 20.0)
    space.remove(first)
    space.add(second)
    assert assert_same(space, caster, (5.0, 5.0), east, 20.0)[0] == pytest.approx(0.5)


def test_moving_bodies_are_followed():
    space = arena(10.0, 10.0)
    body = pymunk.Body(1.0, 1.0)
    body.position = (7.0, 5.0)
    space.add(body, box(body, 0.0, 0.0, 1.0, 1.0))
    caster = RayCaster(space)
    east = np.linspace(-0.3, 0.3, 61)
    assert assert_same(space, caster, (5.0, 5.0), east, 20.0)[30] == pytest.approx(1.5)
    body.velocity, body.angular_velocity = (-1.0, 0.0), 2.0  # pushed and spun by the physics
    for _ in range(30):
        space.step(1 / 60)
    got = assert_same(space, caster, (5.0, 5.0), east, 20.0)
    assert got[30] < 1.3
    body.position, body.angle = (8.0, 5.0), 0.0  # teleported: pymunk needs a reindex
    space.reindex_shapes_for_body(body)
    assert assert_same(space, caster, (5.0, 5.0), east, 20.0)[30] == pytest.approx(2.5)
    kinematic = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    kinematic.position, kinematic.angular_velocity = (5.0, 7.0), 1.0
    space.add(kinematic, box(kinematic, 0.0, 0.0, 2.0, 0.2))
    space.step(0.3)
    assert_same(space, caster, (5.0, 5.0), FAN, 20.0)


def test_moved_static_body_is_followed():
    space = pymunk.Space()
    anchor = pymunk.Body(body_type=pymunk.Body.STATIC)
    space.add(anchor, box(anchor, 3.0, 0.0, 1.0, 1.0))
    caster = RayCaster(space)
    assert assert_same(space, caster, (0.0, 0.0), np.array([0.0]), 10.0)[0] == pytest.approx(2.5)
    anchor.position, anchor.angle = (1.0, 0.0), 0.4
    space.reindex_static()
    assert_same(space, caster, (0.0, 0.0), FAN, 10.0)


def test_static_world_with_alternating_filters_is_bit_identical():
    """The static fast path keeps per-filter work between casts; interleave filters that
    admit different parts of every kind (sharp and rounded edges, circles, segments) and
    check every ray is bit-identical to pymunk, on an even fan and on random angles."""
    rng = np.random.default_rng(7)
    space = arena(12.0, 12.0)
    sb = space.static_body
    for k in range(60):
        x, y = rng.uniform(0.5, 11.5, 2)
        kind = k % 4
        if kind == 0:
            shape = box(sb, x, y, *rng.uniform(0.2, 0.8, 2), rng.uniform(0, math.pi))
        elif kind == 1:
            shape = pymunk.Poly(sb, [(x, y), (x + 0.5, y), (x + 0.2, y + 0.4)], radius=0.05)
        elif kind == 2:
            shape = pymunk.Circle(sb, float(rng.uniform(0.1, 0.4)), (float(x), float(y)))
        else:
            shape = pymunk.Segment(sb, (x, y), (x + rng.uniform(-1, 1), y + rng.uniform(-1, 1)), 0.03)
        shape.filter = pymunk.ShapeFilter(group=k % 3, categories=1 << (k % 2))
        space.add(shape)
    caster = RayCaster(space)
    filters = [pymunk.ShapeFilter(), pymunk.ShapeFilter(group=1), pymunk.ShapeFilter(group=2),
               pymunk.ShapeFilter(mask=0b10), pymunk.ShapeFilter(categories=0b1, mask=0b1)]
    for _ in range(3):
        for shape_filter in filters:
            origin = tuple(rng.uniform(0.5, 11.5, 2))
            for angles in (FAN + rng.uniform(-math.pi, math.pi), rng.uniform(-10, 10, 50)):
                want = reference_cast(space, origin, angles, 8.0, shape_filter)
                got = caster.cast(origin, angles, 8.0, shape_filter)
                assert np.array_equal(got, want), (origin, shape_filter)


def test_the_tracer_is_compiled_unless_switched_off(tracer):
    space = arena(4.0, 4.0)
    kernel = RayCaster(space)._kernel
    assert (kernel is not None) == (tracer == "numba")
    assert RayCaster(space, compiled=False)._kernel is None


def test_robots_in_a_second_space_are_cast_against_as_in_one() -> None:
    """Spaces: robots (bodies and shapes) moved to a second Space are seen as if they were in
    the first, ray for ray, whether the caster traces or pymunk answers (the robots move
    between the Spaces between frames, as robots stepping apart do)."""
    from pymunk_bot.sensors.raycast import Spaces

    one, robots = mixed_world(3)
    two, _ = mixed_world(3)  # the same world, its robots to be split over two Spaces
    apart = pymunk.Space()
    moving = [b for b in two.bodies if b.body_type == pymunk.Body.DYNAMIC]
    caster = RayCaster(Spaces((two, apart)))
    rng = np.random.default_rng(0)
    for frame in range(4):
        for body in moving:  # every frame some robots change Space
            if rng.random() < 0.5:
                source, target = (two, apart) if body.space is two else (apart, two)
                shapes = list(body.shapes)
                source.remove(body, *shapes)
                target.add(body, *shapes)
        caster.begin_frame()
        assert any(b.space is apart for b in moving) and any(b.space is two for b in moving)
        for body in robots[:6]:
            origin = tuple(body.position)
            shape_filter = next(iter(body.shapes)).filter
            want = reference_cast(one, origin, FAN, 6.0, shape_filter)
            both = Spaces((two, apart))
            assert np.array_equal(reference_cast(both, origin, FAN, 6.0, shape_filter), want)
            assert np.array_equal(caster.cast(origin, FAN, 6.0, shape_filter), want), frame
