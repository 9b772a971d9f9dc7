"""Map geometry: outlines as march_hard traces them, rays stop where the image says, unknown is solid."""
from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest
from map_helpers import cast, turtlebot_map, write_map
from pymunk import autogeometry

from pymunk_bot.maps.outlines import add_to_space, free_disc, geometry_from_grid, trace_outlines
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.maps.ros import read_ros_map
from pymunk_bot.sensors.raycast import RayCaster

RES = 0.05  # [m]


def _unit_edges(loops) -> set:
    """Directed half-unit steps of loops (straight runs split), to compare outlines exactly."""
    edges = set()
    for loop in loops:
        for a, b in zip(loop[:-1], loop[1:]):
            a, b = np.asarray(a, float), np.asarray(b, float)
            n = int(round(2 * np.abs(b - a).max()))
            for k in range(n):
                p, q = a + (b - a) * k / n, a + (b - a) * (k + 1) / n
                edges.add((tuple(np.round(p * 2) / 2), tuple(np.round(q * 2) / 2)))
    return edges


def test_outlines_are_the_staircase_march_hard_traces():
    rng = np.random.default_rng(0)
    for _ in range(25):
        shape = rng.integers(2, 20, size=2)
        mask = np.pad(rng.random(shape) < rng.uniform(0.2, 0.7), 1, constant_values=True)
        reference = autogeometry.march_hard(
            pymunk.BB(0, 0, mask.shape[1] - 1, mask.shape[0] - 1), mask.shape[1], mask.shape[0],
            0.5, lambda p: float(mask[round(p[1]), round(p[0])]))
        ours = trace_outlines(mask)
        assert _unit_edges([[(v.x, v.y) for v in line] for line in reference]) == _unit_edges(ours)
        assert all(np.array_equal(loop[0], loop[-1]) for loop in ours)


def _tb3(tmp_path):
    return read_ros_map(write_map(tmp_path, turtlebot_map(), origin="[-9.6, -9.6, 0.0]"))


def test_turtlebot_map_walls_stop_rays_where_the_image_says(tmp_path):
    grid = _tb3(tmp_path)
    geometry = geometry_from_grid(grid)
    space = pymunk.Space()
    add_to_space(space, geometry)
    # The ring's inner faces: cells 99..284 are free inside (pixels a + 3 .. b - 4), so the
    # walls' inner faces lie at -9.6 + 99 * 0.05 = -4.65 and -9.6 + 285 * 0.05 = 4.65.
    origin = (1.2, 0.6)  # free: between the pillars
    assert free_disc(geometry, *origin, 0.2)
    for angle, expected in ((0.0, 4.65 - 1.2), (math.pi, 1.2 + 4.65), (-math.pi / 2, 0.6 + 4.65)):
        assert cast(space, origin, angle) == pytest.approx(expected, abs=RES)
    # A pillar (a disc of radius 4 cells at the room's centre) stops a ray within a cell.
    assert cast(space, (-1.0, 0.0), 0.0) == pytest.approx(1.0 - 0.2, abs=RES)


def test_room_is_not_filled_and_rays_agree_with_the_raycaster(tmp_path):
    geometry = geometry_from_grid(_tb3(tmp_path))
    space = pymunk.Space()
    add_to_space(space, geometry)
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    ranges = RayCaster(space).cast((1.2, 0.6), angles, 12.0)
    assert ranges.min() > 0.3  # nothing encloses the robot's spot
    reference = [cast(space, (1.2, 0.6), a, 12.0) for a in angles]
    assert np.allclose(ranges, reference, atol=1e-9)
    assert ranges.max() < 12.0  # the wall ring is closed


def test_unknown_cells_are_solid_and_outside_the_map_is_too(tmp_path):
    geometry = geometry_from_grid(_tb3(tmp_path))
    assert not free_disc(geometry, -8.0, -8.0, 0.2)  # unknown grey outside the walls
    assert not free_disc(geometry, -4.7, 0.0, 0.2)  # touching the wall
    assert not free_disc(geometry, 0.0, 0.0, 0.1)  # on a pillar
    assert not free_disc(geometry, 20.0, 0.0, 0.2)  # off the map
    open_map = geometry_from_grid(_tb3(tmp_path), unknown_is_solid=False)
    assert free_disc(open_map, -8.0, -8.0, 0.2)


