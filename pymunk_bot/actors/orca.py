"""ORCA: optimal reciprocal collision avoidance (van den Berg, Guy, Lin & Manocha, "Reciprocal
n-body collision avoidance", ISRR 2011), the pedestrian policy of CrowdNav and IR-SIM.

For walker A and each of its nearest neighbours B (other walkers, robots), the velocities that
would bring A within r_A + r_B of B in ``time_horizon`` (B keeping its velocity) form a
truncated cone, the velocity obstacle. u is the smallest change of the relative velocity that
leaves it and n the cone's outward normal there; A takes its share of u (half against another
walker, who does the other half; all of it against a robot, which may not) and must keep to
the half-plane {v : (v - (v_A + share u)) . n >= 0}. A wall at distance d from A's centre
(its nearest point, :func:`.surfaces.nearest_hits`) gives
{v : v . g >= -max(d - r_A, 0) / tau_obst}, g pointing away from it: a hard constraint. A then
takes the velocity closest to its wish inside all of them (``orca_lp.solve_all``, compiled),
the wish turned ``keep_right`` (default KEEP_RIGHT_ANGLE) to its right (see there). A walker's
``robot_share`` replaces ROBOT_SHARE (CrowdNav's humans that see the robot take half), and its
``orca_margin`` is added to every radius (CrowdNav's: 0.01 m). The cones are built for all
walkers at once with numpy. A walker's seeded nudge then moves that answer within the same
half-planes (:func:`nudged_within`): in an exactly symmetric crossing the answer is a corner of
them that no turn of the wish moves, and ORCA alone jams there for good.

ORCA's guarantee holds only while each walker's linear program has room. In a dense crowd (the
middle of twenty walkers swapping places) it has none, and the least-violating answers brought
pairs up to 1.75 mm into each other; the crowd then keeps ORCA walkers CONTACT_MARGIN apart
over the step they hold their velocity (:func:`closing_limits`, solved like clearance.py's
speculative contacts), which ORCA's answers with room and a margin at least as large (CrowdNav's
humans: 2 x 1 cm) already do.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

MAX_WALL_LINES = 4  # nearest wall points per walker that constrain it
ROBOT_SHARE = 1.0  # of u a walker takes against a robot (the default of ``robot_share``)
# [rad] the wished velocity is turned this much to the walker's right. Two walkers that meet
# exactly head-on from rest get half-planes normal to the line between them, which ORCA alone
# never leaves (a known degenerate case); people keep right, and so do these (the default of
# a walker's ``keep_right``; config/motion.py holds the defaults, this layer cannot be imported
# there).
KEEP_RIGHT_ANGLE = 0.1
WALKER_SHARE = 0.5  # ... and against another walker


def _det(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def neighbour_lines(pos: np.ndarray, vel: np.ndarray, radius: np.ndarray, opos: np.ndarray,
                    ovel: np.ndarray, orad: np.ndarray, share: np.ndarray, horizon: np.ndarray,
                    dt: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Half-planes (q, n), each (k, K, 2), of k agents against K neighbours each: agent a at
    ``pos[a]`` with ``vel[a]``, ``radius[a]``; its neighbours at ``opos[a, j]`` ... with
    ``share[a, j]`` of the avoidance; ``horizon[a]`` [s]; ``dt`` [s] the step (for a pair
    already overlapping, which must part within it), one for all or one per agent (k,)."""
    p = opos - pos[:, None, :]  # to the neighbour [m]
    v = vel[:, None, :] - ovel  # relative velocity [m/s]
    r = radius[:, None] + orad  # [m]
    tau = horizon[:, None]
    dist2 = (p ** 2).sum(axis=-1)
    r2 = r * r
    apart = dist2 > r2
    # The cutoff disc: centre p / tau (p / dt when overlapping), radius r / tau (r / dt).
    step = np.asarray(dt, dtype=float)
    scale = np.where(apart, tau, step[:, None] if step.ndim else step)
    w = v - p / scale[..., None]
    wl = np.sqrt((w ** 2).sum(axis=-1))
    dot = (w * p).sum(axis=-1)
    on_disc = ~apart | ((dot < 0.0) & (dot * dot > r2 * wl * wl))
    safe_wl = np.where(wl > 1e-12, wl, 1.0)
    disc_n = np.where((wl > 1e-12)[..., None], w / safe_wl[..., None], np.array([1.0, 0.0]))
    disc_u = (r / scale - wl)[..., None] * disc_n
    # The legs: tangents from the origin to the disc of radius r about p.
    leg = np.sqrt(np.maximum(dist2 - r2, 0.0))
    inv = 1.0 / np.maximum(dist2, 1e-12)
    left = _det(p, w) > 0.0
    px, py = p[..., 0], p[..., 1]
    d_left = np.stack([px * leg - py * r, px * r + py * leg], axis=-1) * inv[..., None]
    d_right = np.stack([px * leg + py * r, -px * r + py * leg], axis=-1) * inv[..., None]
    d = np.where(left[..., None], d_left, d_right)
    leg_u = (v * d).sum(axis=-1)[..., None] * d - v
    leg_n = np.where(left[..., None], np.stack([-d[..., 1], d[..., 0]], axis=-1),
                     np.stack([d[..., 1], -d[..., 0]], axis=-1))
    u = np.where(on_disc[..., None], disc_u, leg_u)
    n = np.where(on_disc[..., None], disc_n, leg_n)
    q = vel[:, None, :] + share[..., None] * u
    return q, n


