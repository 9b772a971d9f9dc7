"""The compiled crowd forces against independent references: the wall force against pymunk's
own point queries, the social force against the pairwise formula written out per pair."""
from __future__ import annotations

import math

import numpy as np
import pymunk

from pymunk_bot.actors.clearance import (CONTACT_MARGIN, MAX_CONTACTS, SURFACE, Clearances,
                                         record)
from pymunk_bot.actors.social_forces import (KEEP_RIGHT, NOMINAL_RADIUS, SIGHT_COS,
                                             SIGHT_WEIGHT, SOCIAL_CUTOFF, STEP_TIME,
                                             cap_speeds, social_forces)
from pymunk_bot.actors.surfaces import CellIndex, Surfaces, nearest_walls, wall_forces


def _space() -> tuple[pymunk.Space, pymunk.Body]:
    """Static circles, segments and polygons (some with a radius, one on a turned body), and
    a moving body with a box and a disc."""
    space = pymunk.Space()
    static = space.static_body
    turned = pymunk.Body(body_type=pymunk.Body.STATIC)
    turned.position, turned.angle = (6.0, 2.0), 0.7
    mover = pymunk.Body(10.0, 1.0)
    mover.position, mover.angle = (3.0, 6.0), -0.4
    space.add(turned, mover)
    shapes = [pymunk.Circle(static, 0.5, (2.0, 2.0)),
              pymunk.Segment(static, (0.0, 0.0), (8.0, 0.5), 0.05),
              pymunk.Segment(static, (8.0, 0.0), (8.0, 8.0), 0.0),
              pymunk.Poly(static, [(4.0, 4.0), (5.0, 4.2), (4.8, 5.5), (3.9, 5.0)]),
              pymunk.Poly(static, [(1.0, 6.0), (1.6, 6.0), (1.6, 7.0), (1.0, 7.0)], radius=0.1),
              pymunk.Poly.create_box(turned, (1.0, 0.4)),
              pymunk.Poly.create_box(mover, (0.6, 0.3)),
              pymunk.Circle(mover, 0.2, (0.5, 0.0))]
    space.add(*shapes)
    return space, mover


def _recorded(clear: Clearances, i: int) -> np.ndarray:
    """Walker ``i``'s recorded bodies, sorted (ties in room come in any order)."""
    return np.array(sorted(map(tuple, clear.near[i, :clear.count[i]]))).reshape(-1, 4)


def test_wall_forces_match_pymunk_point_queries_inside_and_outside_shapes():
    space, mover = _space()
    fixed = [s for s in space.shapes if s.body.body_type == pymunk.Body.STATIC]
    moving = [s for s in space.shapes if s.body is mover]
    rng = np.random.default_rng(1)
    pos = rng.uniform(-0.5, 8.5, size=(400, 2))
    n = len(pos)
    reach = rng.uniform(0.5, 2.5, n)
    excess = rng.uniform(-0.05, 0.1, n)
    strength, wall_range = rng.uniform(1.0, 10.0, n), rng.uniform(0.1, 0.5, n)
    radius, step_reach = rng.uniform(0.2, 0.35, n), rng.uniform(0.0, 0.1, n)
    got = np.zeros((n, 2))
    clear = Clearances(n)
    clear.reach[:] = step_reach
    surfaces = Surfaces(fixed, set())
    walkers = np.column_stack([reach, excess, strength, wall_range, radius])
    wall_forces(surfaces, surfaces.poses(), CellIndex(surfaces.boxes(), float(reach.max())),
                pos, walkers, np.ones(n, bool), got, clear)
    movers = Surfaces(moving, set())
    wall_forces(movers, movers.poses(), None, pos, walkers, np.ones(n, bool), got, clear)
    want = np.zeros((n, 2))
    inside = recorded = 0
    for i, (x, y) in enumerate(pos.tolist()):
        close = []  # (room, direction toward the shape) of the shapes within a step's reach
        for hit in space.point_query((x, y), float(reach[i]), pymunk.ShapeFilter()):
            inside += hit.distance < 0
            gap = max(hit.distance - excess[i], 0.0)
            push = strength[i] / wall_range[i] * math.exp(-gap / wall_range[i])
            want[i] += push * np.array(tuple(hit.gradient))
            if hit.distance - radius[i] - CONTACT_MARGIN < step_reach[i]:
                close.append((max(hit.distance - radius[i] - CONTACT_MARGIN, 0.0),
                              -hit.gradient.x, -hit.gradient.y, SURFACE))
        close.sort()  # (ties in room: in any order, compared sorted)
        assert clear.count[i] == min(len(close), MAX_CONTACTS)
        np.testing.assert_allclose(_recorded(clear, i),
                                   np.array(close).reshape(-1, 4)[:MAX_CONTACTS], atol=1e-9)
        recorded += clear.count[i]
    assert inside > 5  # points inside shapes were compared too
    assert recorded > 20
    assert np.abs(want).max() > 1.0
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def test_nearest_walls_are_pymunks_nearest_first_robots_left_out():
    space, mover = _space()
    fixed = Surfaces([s for s in space.shapes if s.body.body_type == pymunk.Body.STATIC], set())
    robot = Surfaces([s for s in space.shapes if s.body is mover], {mover})
    crate = Surfaces([s for s in space.shapes if s.body is mover], set())
    rng = np.random.default_rng(4)
    points = rng.uniform(-0.5, 8.5, size=(300, 2))
    reach = rng.uniform(0.5, 4.0, len(points))
    keep = 3
    for movers, counted in ((robot, False), (crate, True)):
        hits, count = np.zeros((len(points), keep, 3)), np.zeros(len(points), np.int64)
        nearest_walls(fixed, fixed.poses(), CellIndex(fixed.boxes(), float(reach.max())),
                      points, reach, hits, count)
        nearest_walls(movers, movers.poses(), None, points, reach, hits, count)
        for (x, y), r, got, n in zip(points.tolist(), reach.tolist(), hits, count.tolist()):
            want = sorted((h.distance, h.gradient.x, h.gradient.y)
                          for h in space.point_query((x, y), r, pymunk.ShapeFilter())
                          if counted or h.shape.body is not mover)[:keep]
            assert n == len(want)
            np.testing.assert_allclose(got[:n], np.array(want).reshape(-1, 3), atol=1e-12)
    assert count.max() == keep  # some points had more shapes in reach than are kept


