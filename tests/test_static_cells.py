"""The substep gate's index of the fixed world never says a fixed shape is out of reach when
pymunk's point query finds one, and keeps up when shapes come or go, and when told fixed bodies moved."""
from __future__ import annotations

import numpy as np
import pymunk
import pytest

from pymunk_bot.physics.static_cells import StaticCells


def _world(rng: np.random.Generator) -> tuple[pymunk.Space, pymunk.Body]:
    space = pymunk.Space()
    for _ in range(15):
        x, y = rng.uniform(-20.0, 20.0, 2)
        kind = rng.integers(3)
        if kind == 0:
            shape: pymunk.Shape = pymunk.Circle(space.static_body, rng.uniform(0.05, 1.0), (x, y))
        elif kind == 1:
            shape = pymunk.Segment(space.static_body, (x, y), tuple(rng.uniform(-20.0, 20.0, 2)),
                                   rng.uniform(0.0, 0.1))
        else:
            body = pymunk.Body(body_type=pymunk.Body.STATIC)
            body.position, body.angle = (x, y), rng.uniform(0.0, 3.0)
            space.add(body)
            shape = pymunk.Poly.create_box(body, tuple(rng.uniform(0.1, 3.0, 2)))
        space.add(shape)
    robot = pymunk.Body(1.0, 1.0)
    space.add(robot, pymunk.Circle(robot, 0.2))  # a mover: never counted as fixed
    return space, robot


def _asked(seed: int, points: int, farthest: float):
    """A random world of fixed shapes and a robot, its cells, and random points [m] with a
    random distance [m] each, up to ``farthest``."""
    rng = np.random.default_rng(seed)
    space, robot = _world(rng)
    xy = rng.uniform(-25.0, 25.0, (points, 2))
    return space, robot, StaticCells(space, {robot}), xy, rng.uniform(0.0, farthest, points)


@pytest.mark.parametrize("seed", range(4))
def test_no_fixed_shape_within_reach_is_missed(seed):
    space, robot, cells, xy, look = _asked(seed, 4000, 3.0)
    near = cells.near(xy, look)
    for (x, y), r, maybe in zip(xy.tolist(), look.tolist(), near.tolist()):
        found = [h for h in space.point_query((x, y), r, pymunk.ShapeFilter())
                 if h.shape.body is not robot]
        assert maybe or not found, (x, y, r)
    assert near.mean() < 0.9  # and it does say "none" where the world is empty


@pytest.mark.parametrize("seed", range(4))
def test_the_clearance_brackets_the_distance_to_the_nearest_fixed_shape(seed):
    space, robot, cells, xy, most = _asked(seed, 3000, 4.0)
    bound, within = cells.clearance(xy, most)
    fixed = [shape for shape in space.shapes if shape.body is not robot]
    for (x, y), limit, clear, far in zip(xy.tolist(), most.tolist(), bound.tolist(),
                                         within.tolist()):
        nearest = min(shape.point_query((x, y)).distance for shape in fixed)
        assert 0.0 <= clear <= limit and clear <= max(nearest, 0.0), (x, y, clear, nearest)
        assert nearest <= far, (x, y, nearest, far)  # pymunk, asked that far, finds it
    assert np.mean(bound > 0.5 * most) > 0.5  # and they are no trivial bounds
    assert np.mean(np.isfinite(within)) > 0.2


def test_the_index_follows_shapes_that_come_go_and_move():
    space = pymunk.Space()
    robot = pymunk.Body(1.0, 1.0)
    space.add(robot, pymunk.Circle(robot, 0.2))
    cells = StaticCells(space, {robot})
    here, reach = np.array([[5.0, 5.0]]), np.array([0.5])
    assert not cells.near(here, reach)[0]  # nothing fixed at all
    box = pymunk.Body(body_type=pymunk.Body.STATIC)
    box.position = (20.0, 20.0)
    shape = pymunk.Poly.create_box(box, (1.0, 1.0))
    space.add(box, shape)
    cells.refresh()
    assert not cells.near(here, reach)[0]
    box.position = (5.6, 5.0)  # moved next to the point, and said so (World.disturb)
    space.reindex_shapes_for_body(box)
    cells.refresh()
    assert not cells.near(here, reach)[0]  # the same shapes: not looked at again
    cells.forget()
    cells.refresh()
    assert cells.near(here, reach)[0]
    space.remove(shape)
    cells.refresh()
    assert not cells.near(here, reach)[0]


def test_a_large_round_shape_is_covered_between_the_buffer_polygons_vertices():
    # shapely's buffer of a 5 m disc has its vertices on the circle and its chords sag 6 mm
    # inside it: the cells of the arc beyond a chord must be marked all the same.
    space = pymunk.Space()
    robot = pymunk.Body(1.0, 1.0)
    space.add(robot, pymunk.Circle(robot, 0.2, (50.0, 50.0)),
              pymunk.Circle(space.static_body, 5.0))
    cells = StaticCells(space, {robot})
    turns = np.linspace(0.0, 2.0 * np.pi, 4001)
    xy = 5.0005 * np.column_stack([np.cos(turns), np.sin(turns)])  # 0.5 mm outside the circle
    assert cells.near(xy, np.full(turns.shape[0], 0.001)).all()


def test_a_rebuilt_world_keeps_the_cells_where_its_fixed_shapes_lie_where_they_did():
    """A run reset builds its world anew (new Space, new shapes): where the fixed shapes lie
    where they did, the cells stand (not built again, 3-11 ms a reset); where one moved, they
    are built again and follow it."""
    def world(box_x: float) -> tuple[pymunk.Space, pymunk.Body]:
        space = pymunk.Space()
        body = pymunk.Body(body_type=pymunk.Body.STATIC)
        body.position = (box_x, 0.0)
        space.add(body, pymunk.Poly.create_box(body, (1.0, 1.0)),
                  pymunk.Segment(space.static_body, (-10.0, -5.0), (10.0, -5.0), 0.1))
        robot = pymunk.Body(1.0, 1.0)
        space.add(robot, pymunk.Circle(robot, 0.2))
        return space, robot

    space, robot = world(3.0)
    cells = StaticCells(space, {robot})
    table = cells._table
    near_old, near_new = np.array([[3.0, 1.0]]), np.array([[-3.0, 1.0]])
    look = np.array([0.6])
    same, robot = world(3.0)
    assert cells.watching(same, {robot}) is cells
    assert cells._table is table  # kept
    assert cells.near(near_old, look)[0] and not cells.near(near_new, look)[0]
    moved, robot = world(-3.0)
    cells.watching(moved, {robot})
    assert cells._table is not table  # built again
    assert cells.near(near_new, look)[0] and not cells.near(near_old, look)[0]