def nudged_within(q: np.ndarray, n: np.ndarray, ok: np.ndarray, hard: np.ndarray,
                  vmax: np.ndarray, chosen: np.ndarray, nudge: np.ndarray) -> np.ndarray:
    """``chosen`` (k, 2) [m/s] with each agent's ``nudge`` (k, 2) [m/s]: the velocity closest to
    chosen + nudge inside the agent's half-planes ``q``, ``n`` (k, L, 2), ``ok`` (k, L) which
    count (first), the first ``hard`` (k,) of them walls, within ``vmax`` (k,) [m/s]. An agent
    with no nudge, or whose half-planes leave no room, keeps its velocity bit for bit."""
    from pymunk_bot.actors.orca_lp import EPS, solve_all

    out = chosen.copy()
    agents = np.flatnonzero((nudge != 0.0).any(axis=1))
    if not len(agents):
        return out
    q, n, ok = q[agents], n[agents], ok[agents]
    moved = solve_all(q, n, ok.sum(axis=1).astype(np.int64), hard[agents], vmax[agents],
                      chosen[agents] + nudge[agents])
    kept = (((moved[:, None, :] - q) * n).sum(axis=-1) >= -EPS) | ~ok
    fits = kept.all(axis=1)
    out[agents[fits]] = moved[fits]
    return out


def closing_limits(agents: np.ndarray, pos: np.ndarray, vel: np.ndarray,
                   radius: np.ndarray, step: np.ndarray, reach: np.ndarray,
                   neighbours: tuple[np.ndarray, np.ndarray], partners: np.ndarray,
                   margin: float, near: np.ndarray, count: np.ndarray) -> bool:
    """For the k ``agents`` (indices into the walkers) and those of their ``neighbours``
    (:meth:`Orca.nearest`) who are walkers and ``partners`` (n,) within their ``reach`` (n,)
    [m] (how far each can go in a step) of each other: the linear bound on the pair's
    velocities under which their discs, moving straight, come no closer than ``margin`` [m]
    within ``step`` (n,) [s] (the time each holds its velocity). It is the
    tangent, at the nearest point, of the velocity obstacle whose horizon is that step
    (:func:`neighbour_lines`, the whole of u), written for :func:`.clearance.limit_closing`:
    into ``near`` (n, K, 4) each agent's rows (how far [m] the pair may close within the step
    along a unit direction, that direction, the partner) and into ``count`` (n,) how many.
    Walkers at ``pos`` (n, 2) [m] with velocities ``vel`` (n, 2) [m/s] and radii ``radius``
    (n,) [m]. Returns whether any pair breaks its bound (more than EPS).
    ORCA's answers do when its linear program has no room and its least-violating answers
    bring walkers into each other; when it has, they do only if twice the walkers'
    ``orca_margin`` is below ``margin`` (the obstacle of a step lies inside that of ORCA's
    horizon, for radii at least as large)."""
    from pymunk_bot.actors.orca_lp import EPS

    order, valid = neighbours
    pair = valid & (order < len(pos))
    other = np.where(pair, order, 0)
    pair &= partners[other]
    mine = np.broadcast_to(agents[:, None], order.shape)
    towards = pos[other] - pos[mine]  # [m]
    apart = np.sqrt((towards ** 2).sum(axis=-1))
    room = apart - radius[mine] - radius[other] - margin  # [m]
    pair &= room < reach[mine] + reach[other]
    count[agents] = 0
    # Moving straight, a pair comes no nearer within the step than its distance less its
    # closing speed along the line between them times the step: most ticks, no pair closes in.
    closing = ((vel[mine] - vel[other]) * towards).sum(axis=-1) / np.maximum(apart, 1e-12)
    if not (pair & (closing * step[mine] > room)).any():
        return False
    a, b = mine[pair], other[pair]  # the pairs, agent by agent
    held = step[a]
    q, n = neighbour_lines(pos[a], vel[a], radius[a] + 0.5 * margin, pos[b][:, None, :],
                           vel[b][:, None, :], (radius[b] + 0.5 * margin)[:, None],
                           np.ones((len(a), 1)), held, held)
    q, n = q[:, 0], n[:, 0]
    # (v_a - v_b) . n >= least [m/s] keeps the pair apart; they may close EPS faster (rounding)
    least = ((q - vel[b]) * n).sum(axis=-1) - EPS
    slot = np.cumsum(pair, axis=1)[pair] - 1  # each pair's row among its agent's
    near[a, slot, 0] = -least * held
    near[a, slot, 1:3] = -n
    near[a, slot, 3] = b
    count[agents] = pair.sum(axis=1)
    return bool((((q - vel[a]) * n).sum(axis=-1) > EPS).any())