def test_a_cell_index_lists_every_shape_within_reach_of_its_cells():
    rng = np.random.default_rng(3)
    corners = rng.uniform(0, 50, size=(300, 2))
    boxes = np.column_stack([corners, corners + rng.uniform(0.1, 3.0, size=(300, 2))])
    cells = CellIndex(boxes, 1.5)
    for x, y in rng.uniform(-3, 55, size=(500, 2)).tolist():
        col = math.floor((x - cells.origin[0]) / cells.size)
        row = math.floor((y - cells.origin[1]) / cells.size)
        near = {s for s, (l, b, r, t) in enumerate(boxes.tolist())
                if l - 1.5 <= x <= r + 1.5 and b - 1.5 <= y <= t + 1.5}
        if not (0 <= col < cells.cols and 0 <= row < cells.rows):
            assert not near
            continue
        cell = row * cells.cols + col
        assert near <= set(cells.shapes[cells.start[cell]:cells.start[cell + 1]].tolist())


def _pair_force(p, v, e, r, q, w, rq, v0, sigma):
    """One other body's social force on a walker, the 1995 formula written out."""
    s = w * STEP_TIME
    rel = p - q
    if np.hypot(*rel) >= np.hypot(*s) + SOCIAL_CUTOFF + rq:
        return np.zeros(2)
    rn, qn = np.hypot(*rel), np.hypot(*(rel - s))
    two_b = math.sqrt((rn + qn) ** 2 - s @ s)
    grad = (rn + qn) / (2 * two_b) * (rel / rn + (rel - s) / qn)
    gap = max(0.5 * two_b - (r + rq - 2 * NOMINAL_RADIUS), 0.0)
    weight = 1.0 if -(rel @ e) / rn >= SIGHT_COS else SIGHT_WEIGHT
    return weight * v0 / sigma * math.exp(-gap / sigma) * grad


