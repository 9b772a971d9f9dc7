"""Many casts in one pass (RayCaster.cast_many) give what pymunk gives, ray for ray."""
from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest
from test_raycast import add_robot, arena, box, mixed_world

from pymunk_bot.sensors.raycast import RayCaster, reference_cast
from pymunk_bot.sensors.raycast.sides import sides_many


def sharp_world(seed: int, size: float = 12.0) -> tuple[pymunk.Space, list[pymunk.Body]]:
    """Boxes, circles, segments and moving robots, with no rounded polygon (the batch's case)."""
    rng = np.random.default_rng(seed)
    space = arena(size, size)
    sb = space.static_body
    for _ in range(25):
        angle = rng.uniform(0, math.pi) if rng.random() < 0.5 else 0.0
        space.add(box(sb, *rng.uniform(0, size, 2), *rng.uniform(0.1, 1.2, 2), angle))
    for _ in range(4):
        space.add(pymunk.Circle(sb, rng.uniform(0.05, 0.6), tuple(rng.uniform(0, size, 2))))
    for _ in range(4):
        a = rng.uniform(0, size, 2)
        space.add(pymunk.Segment(sb, tuple(a), tuple(a + rng.uniform(-3, 3, 2)),
                                 float(rng.choice([0.0, 0.02, 0.3]))))
    robots = [add_robot(space, *rng.uniform(0.5, size - 0.5, 2), group=i + 1) for i in range(12)]
    for body in robots:
        body.velocity = tuple(rng.uniform(-1, 1, 2))
    for _ in range(5):
        space.step(0.05)
    return space, robots


def cast_all(space: pymunk.Space, robots: list[pymunk.Body], beams: int, max_range: float,
             rng: np.random.Generator, extra_origins: int = 8):
    """Casts from every robot (its own filter) and from random points (no filter)."""
    origins = [tuple(b.position) for b in robots]
    filters = [pymunk.ShapeFilter(group=i + 1) for i in range(len(robots))]
    origins += [tuple(rng.uniform(-0.5, 12.5, 2)) for _ in range(extra_origins)]
    filters += [pymunk.ShapeFilter()] * extra_origins
    angles = [rng.uniform(-math.pi, math.pi) + np.linspace(-math.pi, math.pi, beams, endpoint=False)
              for _ in origins]
    return origins, angles, [max_range] * len(origins), filters


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("beams", [64, 360])
@pytest.mark.parametrize("extra", [8, 40])  # 20 casts, or 52 (side lines found as arrays)
def test_batched_casts_equal_pymunk_bit_for_bit(seed, beams, extra):
    space, robots = sharp_world(seed)
    caster = RayCaster(space)
    caster.begin_frame()
    rng = np.random.default_rng(100 + seed)
    requests = cast_all(space, robots, beams, float(rng.uniform(3.0, 15.0)), rng, extra)
    got = caster.cast_many(*requests)
    for origin, angles, max_range, f, ranges in zip(*requests, got):
        want = reference_cast(space, origin, angles, max_range, f)
        assert np.array_equal(ranges, want), (origin, np.flatnonzero(ranges != want)[:5])


def test_batched_casts_hand_hard_origins_to_the_single_cast():
    """Rounded polygons, origins inside shapes: still what pymunk says."""
    space, robots = mixed_world(3)
    caster = RayCaster(space)
    caster.begin_frame()
    rng = np.random.default_rng(7)
    requests = cast_all(space, robots, 90, 8.0, rng, extra_origins=20)
    origins = list(requests[0]) + [(1.5, 1.3)]  # inside the rounded triangle
    angles = list(requests[1]) + [np.linspace(0.0, 6.0, 90)]
    requests = (origins, angles, list(requests[2]) + [8.0], list(requests[3]) + [pymunk.ShapeFilter()])
    for origin, a, max_range, f, ranges in zip(*requests, caster.cast_many(*requests)):
        assert np.array_equal(ranges, reference_cast(space, origin, a, max_range, f))


