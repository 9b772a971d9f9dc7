"""Hybrid A* for car-like robots (Dolgov, Thrun, Montemerlo & Diebel, "Path Planning for
Autonomous Vehicles in Unknown Semi-structured Environments", IJRR 29(5), 2010).

The search expands continuous poses (x, y, theta) with short arcs the car can drive: forward
and (optionally) in reverse, each at five curvatures from full left lock to full right lock,
and keeps one pose per cell of (x, y, heading bin). Every arc is checked along its length with
the robot's real footprint: the discs that cover it must each fit the clearance grid. Reversing
and changing direction cost extra. The heuristic is the larger of the straight-line distance
and the obstacle-aware distance on a coarse grid (Dijkstra from the goal), both admissible
for the position part of the cost.
"""
from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pymunk_bot.planning.grid import ClearanceGrid

HEURISTIC_CELL = 0.2  # [m] cells of the obstacle-aware distance heuristic
CURVATURE_FRACTIONS = (-1.0, -0.5, 0.0, 0.5, 1.0)
MAX_ANALYTIC_TURN = math.pi  # [rad] of turning a Dubins finish may have in all
ANALYTIC_RANGE = 4.0  # closer than this many turning radii, try a Dubins finish every expansion


@dataclass(frozen=True)
class HybridParams:
    """Search settings (units next to each)."""

    step: float = 0.2  # [m] arc length of one expansion
    heading_bins: int = 72  # headings per turn kept apart
    reverse: bool = True  # may it back up
    reverse_cost: float = 1.5  # cost per metre in reverse, relative to forward
    switch_cost: float = 1.0  # [m] extra cost of changing direction
    steer_cost: float = 0.05  # [m] per expansion that is not straight
    max_expansions: int = 40000  # give up after this many
    margin: float = 0.02  # [m] clearance kept beyond the footprint


@dataclass
class HybridResult:
    """``poses`` (n, 3) [m, m, rad] along the path and ``direction`` (n,) +1 forward, -1 reverse
    (the direction of the motion that arrives at each pose); empty with ``reason`` on failure."""

    poses: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    direction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    reason: str = ""
    expansions: int = 0

    @property
    def found(self) -> bool:
        return len(self.poses) > 0

    def segments(self) -> list[tuple[int, np.ndarray]]:
        """The path cut where the direction changes: [(direction, poses (m, 3)), ...]."""
        out: list[tuple[int, np.ndarray]] = []
        start = 0
        for k in range(2, len(self.poses)):
            if self.direction[k] != self.direction[k - 1]:
                out.append((int(self.direction[k - 1]), self.poses[start:k]))
                start = k - 1
        out.append((int(self.direction[-1]), self.poses[start:]))
        return out


class FootprintChecker:
    """Does a car fit at many poses at once? Discs (robot frame) against a clearance grid."""

    def __init__(self, grid: ClearanceGrid, centres: np.ndarray, radii: np.ndarray,
                 margin: float) -> None:
        self.grid = grid
        self.centres = np.asarray(centres, dtype=float)
        # Nearest-cell look-ups can be off by half a cell diagonal: keep that much more.
        self.need = np.asarray(radii, dtype=float) + margin + grid.resolution * math.sqrt(0.5)

    def free(self, poses: np.ndarray) -> np.ndarray:
        """(...,) bool for poses (..., 3)."""
        x, y, th = poses[..., 0, None], poses[..., 1, None], poses[..., 2, None]
        c, s = np.cos(th), np.sin(th)
        px = x + c * self.centres[:, 0] - s * self.centres[:, 1]
        py = y + s * self.centres[:, 0] + c * self.centres[:, 1]
        g = self.grid
        inside = (px >= 0) & (py >= 0) & (px <= g.size[0]) & (py <= g.size[1])
        cols = np.clip((px / g.resolution).astype(int), 0, g.cols - 1)
        rows = np.clip((py / g.resolution).astype(int), 0, g.rows - 1)
        ok = inside & (g.clearance[rows, cols] >= self.need)
        return ok.all(axis=-1)