class Orca:
    """ORCA velocities for the walkers ``agents`` (indices into the crowd)."""

    def __init__(self, agents: np.ndarray, configs: Sequence[Any]) -> None:
        self.agents = agents
        self.horizon = np.array([configs[i].time_horizon for i in agents], dtype=float)
        self.wall_horizon = np.array([configs[i].obstacle_time_horizon for i in agents])
        self.reach = np.array([configs[i].neighbor_distance for i in agents], dtype=float)
        self.limit = np.array([configs[i].max_neighbors for i in agents], dtype=np.int64)
        self.keep_right = np.array([configs[i].keep_right for i in agents], dtype=float)  # [rad]
        self.robot_share = np.array([configs[i].robot_share for i in agents], dtype=float)
        self.margin = np.array([configs[i].orca_margin for i in agents], dtype=float)  # [m]

    def nearest(self, pos: np.ndarray, others: np.ndarray,
                visible: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each agent's neighbours, nearest first: ``order`` (k, K), indices into ``others``
        (m, 2) [m], and ``valid`` (k, K), which of them count (``visible`` (k, m) to it, within
        its neighbour distance, among its nearest max_neighbors)."""
        m = len(others)
        d2 = ((others[None, :, :] - pos[:, None, :]) ** 2).sum(axis=-1)
        d2 = np.where(visible & (d2 <= (self.reach ** 2)[:, None]), d2, np.inf)
        width = int(min(m, self.limit.max())) if m else 0
        order = np.argsort(d2, axis=1, kind="stable")[:, :width]
        valid = np.isfinite(np.take_along_axis(d2, order, axis=1))
        valid &= np.arange(width)[None, :] < self.limit[:, None]
        return order, valid

    def velocities(self, pos: np.ndarray, vel: np.ndarray, radius: np.ndarray,
                   others: tuple[np.ndarray, np.ndarray, np.ndarray], walkers: int,
                   neighbours: tuple[np.ndarray, np.ndarray], pref: np.ndarray,
                   vmax: np.ndarray, dt: float | np.ndarray,
                   walls: tuple[np.ndarray, np.ndarray],
                   nudge: np.ndarray | None = None) -> np.ndarray:
        """New velocities (k, 2) [m/s] of the agents, at ``pos``, ``vel``, ``radius`` (k, ...),
        wishing ``pref`` (k, 2) within ``vmax`` (k,). ``others``: positions, velocities and
        radii of everything avoided (the first ``walkers`` are walkers, the rest robots);
        ``neighbours``: whom each agent takes into account (:meth:`nearest`); ``dt`` [s]: the
        step each agent's velocity is held for (one, or (k,)); ``walls``: per
        agent, up to MAX_WALL_LINES (distance [m], gradient x, gradient y) of nearby surfaces,
        nearest first, (k, MAX_WALL_LINES, 3), and how many (k,). ``nudge`` (k, 2) [m/s]: each
        agent then takes the velocity closest to its answer plus its nudge inside its
        half-planes (an answer on a corner of them, the same for every agent of a symmetric
        crowd, does not move when the wish does; the nudge moves it, along the borders where
        it points out of them, so it never brings a walker into contact). An agent whose
        half-planes leave no room keeps its least-violating answer."""
        from pymunk_bot.actors.orca_lp import solve_all

        c, s = np.cos(self.keep_right), np.sin(self.keep_right)
        pref = np.column_stack([c * pref[:, 0] + s * pref[:, 1], -s * pref[:, 0] + c * pref[:, 1]])
        opos, ovel, orad = others
        order, valid = neighbours
        share = np.where(order < walkers, WALKER_SHARE, self.robot_share[:, None])
        margin = self.margin
        q_n, n_n = neighbour_lines(pos, vel, radius + margin, opos[order], ovel[order],
                                   orad[order] + margin[:, None], share, self.horizon, dt)
        hits, count = walls
        wall_valid = np.arange(MAX_WALL_LINES)[None, :] < count[:, None]
        n_w = np.where(wall_valid[..., None], hits[..., 1:], 0.0)
        room = np.maximum(hits[..., 0] - radius[:, None], 0.0) / self.wall_horizon[:, None]
        q_w = -n_w * np.where(wall_valid, room, 0.0)[..., None]
        q = np.concatenate([q_w, q_n], axis=1)
        n = np.concatenate([n_w, n_n], axis=1)
        ok = np.concatenate([wall_valid, valid], axis=1)
        first = np.argsort(~ok, axis=1, kind="stable")  # valid half-planes first, walls first
        q = np.ascontiguousarray(np.take_along_axis(q, first[..., None], axis=1))
        n = np.ascontiguousarray(np.take_along_axis(n, first[..., None], axis=1))
        counts = ok.sum(axis=1).astype(np.int64)
        hard = wall_valid.sum(axis=1).astype(np.int64)
        vmax = np.ascontiguousarray(vmax, dtype=float)
        chosen = solve_all(q, n, counts, hard, vmax, np.ascontiguousarray(pref, dtype=float))
        if nudge is not None:
            ok_sorted = np.take_along_axis(ok, first, axis=1)
            chosen = nudged_within(q, n, ok_sorted, hard, vmax, chosen, nudge)
        return chosen