def test_origins_on_and_just_off_shapes_get_pymunks_start_inside_answer():
    """The start-inside check asks pymunk only about origins near an admitted shape's bounding
    circle: origins on a surface, 1e-10 m off it (inside pymunk's query radius), 1 mm off,
    inside, and inside a shape the filter rejects, all still give pymunk's ranges."""
    space = arena(6.0, 6.0)
    sb = space.static_body
    space.add(box(sb, 2.0, 2.0, 1.0, 1.0, 0.0), pymunk.Circle(sb, 0.5, (4.5, 4.0)))
    hidden = pymunk.Circle(sb, 0.4, (1.0, 4.5))
    hidden.filter = pymunk.ShapeFilter(group=7)
    space.add(hidden)
    caster = RayCaster(space)
    caster.begin_frame()
    origins = [(2.5, 2.0), (2.5 + 1e-10, 2.0), (2.501, 2.2), (2.2, 2.1),  # the box's side
               (5.0, 4.0), (5.0 + 1e-10, 4.0), (4.5, 4.2),  # the circle's rim, its inside
               (1.0, 4.5), (1.3, 4.5), (3.3, 3.3)]  # inside the hidden circle; open floor
    filters = [pymunk.ShapeFilter()] * 7 + [pymunk.ShapeFilter(group=7)] * 2 + [
        pymunk.ShapeFilter()]
    angles = [np.linspace(-math.pi, math.pi, 72, endpoint=False) + 0.01 * i
              for i in range(len(origins))]
    requests = (origins, angles, [5.0] * len(origins), filters)
    for origin, a, max_range, f, ranges in zip(*requests, caster.cast_many(*requests)):
        assert np.array_equal(ranges, reference_cast(space, origin, a, max_range, f)), origin


def test_a_frame_sees_moved_bodies_only_after_the_next_begin_frame():
    space = arena(10.0, 10.0)
    body = add_robot(space, 5.0, 5.0, group=1)
    caster = RayCaster(space)
    caster.begin_frame()
    ahead = np.array([0.0])
    before = caster.cast((2.0, 5.0), ahead, 9.0)
    body.position = (7.0, 5.0)
    space.reindex_shapes_for_body(body)
    caster.begin_frame()
    after = caster.cast((2.0, 5.0), ahead, 9.0)
    assert before[0] == pytest.approx(2.8) and after[0] == pytest.approx(4.8)


def test_robots_at_rest_among_moving_ones_match_pymunk_every_frame():
    """Tables are reused for a filter whose visible bodies rested; each frame still equals
    pymunk, for the batch and the single cast, while robots stop and start in turn."""
    space, robots = sharp_world(3)
    caster = RayCaster(space)
    rng = np.random.default_rng(7)
    for frame in range(12):
        movers = frame % 3  # none, then one (it alone sees a world at rest), then two
        resting = set(rng.choice(len(robots), size=len(robots) - movers, replace=False).tolist())
        for k, body in enumerate(robots):
            body.velocity = (0.0, 0.0) if k in resting else tuple(rng.uniform(-1, 1, 2))
            body.angular_velocity = 0.0
        space.step(0.05)
        caster.begin_frame()
        origins, angles, ranges, filters = cast_all(space, robots, 90, 8.0, rng, extra_origins=2)
        batched = caster.cast_many(origins, angles, ranges, filters)
        for o, a, r, f, got in zip(origins, angles, ranges, filters, batched):
            want = reference_cast(space, o, a, r, f)
            assert np.array_equal(got, want), f"frame {frame}"
            assert np.array_equal(caster.cast(o, a, r, f), want), f"frame {frame}"


def test_endpoints_of_many_casts_are_those_of_each():
    from pymunk_bot.sensors.raycast.reference import endpoints, endpoints_many
    rng = np.random.default_rng(2)
    ox, oy, r = rng.uniform(-50, 50, 5), rng.uniform(-50, 50, 5), rng.uniform(0.1, 30, 5)
    angles = rng.uniform(-10, 10, (5, 73))
    cos, sin, ends = endpoints_many(ox, oy, angles, r)
    for k in range(5):
        c, s, e = endpoints(float(ox[k]), float(oy[k]), angles[k], float(r[k]))
        assert np.array_equal(cos[k], c) and np.array_equal(sin[k], s)
        assert np.array_equal(ends[k], e)