def distance_field(grid: ClearanceGrid, goal, clearance: float) -> tuple[np.ndarray, float]:
    """Obstacle-aware distance [m] to ``goal`` from every cell of a coarse grid (inf: cut off),
    through cells whose clearance is at least ``clearance``; and the coarse cell size [m]."""
    cell = max(HEURISTIC_CELL, grid.resolution)
    step = max(1, round(cell / grid.resolution))
    coarse = grid.clearance[::step, ::step] + 0.5 * step * grid.resolution * math.sqrt(2)
    rows, cols = coarse.shape
    cell = step * grid.resolution
    passable = coarse >= clearance
    dist = np.full((rows, cols), np.inf)
    gr = min(rows - 1, int(goal[1] / cell))
    gc = min(cols - 1, int(goal[0] / cell))
    dist[gr, gc] = 0.0
    heap = [(0.0, gr, gc)]
    moves = [(dr, dc, cell * math.hypot(dr, dc)) for dr in (-1, 0, 1) for dc in (-1, 0, 1)
             if dr or dc]
    while heap:
        d, r, c = heapq.heappop(heap)
        if d > dist[r, c]:
            continue
        for dr, dc, w in moves:
            nr, nc = r + dr, c + dc
            if 0 <= nr < rows and 0 <= nc < cols and passable[nr, nc] and d + w < dist[nr, nc]:
                dist[nr, nc] = d + w
                heapq.heappush(heap, (d + w, nr, nc))
    return dist, cell


def _primitives(step: float, radius: float, spacing: float, reverse: bool):
    """Every primitive at once: directions (P,), curvature fractions (P,) and the pose change
    along each (P, S, 3), robot frame."""
    n = max(2, math.ceil(step / spacing))
    s = np.linspace(step / n, step, n)
    dirs, fracs, samples = [], [], []
    for direction in ((1, -1) if reverse else (1,)):
        for fraction in CURVATURE_FRACTIONS:
            k = fraction / radius
            d = direction * s
            if abs(k) < 1e-12:
                samples.append(np.column_stack([d, np.zeros(n), np.zeros(n)]))
            else:
                th = k * d
                samples.append(np.column_stack([np.sin(th) / k, (1 - np.cos(th)) / k, th]))
            dirs.append(direction)
            fracs.append(fraction)
    return np.array(dirs), np.array(fracs), np.array(samples)


