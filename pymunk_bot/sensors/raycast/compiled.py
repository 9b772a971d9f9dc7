"""One cast's culling and exact tests compiled with numba: what ``Fan``, ``Scene`` and
``kernels`` do with arrays, done primitive by primitive with no temporary arrays.

The pair tests are the kernels' Chipmunk expressions, operand for operand; numba compiles
them without fused multiply-adds or reordering (no fastmath), so each alpha is the float
numpy and Chipmunk compute. Angles (atan2, asin, hypot; the rays' angles wrapped to a turn)
only choose which pairs are tested,
with the same margins as the numpy path, far above any difference in their last bits.
Imported lazily by the caster: ``import pymunk_bot`` never loads numba.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from pymunk_bot.sensors.raycast.primitives import AX, AY, BX, BY, DTMAX, DTMIN, NX, NY, RAD, VN

_TWO_PI = 2.0 * math.pi
_PARALLEL_EPS = 10e-6  # as kernels._PARALLEL_EPS (Chipmunk's 10e-6)
_EDGE_MARGIN = 1e-7  # as scene._EDGE_MARGIN
_EDGE_NEAR = 1e-5  # as scene.EDGE_NEAR
LOOK_AGAIN = 32  # primitives traced between two looks at the farthest hit (once every ray hit)
# The primitives are traced nearest first, roughly: by the least alpha a hit on their shape can
# have, in rings whose outer edges double (the last reaches the range), so the rays' hits are
# near early and the farther rings are passed over once every ray has hit something nearer.
RINGS = 6
_RING_EDGES = (1.0 / 32.0, 1.0 / 16.0, 0.125, 0.25, 0.5)  # [alpha] outer edges but the last's


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _circle_alpha(dax: float, day: float, dbx: float, dby: float, r: float) -> float:
    """CircleSegmentQuery's alpha for da = a - c, db = b - c; 2.0 where it misses."""
    aa = dax * dax + day * day
    ab = dax * dbx + day * dby
    bb = dbx * dbx + dby * dby
    qa = aa - 2.0 * ab + bb
    qb = ab - aa
    rsum = r + 0.0
    det = qb * qb - qa * (aa - rsum * rsum)
    if not det >= 0.0:
        return 2.0
    t = (-qb - math.sqrt(det)) / qa
    if t >= 0.0 and t <= 1.0:
        return t
    return 2.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _sorted_rays(ang: np.ndarray, given: np.ndarray) -> tuple:
    """The rays' direction angles (``ang`` [rad] wrapped to [-pi, pi)) in sorted order, the
    ray of each, an evenly spaced grid's (t0, 1 / step, err) when they form one (as
    fan.Rays decides; else err < 0), and the wrap's rounding bound [rad]. ``given`` is the
    order for rays that are not one turn rotated (else empty); without it such rays give an
    empty order."""
    n = ang.shape[0]
    theta = np.empty(n)
    biggest = 0.0
    for i in range(n):
        theta[i] = ang[i] - _TWO_PI * math.floor((ang[i] + math.pi) / _TWO_PI)
        biggest = max(biggest, abs(ang[i]))
    wrap = 1e-15 * (1.0 + biggest)  # what wrapping can be off by, far below the margins
    drops, k = 0, 0
    for i in range(n - 1):
        if theta[i + 1] < theta[i]:
            drops += 1
            k = i + 1
    rotated = drops == 0 or (drops == 1 and theta[n - 1] <= theta[0])
    if not rotated and given.shape[0] != n:
        return theta, given, 0.0, 0.0, -1.0, wrap
    order = np.empty(n, dtype=np.intp)
    st = np.empty(n)
    for i in range(n):
        order[i] = (k + i) % n if rotated else given[i]
        st[i] = theta[order[i]]
        if i and st[i] < st[i - 1]:  # a given order made from angles a bit apart from these
            st[i] = st[i - 1]
    t0, inv, err = 0.0, 0.0, -1.0
    if n >= 8:
        step = (st[n - 1] - st[0]) / (n - 1)
        if step > 0.0:
            inv = 1.0 / step
            off = 0.0
            for i in range(n):
                off = max(off, abs((st[i] - st[0]) * inv - i))
            e = off + 2.0 * abs(n * step - _TWO_PI) / step + 1e-6
            if e < 0.25:
                t0, err = st[0] - _TWO_PI, e
    return st, order, t0, inv, err, wrap


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _ray_range(lo: float, hi: float, st: np.ndarray, t0: float, inv: float,
               err: float) -> tuple:
    """First and end (exclusive) entry, over three turns of the sorted rays, of the rays
    whose angle lies in [lo, hi]; on a grid the range may take in a neighbour (harmless)."""
    n = st.shape[0]
    if err >= 0.0:
        x0 = min(max((lo - t0) * inv - err, 0.0), 3.0 * n)
        x1 = min(max((hi - t0) * inv + (err + 1.0), 0.0), 3.0 * n)
        return int(math.ceil(x0)), int(x1)
    # Binary searches over the sorted angles tiled at -2 pi, 0, +2 pi.
    a, b = 0, 3 * n
    while a < b:
        mid = (a + b) // 2
        if st[mid % n] + (mid // n - 1) * _TWO_PI < lo:
            a = mid + 1
        else:
            b = mid
    first = a
    a, b = first, 3 * n
    while a < b:
        mid = (a + b) // 2
        if st[mid % n] + (mid // n - 1) * _TWO_PI <= hi:
            a = mid + 1
        else:
            b = mid
    return first, a


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _rejects(shape_filters: np.ndarray, o: int, group: int, categories: int, mask: int) -> bool:
    """cpShapeFilterReject of shape ``o`` (its (group, categories, mask) a column of
    ``shape_filters``) and a query's filter."""
    return ((shape_filters[0, o] != 0 and shape_filters[0, o] == group)
            or (shape_filters[1, o] & mask) == 0
            or (categories & shape_filters[2, o]) == 0)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def endpoints_rows(ox: np.ndarray, oy: np.ndarray, ang: np.ndarray, rng: np.ndarray,
                   ends: np.ndarray) -> None:
    """The (K, 2, n) segment end points of :func:`.reference.endpoints_many` into ``ends``:
    origin + rng * (cos, sin) of each ray, the C library's cos and sin (numpy's on this
    build; tests/sensors check it bit for bit), in a third of numpy's time."""
    for k in range(ang.shape[0]):
        for j in range(ang.shape[1]):
            ends[k, 0, j] = math.cos(ang[k, j]) * rng[k] + ox[k]
            ends[k, 1, j] = math.sin(ang[k, j]) * rng[k] + oy[k]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def near_admitted(boxes: np.ndarray, bound: np.ndarray, shape_filters: np.ndarray,
                  ox: np.ndarray, oy: np.ndarray, reach: np.ndarray, filters: np.ndarray,
                  near: np.ndarray) -> None:
    """Per origin k (its query filter a row of ``filters``, as :func:`trace_filtered`'s):
    whether some shape the filter admits comes within ``reach[k]`` [m] of it by its bounds:
    the static shapes' bounding boxes (``boxes`` (4, n_static): l, b, r, t; a wall's circle
    would cover half the arena), then the moving shapes' bounding circles (the rest of the
    columns of ``bound``). An origin near none is inside no shape and within ``reach`` of
    none, so pymunk's point query there finds nothing (NaN counts as near)."""
    n_static = boxes.shape[1]
    for k in range(ox.shape[0]):
        group, categories, mask = filters[k, 0], filters[k, 1], filters[k, 2]
        x, y, d = ox[k], oy[k], reach[k]
        near[k] = False
        for o in range(bound.shape[1]):  # the bounds first: the filter only for shapes near
            if o < n_static:
                apart = (x < boxes[0, o] - d or x > boxes[2, o] + d
                         or y < boxes[1, o] - d or y > boxes[3, o] + d)
            else:
                dx, dy, r = x - bound[0, o], y - bound[1, o], bound[2, o] + d
                apart = dx * dx + dy * dy > r * r
            if not apart and not _rejects(shape_filters, o, group, categories, mask):
                near[k] = True
                break


@numba.njit(cache=True, nogil=True, error_model="numpy")
def trace_filtered(rows: np.ndarray, counts: np.ndarray, owner: np.ndarray, bound: np.ndarray,
                   shape_filters: np.ndarray, rounded: bool, ox: np.ndarray, oy: np.ndarray,
                   scale: np.ndarray, rng: np.ndarray, filters: np.ndarray, ang: np.ndarray,
                   ends: np.ndarray, sides: np.ndarray, n_sides: np.ndarray,
                   order_given: np.ndarray, best: np.ndarray, flagged: np.ndarray,
                   n_flagged: np.ndarray) -> None:
    """:func:`trace` for K casts on one table, row k of every array: each result goes to
    ``n_flagged[k]``, ``sides[k, :, :n_sides[k]]`` are its side intervals. The query
    filters are applied here: ``filters`` (K, 3) and ``shape_filters`` (3, n_shapes) hold
    (group, categories, mask) of each cast and of each shape; a shape is traced unless
    cpShapeFilterReject rejects the pair."""
    # Scratch of every cast: the primitives it admits, with their rings, then in ring order;
    # where each ring starts in that order.
    near_first = np.empty((3, rows.shape[1]), dtype=np.intp)
    starts = np.empty(RINGS + 1, dtype=np.intp)
    # Whether to trace nearest first: it pays where every ray hits something (the farther
    # primitives are then passed over), and costs a sort where some ray reaches its range.
    # The cast before tells (casts of one call are alike: one scene, one kind of LiDAR).
    sort = True
    for k in range(ox.shape[0]):
        n_flagged[k] = trace(rows, counts, shape_filters, filters[k], owner, bound, rounded,
                             ox[k], oy[k], scale[k], rng[k], ang[k], ends[k],
                             sides[k, :, :n_sides[k]], order_given[k], best[k], flagged[k],
                             near_first, starts, sort)
        sort = best[k].max() < 1.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def trace(rows: np.ndarray, counts: np.ndarray, shape_filters: np.ndarray, query: np.ndarray,
          owner: np.ndarray, bound: np.ndarray, rounded: bool, ox: float, oy: float,
          scale: float, rng: float, ang: np.ndarray, ends: np.ndarray, side: np.ndarray,
          order_given: np.ndarray, best: np.ndarray, flagged: np.ndarray,
          near_first: np.ndarray, starts: np.ndarray, sort: bool) -> int:
    """Lower ``best`` (alpha per ray, starting at 1) by every hit of a primitive of the table
    ``rows`` (columns: ``counts`` edges, flags, circles, segments; ``owner``: the shape of
    each, whose bounding circle (cx, cy, r) is a column of ``bound``) that the ``query``
    filter (group, categories, mask) admits (``shape_filters``: each shape's; tested only
    for shapes in range, the rest cost nothing per cast); write the
    rays that pass near a flag, or inside a ``side`` interval (2, k) [rad], to ``flagged``
    and return how many there are (a ray may appear more than once); -1 if they do not
    fit; -2 if the rays are not one turn in order and ``order_given`` is empty (call again
    with their angle order). ``near_first`` (3, m) and ``starts`` (RINGS + 1): scratch;
    ``sort``: the primitives in range are traced nearest first (else in the table's order;
    the same answers)."""
    n = best.shape[0]
    group, categories, mask = query[0], query[1], query[2]
    st, order, t0, inv, err, wrap = _sorted_rays(ang, order_given)
    if order.shape[0] != n:
        return -2
    slack = 1e-9 * scale
    margin = _EDGE_MARGIN + 1e-15 * scale / rng + wrap
    near_plane = _EDGE_NEAR * scale
    ne, nf, nc = counts[0], counts[1], counts[2]
    m = rows.shape[1]
    n_flagged = 0
    # Chipmunk's plane test for edges: d = a.n - v0.n - r; back faces (d < 0) are skipped.
    d_edge = np.empty(ne)
    an_edge = np.empty(ne)
    on_plane = False
    for j in range(ne):
        an = rows[NX, j] * ox + oy * rows[NY, j]
        d = an - rows[VN, j]
        if rounded:
            d -= rows[RAD, j]
        an_edge[j], d_edge[j] = an, d
        if d >= 0.0 and d <= near_plane and not _rejects(shape_filters, owner[j], group,
                                                          categories, mask):
            on_plane = True
    # The primitives in range that the filter admits, ring by ring where there are many.
    admitted, ring_of, in_order = near_first[0], near_first[1], near_first[2]
    count = 0
    for j in range(m):
        if j < ne and not d_edge[j] >= 0.0:
            continue
        o = owner[j]  # no ray reaches a shape whose bounding circle is out of range
        cx, cy, reach = bound[0, o] - ox, bound[1, o] - oy, rng + bound[2, o] + slack
        d2 = cx * cx + cy * cy
        if d2 > reach * reach or _rejects(shape_filters, o, group, categories, mask):
            continue
        admitted[count] = j
        count += 1
    sequence = admitted
    starts[0] = 0
    starts[1:] = count  # one ring, in the table's order
    if sort:
        _sort_near_first(admitted, ring_of, in_order, starts, count, owner, bound, ox, oy, rng,
                         slack, ne, nf)
        sequence = in_order
    # Once every ray has hit something, a primitive whose shape lies farther than the
    # farthest hit cannot lower any ray's alpha: it is passed over (the farthest hit is
    # looked at again every LOOK_AGAIN primitives traced, and at each ring, which ends the
    # cast when its inner edge lies beyond), and so is a ray already nearer.
    unhit = 0
    for i in range(n):
        if best[i] >= 1.0:
            unhit += 1
    farthest = 1.0  # [alpha] at least the farthest any ray still reaches
    traced = 0
    ring = 0
    for q in range(count):
        if q == starts[ring + 1]:  # a ring more (or several: empty ones between)
            while q == starts[ring + 1]:
                ring += 1
            if unhit == 0:
                farthest = best.max()
                if _RING_EDGES[ring - 1] > farthest:
                    break
        j = sequence[q]
        o = owner[j]
        kind = 0 if j < ne else (1 if j < ne + nf else (2 if j < ne + nf + nc else 3))
        least = -1.0  # [alpha] the least a hit on the shape can have (-1: not known)
        if unhit == 0 and kind != 1:  # (flags, within rounding of their shape, are kept)
            cx, cy = bound[0, o] - ox, bound[1, o] - oy
            least = (math.sqrt(cx * cx + cy * cy) - bound[2, o] - slack) / rng
            traced += 1
            if traced % LOOK_AGAIN == 0:
                farthest = best.max()
            if least > farthest:
                continue
        ax, ay = rows[AX, j] - ox, rows[AY, j] - oy
        bx, by = rows[BX, j] - ox, rows[BY, j] - oy
        if kind == 3 and ax * by - ay * bx < 0.0:  # segments: A to B counter-clockwise
            ax, ay, bx, by = bx, by, ax, ay
        point = kind == 1 or kind == 2  # A = B: no span, one distance
        phi = math.atan2(ay, ax)
        span = 0.0 if point else math.atan2(by, bx) - phi
        if span < 0.0:
            span += _TWO_PI
        half = margin
        full = kind == 0 and on_plane and d_edge[j] <= near_plane
        if kind >= 2 or rounded:  # widen by the end discs (flags: radius 0)
            reach = rows[RAD, j] + slack
            near = math.hypot(ax, ay) if point else min(math.hypot(ax, ay), math.hypot(bx, by))
            half += math.asin(min(reach / near, 1.0))
            full = full or near <= reach
            if kind == 3:
                ex, ey = bx - ax, by - ay
                u = min(max(-(ax * ex + ay * ey) / ((ex * ex + ey * ey) + 1e-300), 0.0), 1.0)
                full = full or math.hypot(ax + u * ex, ay + u * ey) - rows[RAD, j] <= slack
        if full:
            first, stop = n, 2 * n
        else:
            lo = phi - half
            first, stop = _ray_range(lo, lo + (span + 2.0 * half), st, t0, inv, err)
        for e in range(first, stop):
            ray = order[e % n]
            if best[ray] < least:  # it has hit something nearer than the shape can be
                continue
            bx_, by_ = ends[0, ray], ends[1, ray]
            if kind == 0:  # cpPolyShapeSegmentQuery's plane
                nx, ny = rows[NX, j], rows[NY, j]
                den = an_edge[j] - (bx_ * nx + by_ * ny)
                t = d_edge[j] / den
                if on_plane:
                    if not (abs(den) >= _PARALLEL_EPS and t >= 0.0):
                        continue
                elif not den >= _PARALLEL_EPS:
                    continue
                one_t = 1.0 - t
                dt = nx * (oy * one_t + by_ * t) - ny * (ox * one_t + bx_ * t)
                if rows[DTMIN, j] <= dt and dt <= rows[DTMAX, j] and t < best[ray]:
                    unhit -= best[ray] >= 1.0
                    best[ray] = t
            elif kind == 1:  # near a box corner lying on its shape: pymunk decides
                flagged[n_flagged] = ray
                n_flagged += 1
            elif kind == 2:
                cx, cy = rows[AX, j], rows[AY, j]
                t = _circle_alpha(ox - cx, oy - cy, bx_ - cx, by_ - cy, rows[RAD, j])
                if t < best[ray]:
                    unhit -= best[ray] >= 1.0
                    best[ray] = t
            else:
                t = _segment_alpha(rows, j, ox, oy, bx_, by_)
                if t < best[ray]:
                    unhit -= best[ray] >= 1.0
                    best[ray] = t
        if n_flagged > flagged.shape[0] - 3 * n:
            return -1  # no room for another primitive's rays: the caller asks pymunk
    for s in range(side.shape[1]):
        first, stop = _ray_range(side[0, s], side[1, s], st, t0, inv, err)
        for e in range(first, stop):
            if n_flagged == flagged.shape[0]:
                return -1
            flagged[n_flagged] = order[e % n]
            n_flagged += 1
    return n_flagged


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _sort_near_first(admitted: np.ndarray, ring_of: np.ndarray, in_order: np.ndarray,
                     starts: np.ndarray, count: int, owner: np.ndarray, bound: np.ndarray,
                     ox: float, oy: float, rng: float, slack: float, ne: int, nf: int) -> None:
    """The ``count`` primitives ``admitted`` into ``in_order`` ring by ring (each ring in
    the table's order; a counting sort), ``starts[r]`` where ring r begins (``starts[RINGS]``:
    ``count``). A primitive's ring: the least alpha a hit on its shape (its bounding circle,
    seen from the origin ``ox``, ``oy`` [m], ``rng`` [m] ahead) can have; flags (corners pymunk
    decides, always kept) go first."""
    starts[:] = 0
    for q in range(count):
        j = admitted[q]
        ring = 0
        if not ne <= j < ne + nf:
            o = owner[j]
            cx, cy = bound[0, o] - ox, bound[1, o] - oy
            least = (math.sqrt(cx * cx + cy * cy) - bound[2, o] - slack) / rng
            while ring < RINGS - 1 and least >= _RING_EDGES[ring]:
                ring += 1
        ring_of[q] = ring
        starts[ring + 1] += 1
    for ring in range(RINGS):  # sizes -> where each ring ends
        starts[ring + 1] += starts[ring]
    for q in range(count - 1, -1, -1):  # from the last: each ring keeps the table's order
        ring = ring_of[q]
        starts[ring + 1] -= 1  # (ends down to beginnings: ring r's is now at r + 1)
        in_order[starts[ring + 1]] = admitted[q]
    for ring in range(RINGS):
        starts[ring] = starts[ring + 1]
    starts[RINGS] = count


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _segment_alpha(rows: np.ndarray, j: int, ox: float, oy: float, bx: float,
                   by: float) -> float:
    """cpSegmentShapeSegmentQuery with query radius 0, end caps included; 2.0 on a miss."""
    tax, tay, tbx, tby = rows[AX, j], rows[AY, j], rows[BX, j], rows[BY, j]
    r, nx, ny = rows[RAD, j], rows[NX, j], rows[NY, j]
    d = (tax - ox) * nx + (tay - oy) * ny
    pos = d > 0.0
    offx = (-nx if pos else nx) * r - ox
    offy = (-ny if pos else ny) * r - oy
    dx, dy = bx - ox, by - oy
    straddle = (dx * (tay + offy) - dy * (tax + offx)) * (dx * (tby + offy) - dy * (tbx + offx)) <= 0.0
    if straddle:
        d_off = d + (-r if pos else r)
        ad = -d_off
        bd = (dx * nx + dy * ny) - d_off
        if ad * bd < 0.0:
            return ad / (ad - bd)
        return 2.0
    if r == 0.0:
        return 2.0
    # Chipmunk keeps cap 1 only if its alpha (1.0 when missed) is strictly smaller.
    a1 = _circle_alpha(ox - tax, oy - tay, bx - tax, by - tay, r)
    a2 = _circle_alpha(ox - tbx, oy - tby, bx - tbx, by - tby, r)
    hit1, hit2 = a1 <= 1.0, a2 <= 1.0
    a1, a2 = a1 if hit1 else 1.0, a2 if hit2 else 1.0
    if a1 < a2:
        return a1 if hit1 else 2.0
    return a2 if hit2 else 2.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def move_into(local: np.ndarray, local_bound: np.ndarray, tf: np.ndarray, prim_body: np.ndarray,
              shape_body: np.ndarray, dest: np.ndarray, first_shape: int, rows: np.ndarray,
              bound: np.ndarray) -> None:
    """geometry.moved, written straight into a merged table: moving primitive c (body-local
    column c of ``local``) goes to column ``dest[c]`` of ``rows``, moving shape s's bounding
    circle to column ``first_shape + s`` of ``bound``; Chipmunk's transform arithmetic in
    Chipmunk's order, the very floats geometry.moved computes."""
    for c in range(local.shape[1]):
        b = prim_body[c]
        rx, ry, tx, ty = tf[0, b], tf[1, b], tf[2, b], tf[3, b]
        d = dest[c]
        rows[AX, d] = rx * local[AX, c] - ry * local[AY, c] + tx
        rows[AY, d] = ry * local[AX, c] + rx * local[AY, c] + ty
        rows[BX, d] = rx * local[BX, c] - ry * local[BY, c] + tx
        rows[BY, d] = ry * local[BX, c] + rx * local[BY, c] + ty
        rows[NX, d] = rx * local[NX, c] - ry * local[NY, c]
        rows[NY, d] = ry * local[NX, c] + rx * local[NY, c]
        rows[RAD, d] = local[RAD, c]
        rows[VN, d] = rows[AX, d] * rows[NX, d] + rows[AY, d] * rows[NY, d]
        rows[DTMIN, d] = rows[NX, d] * rows[BY, d] - rows[NY, d] * rows[BX, d]
        rows[DTMAX, d] = rows[NX, d] * rows[AY, d] - rows[NY, d] * rows[AX, d]
    for s in range(local_bound.shape[1]):
        b = shape_body[s]
        rx, ry, tx, ty = tf[0, b], tf[1, b], tf[2, b], tf[3, b]
        bound[0, first_shape + s] = rx * local_bound[0, s] - ry * local_bound[1, s] + tx
        bound[1, first_shape + s] = ry * local_bound[0, s] + rx * local_bound[1, s] + ty
        bound[2, first_shape + s] = local_bound[2, s]