def test_compiled_end_points_are_numpys_bit_for_bit():
    """The compiled casts build their segments with the C library's cos and sin: the very
    segments reference_cast queries (numpy's), or the compiled LiDAR would not be pymunk's."""
    pytest.importorskip("numba")
    from pymunk_bot.sensors.raycast.compiled import endpoints_rows
    from pymunk_bot.sensors.raycast.reference import endpoints_many
    rng = np.random.default_rng(3)
    for spread in (math.pi, 50.0, 1e4):
        ox, oy, r = rng.uniform(-80, 80, 40), rng.uniform(-80, 80, 40), rng.uniform(0.1, 30, 40)
        angles = rng.uniform(-spread, spread, (40, 500))
        ends = np.empty((40, 2, 500))
        endpoints_rows(ox, oy, angles, r, ends)
        assert np.array_equal(ends, endpoints_many(ox, oy, angles, r)[2])


def test_compiled_mover_builds_numpys_table_bit_for_bit():
    from pymunk_bot.sensors.raycast.cache import SceneCache
    from pymunk_bot.sensors.raycast.compiled import move_into
    space, robots = sharp_world(1)
    for _ in range(3):
        numpy_cache, compiled_cache = SceneCache(space), SceneCache(space, move_into)
        (a,), bound_a, _, _ = numpy_cache.world(pymunk.ShapeFilter())
        (b,), bound_b, _, _ = compiled_cache.world(pymunk.ShapeFilter())
        assert np.array_equal(a.rows, b.rows) and np.array_equal(a.owner, b.owner)
        assert a.counts == b.counts and np.array_equal(bound_a, bound_b)
        space.step(0.05)


def test_side_lines_are_found_alike_for_few_and_many_origins():
    """A few casts look side lines up origin by origin, many as arrays: the same answers,
    for origins on box side lines, a hair off them, at corners and anywhere."""
    space, _ = sharp_world(3)
    caster = RayCaster(space)
    caster.begin_frame()
    caster.cast((6.0, 6.0), np.linspace(-3, 3, 64), 5.0)  # builds the scene's side lines
    xs, ys = caster._cache.side_x, caster._cache.side_y
    rng = np.random.default_rng(7)
    points = []
    for _ in range(40):
        x, y = float(rng.choice(xs)), float(rng.choice(ys))
        off = float(rng.choice([0.0, 1e-12, -1e-9, 1e-6, 0.3]))
        points += [(x + off, float(rng.uniform(0, 12))), (float(rng.uniform(0, 12)), y - off),
                   (x, y + off)]
    ox, oy = np.array(points).T.copy()
    scale = 1.0 + np.abs(ox) + np.abs(oy) + 5.0
    many = sides_many(caster._cache, ox, oy, scale)
    assert ox.shape[0] > 32 and many[2].any() and (many[1] > 0).any()  # corners and sides met
    for start in range(0, ox.shape[0], 16):
        chunk = slice(start, start + 16)
        sides, n_sides, cornered = sides_many(caster._cache, ox[chunk], oy[chunk], scale[chunk])
        assert np.array_equal(cornered, many[2][chunk])
        free = ~cornered  # a cornered origin takes the single cast's path: its sides unused
        assert np.array_equal(n_sides[free], many[1][chunk][free])
        assert np.array_equal(sides[free], many[0][chunk][free])


def test_body_reader_gives_pymunks_own_transforms():
    """One batch read gives every moving body's (cos, sin, tx, ty) exactly as pymunk's
    rotation_vector and position, also after bodies come and go."""
    from pymunk_bot.sensors.raycast.primitives import BodyReader, transforms

    space, robots = sharp_world(4)
    spare = pymunk.Body(body_type=pymunk.Body.KINEMATIC)  # shapeless, before the crate
    space.add(spare)
    crate = pymunk.Body(2.0, 1.0)
    crate.position, crate.angle = (3.0, 3.0), 0.7
    space.add(crate, pymunk.Poly(crate, [(0.1, 0.1), (0.6, 0.1), (0.3, 0.5)]))  # cog off the origin
    bodies = robots + [crate]
    reader = BodyReader(space, bodies)
    assert reader.batched
    rng = np.random.default_rng(2)
    for step in range(20):
        for body in bodies:
            body.angular_velocity = float(rng.uniform(-40, 40))
        space.step(0.05)
        if step == 10:  # a shapeless body leaves: pymunk moves the last body into its place
            space.remove(spare)
        assert np.array_equal(reader.read(), transforms(bodies))