def test_pillars_become_convex_pieces_and_walls_segments(tmp_path):
    geometry = geometry_from_grid(_tb3(tmp_path))
    for piece in geometry.polygons:
        assert autogeometry.area_for_poly([tuple(p) for p in piece]) > 0  # counter-clockwise
        hull = autogeometry.to_convex_hull([tuple(p) for p in piece], 1e-9)
        assert len(hull) - 1 == len(piece)  # convex: every vertex is on the hull
    centres = np.array([p.mean(axis=0) for p in geometry.polygons])
    assert len(geometry.polygons) >= 9 and np.abs(centres).max() < 3.0  # only the pillars
    assert len(geometry.segments) >= 4  # the ring's inner and outer faces


def test_diagonal_wall_has_no_gaps_between_touching_corners():
    data = np.zeros((40, 40), np.int8)
    data[np.arange(40), np.arange(40)] = 100  # cells touching only at corners
    geometry = geometry_from_grid(OccupancyGrid(data, RES))
    space = pymunk.Space()
    add_to_space(space, geometry)
    # rays from below the diagonal toward it never get through to the other side
    for x in np.linspace(0.3, 1.7, 29):
        hit = cast(space, (x, 0.05), math.pi / 2, 3.0)
        assert hit < x + RES


def test_shipped_office_map_and_floor_plan():
    from pathlib import Path

    import yaml

    from pymunk_bot.maps.files import load_world_map

    draft_path = Path("scenarios/floor_plan.yaml")
    draft = yaml.safe_load(draft_path.read_text())
    geometry = load_world_map(draft_path.parent / draft["world"]["map"])
    assert geometry.grid.unknown().any()  # SLAM-like: unknown beyond the walls
    robot = draft["robots"][0]
    assert free_disc(geometry, *robot["pose"][:2], 0.2)
    assert free_disc(geometry, *robot["goal"]["position"], 0.2)
    assert not free_disc(geometry, -0.8, -0.8, 0.1)  # the unknown border


def test_a_solid_block_with_a_room_inside_keeps_the_room():
    """A 2 m solid square with a 1 m free room in it (and a 2-cell pinhole elsewhere): the room
    stays free, so the block is segments (convex pieces would fill it), the pinhole is filled."""
    data = np.zeros((60, 60), np.int8)
    data[10:50, 10:50] = 100
    data[20:40, 20:40] = 0  # the room: 20 x 20 cells, x and y in [1, 2] m
    data[44:46, 44] = 0  # a pinhole: no robot fits, it becomes solid
    geometry = geometry_from_grid(OccupancyGrid(data, RES))
    assert not geometry.polygons  # the block encloses the room: kept as outlines
    assert free_disc(geometry, 1.5, 1.5, 0.45)  # the room's middle, a cell from its walls
    assert not free_disc(geometry, 1.5, 1.5, 0.55)  # reaches into its walls
    assert not free_disc(geometry, 0.75, 1.5, 0.1)  # inside the block's wall
    space = pymunk.Space()
    add_to_space(space, geometry)
    assert cast(space, (1.5, 1.5), 0.0) == pytest.approx(0.5, abs=1e-9)  # the room's east wall
    assert cast(space, (1.5, 1.5), math.pi / 2) == pytest.approx(0.5, abs=1e-9)
    # the pinhole's cells are inside solid: no segment runs around them
    assert not space.point_query((2.225, 2.25), 0.1, pymunk.ShapeFilter())


def test_a_point_on_a_convex_piece_is_not_free():
    data = np.zeros((40, 40), np.int8)
    data[15:25, 15:25] = 100  # a 0.5 m pillar, x and y in [0.75, 1.25] m
    geometry = geometry_from_grid(OccupancyGrid(data, RES))
    assert len(geometry.polygons) == 1
    assert not free_disc(geometry, 1.0, 1.0, 0.0)  # a point inside the piece
    assert not free_disc(geometry, 1.25, 1.0, 0.0)  # on its outline
    assert free_disc(geometry, 1.3, 1.0, 0.0) and free_disc(geometry, 1.3, 1.0, 0.049)
    assert not free_disc(geometry, 1.3, 1.0, 0.051)