def _place(pose: np.ndarray, local: np.ndarray) -> np.ndarray:
    """Robot-frame pose changes (..., 3) applied at ``pose``."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    out = np.empty_like(local)
    out[..., 0] = pose[0] + c * local[..., 0] - s * local[..., 1]
    out[..., 1] = pose[1] + s * local[..., 0] + c * local[..., 1]
    out[..., 2] = pose[2] + local[..., 2]
    return out


def hybrid_astar(checker: FootprintChecker, start, goal, goal_tolerance: float,
                 min_turn_radius: float, params: HybridParams = HybridParams(),
                 goal_heading: float | None = None, heading_tolerance: float = 0.2,
                 heuristic_clearance: float = 0.0) -> HybridResult:
    """Plan from ``start`` (x, y, theta) until the pose point is within ``goal_tolerance`` [m]
    of ``goal`` (x, y), facing ``goal_heading`` within ``heading_tolerance`` if given.

    With a goal heading, every few expansions the search also tries to finish with one
    Reeds-Shepp path to the exact goal pose (forward and reverse, with cusps; a Dubins path when
    reversing is not allowed): the analytic expansion of Dolgov et al., which finds the last
    manoeuvre into a parking space."""
    grid = checker.grid
    start = np.asarray(start, dtype=float)
    if not checker.free(start[None])[0]:
        return HybridResult(reason="the start pose collides (footprint against the map)")
    field_, cell = distance_field(grid, goal, heuristic_clearance)
    spacing = 0.5 * grid.resolution
    dirs, fracs, local = _primitives(params.step, min_turn_radius, spacing, params.reverse)
    step_cost = params.step * np.where(dirs < 0, params.reverse_cost, 1.0) + np.where(
        fracs != 0, params.steer_cost, 0.0)
    bins = params.heading_bins
    key_res = max(0.7 * params.step, grid.resolution)
    target = None if goal_heading is None else (float(goal[0]), float(goal[1]), float(goal_heading))

    def key(p):
        return (int(p[0] // key_res), int(p[1] // key_res),
                int(round(p[2] / (2 * math.pi / bins))) % bins)

    def h(p):
        r = min(field_.shape[0] - 1, int(p[1] / cell))
        c = min(field_.shape[1] - 1, int(p[0] / cell))
        value = max(math.hypot(goal[0] - p[0], goal[1] - p[1]), float(field_[r, c]))
        return value

    def at_goal(p):
        if math.hypot(goal[0] - p[0], goal[1] - p[1]) > goal_tolerance:
            return False
        return goal_heading is None or abs(
            (p[2] - goal_heading + math.pi) % (2 * math.pi) - math.pi) <= heading_tolerance

    # (pose, parent, direction, samples to reach it)
    nodes: list[tuple[np.ndarray, int, int, Any]] = [(start, -1, 0, None)]
    best = {key(start): 0.0}
    heap = [(h(start), 0.0, 0)]
    expansions = 0
    while heap:
        _, g, index = heapq.heappop(heap)
        pose, _, direction, _ = nodes[index]
        if g > best.get(key(pose), math.inf) + 1e-9:
            continue
        if at_goal(pose):
            return _trace(nodes, index, expansions)
        expansions += 1
        if expansions > params.max_expansions:
            break
        near = math.hypot(goal[0] - pose[0], goal[1] - pose[1]) < ANALYTIC_RANGE * min_turn_radius
        if target is not None and (near or expansions % 10 == 1):
            finish = _analytic(checker, pose, target, min_turn_radius, spacing, params.reverse)
            if finish is not None:
                poses, directions = finish
                nodes.append((poses[-1], index, int(directions[-1]), (poses, directions)))
                return _trace(nodes, len(nodes) - 1, expansions)
        world = _place(pose, local)  # (P, S, 3)
        free = checker.free(world).all(axis=1)
        for k in np.flatnonzero(free).tolist():
            end = world[k, -1]
            cost = step_cost[k]
            if direction and dirs[k] != direction:
                cost += params.switch_cost
            node_key = key(end)
            g2 = g + cost
            if g2 < best.get(node_key, math.inf) - 1e-9:
                best[node_key] = g2
                nodes.append((end, index, int(dirs[k]), world[k]))
                heapq.heappush(heap, (g2 + h(end), g2, len(nodes) - 1))
    reason = (f"no drivable path within {params.max_expansions} expansions"
              if expansions > params.max_expansions else "no drivable path to the goal")
    return HybridResult(reason=reason, expansions=expansions)


def _analytic(checker: FootprintChecker, pose, target, radius: float, spacing: float,
              reverse: bool) -> tuple[np.ndarray, np.ndarray] | None:
    """A collision-free finish from ``pose`` to ``target``: the Reeds-Shepp path when reversing
    is allowed (else the Dubins path); (poses, direction per pose) or None."""
    from pymunk_bot.planning import dubins, reeds_shepp
    if reverse:
        segments = reeds_shepp.shortest(pose, target, radius)
        if segments is None:
            return None
        poses, directions = reeds_shepp.sample(pose, segments, radius, spacing)
    else:
        segments = dubins.shortest(pose, target, radius)
        if segments is None:
            return None
        poses = dubins.sample(pose, segments, radius, spacing)
        directions = np.ones(len(poses))
    turning = sum(abs(length) for kind, length in segments if kind != "S") / radius
    if turning > MAX_ANALYTIC_TURN or not checker.free(poses).all():
        return None  # a loop (the search finds better than driving in circles), or a collision
    return poses, directions


def _trace(nodes, index: int, expansions: int) -> HybridResult:
    chain = []
    while index >= 0:
        chain.append(nodes[index])
        index = nodes[index][1]
    chain.reverse()
    poses = [chain[0][0][None]]
    direction = [float(chain[1][2]) if len(chain) > 1 else 1.0]
    for _, _, d, samples in chain[1:]:
        if isinstance(samples, tuple):  # an analytic finish: its own direction per pose
            poses.append(samples[0])
            direction.extend(samples[1].tolist())
        else:
            poses.append(samples)
            direction.extend([float(d)] * len(samples))
    if len(direction) > 1:
        direction[0] = direction[1]
    return HybridResult(np.vstack(poses), np.array(direction, dtype=float), expansions=expansions)