def test_social_forces_match_the_pairwise_formula_with_driving_keep_right_and_robots():
    rng = np.random.default_rng(5)
    n, robots = 12, 2
    pos = rng.uniform(0, 5, size=(n, 2))
    vel = rng.normal(0, 0.8, size=(n, 2))
    goal = rng.uniform(0, 5, size=(n, 2))
    wish, tau = rng.uniform(0.5, 1.5, n), rng.uniform(0.3, 0.7, n)
    pull = rng.normal(0, 0.2, size=(n, 2))
    radius = rng.uniform(0.2, 0.35, n)
    opos = np.vstack([pos, rng.uniform(0, 5, size=(robots, 2))])
    ovel = np.vstack([vel, rng.normal(0, 0.5, size=(robots, 2))])
    orad = np.concatenate([radius, [0.3, 0.5]])
    v0, sigma = rng.uniform(1, 3, n), rng.uniform(0.2, 0.5, n)
    reacts = np.arange(n) % 3 != 0
    force, pref = np.zeros((n, 2)), np.zeros((n, 2))
    clear = Clearances(n)
    clear.reach[:] = 0.3
    clear.count[:] = 5  # (a last tick's: social_forces starts afresh)
    social_forces(pos, vel, goal, wish, pull, tau, radius, opos, ovel, orad, v0, sigma, reacts,
                  force, pref, clear.reach, clear.near, clear.count)
    recorded = 0
    for i in range(n):  # other walkers (not robots) that both could reach within a step
        rel = pos - pos[i]
        dist = np.hypot(*rel.T)
        close = sorted((max(dist[j] - radius[i] - radius[j] - CONTACT_MARGIN, 0.0),
                        *(rel[j] / dist[j]), j) for j in range(n)
                       if j != i and dist[j] - radius[i] - radius[j] - CONTACT_MARGIN < 0.6)
        assert clear.count[i] == min(len(close), MAX_CONTACTS)
        np.testing.assert_allclose(_recorded(clear, i),
                                   np.array(close).reshape(-1, 4)[:MAX_CONTACTS], atol=1e-12)
        recorded += clear.count[i]
    assert recorded > 4
    for i in range(n):
        e = (goal[i] - pos[i]) / np.hypot(*(goal[i] - pos[i]))
        np.testing.assert_allclose(pref[i], wish[i] * e + pull[i], rtol=1e-12)
        total = np.zeros(2)
        for j in range(n + robots):
            if j != i and (j < n or reacts[i]):
                total += _pair_force(pos[i], vel[i], e, radius[i], opos[j], ovel[j], orad[j],
                                     v0[i], sigma[i])
        against = max(-(total @ e), 0.0)
        total += KEEP_RIGHT * against * np.array([e[1], -e[0]])
        total += (pref[i] - vel[i]) / tau[i]
        np.testing.assert_allclose(force[i], total, rtol=1e-9, atol=1e-12)


def test_speeds_are_capped_and_directions_kept():
    velocity = np.array([[3.0, 4.0], [0.3, 0.4], [0.0, 0.0]])
    cap_speeds(velocity, np.array([1.0, 1.0, 1.0]))
    np.testing.assert_allclose(velocity, [[0.6, 0.8], [0.3, 0.4], [0.0, 0.0]])


def test_a_walker_running_into_a_queue_pushes_it_against_a_wall_without_closing_a_gap():
    # Along x: a wall at x = 0, walkers B (70 kg) and C (140 kg) standing 3 mm and 8 mm clear
    # of it and of each other, walker A (70 kg) running at them at 1.5 m/s from 1 cm, and D
    # walking along y beside nobody. The allowed closing speeds: (clearance - margin) / step.
    step = np.full(4, 1.0 / 60.0)
    clear = Clearances(4)
    clear.reach[:] = 0.03
    left = (-1.0, 0.0)
    record(clear.near, clear.count, 1, 0.003, *left, SURFACE)  # B: 3 mm from the wall
    record(clear.near, clear.count, 1, 0.008, 1.0, 0.0, 2)  # B - C
    record(clear.near, clear.count, 2, 0.008, *left, 1)
    record(clear.near, clear.count, 2, 0.010, 1.0, 0.0, 0)  # C - A
    record(clear.near, clear.count, 0, 0.010, *left, 2)
    velocity = np.array([[-1.5, 0.2], [0.0, 0.0], [0.0, 0.0], [0.0, 1.0]])
    mass = np.array([70.0, 70.0, 140.0, 70.0])
    clear.limit(velocity, step, mass, np.ones(4, bool))
    a, b, c, d = velocity
    assert -b[0] <= 1e-12  # B does not move toward the wall (3 mm: inside the margin)
    residual = 0.02 * 1.5  # [m/s] what ITERATIONS sweeps may leave of A's speed on pairs
    assert c[0] - b[0] <= (0.008 - CONTACT_MARGIN) / step[0] + residual
    assert a[0] - c[0] <= (0.010 - CONTACT_MARGIN) / step[0] + residual
    assert -1.5 < a[0] < -0.2 and a[1] == 0.2  # A slows along x only ...
    assert c[0] < -0.1  # ... and pushes C (a pair shares the correction by mass)
    np.testing.assert_array_equal(d, [0.0, 1.0])  # nothing near: untouched
