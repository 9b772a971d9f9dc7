"""The Dynamic Window Approach: choose (v, omega) by scoring short arcs against LiDAR points.

Fox, Burgard and Thrun, "The Dynamic Window Approach to Collision Avoidance", IEEE Robotics &
Automation Magazine 4(1), 1997. Each control tick the robot considers only the velocities it can
reach within one period (its acceleration limits: the "dynamic window"), simulates each as a
constant-velocity arc for ``horizon`` seconds, drops arcs on which it could not stop before the
first obstacle, and picks the best weighted sum of heading toward the target, clearance and
speed, plus (as in ROS's dwa_local_planner) progress toward the target, so that standing still
in front of an obstacle never beats driving around it.

We chose DWA over VFH+ because it reasons with the drive's real limits (a force-limited diff
drive with max wheel speed and acceleration), works directly on the scan points without a
histogram grid, and its admissibility test ("can I still stop?") is the property our regression
tests check: no collisions. Like every purely reactive method it has local minima (a U-shaped
trap holds it); ``navigate`` adds a global planner for that.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from pymunk_bot.robots.readings import LaserScan, RobotSpec


@dataclass(frozen=True)
class DwaParams:
    """Tuning of the dynamic window (units next to each)."""

    horizon: float = 1.5  # [s] how far ahead each candidate arc is simulated
    time_samples: int = 12  # collision checks along each arc
    v_samples: int = 7  # forward speeds tried
    w_samples: int = 15  # turn rates tried
    safety: float = 0.1  # [m] extra clearance that already counts as a collision
    heading_weight: float = 0.4
    progress_weight: float = 1.0
    clearance_weight: float = 0.5
    speed_weight: float = 0.2
    clearance_cap: float = 0.4  # [m] clearance beyond this scores no better
    max_speed: float | None = None  # [m/s]; None = the robot's max wheel speed
    allow_reverse: bool = False  # back up slowly when nothing forward is safe


def scan_points(scan: LaserScan) -> np.ndarray:
    """LiDAR returns as points in the robot frame [m], shape (n, 2); beams without one dropped.

    Beam angles are relative to the robot heading (the mount's yaw is already in them); the
    beams start at the mount's position ``offset[:2]``.
    """
    ranges = np.asarray(scan.ranges, dtype=float)
    hit = (ranges < scan.max_range) & (ranges >= scan.min_range) & np.isfinite(ranges)
    r, a = ranges[hit], np.asarray(scan.angles, dtype=float)[hit]
    ox, oy = scan.offset[0], scan.offset[1]
    return np.column_stack([ox + r * np.cos(a), oy + r * np.sin(a)])


class DynamicWindow:
    """Chooses a safe (v, omega) toward a target point, both in the robot frame."""

    def __init__(self, robot: RobotSpec, params: DwaParams, period: float) -> None:
        self.robot = robot
        self.params = params
        self.period = period  # [s] control period: the window is what one period can reach
        self.max_speed = min(params.max_speed or robot.max_wheel_speed, robot.max_wheel_speed)
        self.half_track = 0.5 * robot.track_width
        self.accel = robot.max_accel  # [m/s^2] per wheel
        self.alpha = robot.max_accel / self.half_track  # [rad/s^2] turning on the spot
        self.max_omega = robot.max_wheel_speed / self.half_track  # [rad/s]
        self.last_clearance = math.inf  # [m] of the chosen arc, for callers that watch for blocks

    def _window(self, v0: float, w0: float) -> tuple[np.ndarray, np.ndarray]:
        p = self.params
        dv = self.accel * self.period
        dw = self.alpha * self.period
        v_low = -0.25 * self.max_speed if p.allow_reverse else 0.0
        v: np.ndarray = np.linspace(max(v_low, v0 - dv), min(self.max_speed, v0 + dv), p.v_samples)
        w: np.ndarray = np.linspace(max(-self.max_omega, w0 - dw), min(self.max_omega, w0 + dw),
                                    p.w_samples)
        v = np.unique(np.concatenate([v, [0.0] if v[0] <= 0.0 <= v[-1] else []]))
        w = np.unique(np.concatenate([w, [0.0] if w[0] <= 0.0 <= w[-1] else []]))
        vv, ww = np.meshgrid(v, w, indexing="ij")
        vv, ww = vv.ravel(), ww.ravel()
        # A diff drive shares its wheel speed between driving and turning.
        ok = np.abs(vv) + np.abs(ww) * self.half_track <= self.robot.max_wheel_speed + 1e-9
        return vv[ok], ww[ok]

    def arcs(self, v: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (m candidates x k times) and headings of constant-(v, omega) arcs."""
        p = self.params
        t = np.linspace(p.horizon / p.time_samples, p.horizon, p.time_samples)
        wt = np.outer(w, t)
        straight = np.abs(w) < 1e-6
        safe_w = np.where(straight, 1.0, w)[:, None]
        x = np.where(straight[:, None], np.outer(v, t), v[:, None] / safe_w * np.sin(wt))
        y = np.where(straight[:, None], 0.0, v[:, None] / safe_w * (1.0 - np.cos(wt)))
        return x, y, wt

    def candidates(self, v0: float, w0: float, obstacles: np.ndarray,
                   speed_cap: float = math.inf, velocities: np.ndarray | None = None):
        """The admissible (v, omega) pairs from the current (v0, w0) and their arcs.

        Returns (v, w, x, y, heading, clearance) over the admissible candidates, or None when
        none is admissible. Arcs are checked against ``obstacles`` (robot frame, (n, 2)); a
        candidate is admissible when the robot can stop (v^2 / 2a) within its free run, and
        turning on the spot always is (the robot is a disc). ``velocities`` (n, 2) [m/s], if
        given, marks points that move: each is checked both where it is and where it will be
        at each sample time, so a prediction can only make an arc less safe, never more.
        """
        p = self.params
        v, w = self._window(v0, w0)
        if speed_cap < math.inf:
            keep = v <= max(speed_cap, 0.0) + 1e-9
            if not keep.any():  # the window is above the cap: brake as hard as allowed
                keep = v == v.min()
            v, w = v[keep], w[keep]
        x, y, heading = self.arcs(v, w)
        reach = self.max_speed * p.horizon + self.robot.radius + p.safety + 0.1
        pts = np.asarray(obstacles, dtype=float).reshape(-1, 2)
        vel = (np.zeros_like(pts) if velocities is None
               else np.asarray(velocities, dtype=float).reshape(-1, 2))
        if len(pts):
            near = np.hypot(pts[:, 0], pts[:, 1]) < reach + np.hypot(vel[:, 0], vel[:, 1]) * p.horizon
            pts, vel = pts[near], vel[near]
        now = math.inf
        if len(pts):
            # Clearance of the robot's disc at each arc sample to the nearest point ...
            moving = np.any(vel != 0.0, axis=1)
            t = np.linspace(p.horizon / p.time_samples, p.horizon, p.time_samples)
            # ... and to where the moving ones will be at each sample time, (k, n) each
            px = pts[moving, 0][None, :] + t[:, None] * vel[moving, 0][None, :]
            py = pts[moving, 1][None, :] + t[:, None] * vel[moving, 1][None, :]
            d = arc_distances(np.ascontiguousarray(x), np.ascontiguousarray(y),
                              np.ascontiguousarray(pts), px, py)
            clear_t = d - self.robot.radius  # (m, k)
            now = float(np.sqrt(pts[:, 0] ** 2 + pts[:, 1] ** 2).min()) - self.robot.radius
            # Already inside the safety band: arcs may get a little closer (never below a
            # quarter of it), or every arc would count as a collision and the robot would freeze.
            hit = clear_t < min(p.safety, max(now - 0.2 * p.safety, 0.25 * p.safety))
            first = np.where(hit.any(axis=1), hit.argmax(axis=1), p.time_samples)
            free_run = np.abs(v) * first * (p.horizon / p.time_samples)  # [m] to the last safe sample
            clearance = clear_t.min(axis=1)
        else:
            free_run = np.full(v.shape, math.inf)
            clearance = np.full(v.shape, math.inf)
        admissible = (v * v <= 2.0 * self.accel * free_run) | (v == 0.0)
        if p.allow_reverse and now < p.safety:
            admissible |= v < 0  # already too close: backing away is allowed
        if not admissible.any():
            return None
        keep = admissible
        return v[keep], w[keep], x[keep], y[keep], heading[keep], clearance[keep]

    def choose(self, v0: float, w0: float, obstacles: np.ndarray, target: np.ndarray,
               speed_cap: float = math.inf,
               velocities: np.ndarray | None = None) -> tuple[float, float]:
        """Best (v, omega) toward ``target`` (robot frame) from the current (v0, w0).

        ``speed_cap`` [m/s] limits forward speed (e.g. to slow down at the goal);
        ``velocities`` of the obstacle points, see :meth:`candidates`.
        """
        p = self.params
        found = self.candidates(v0, w0, obstacles, speed_cap, velocities)
        if found is None:
            self.last_clearance = 0.0
            return 0.0, 0.0
        v, w, x, y, heading, clearance = found
        # Heading: the target's bearing from the arc's end pose (0 best, pi worst).
        tx, ty = float(target[0]), float(target[1])
        end_x, end_y, end_h = x[:, -1], y[:, -1], heading[:, -1]
        bearing = np.abs((np.arctan2(ty - end_y, tx - end_x) - end_h + np.pi) % (2 * np.pi) - np.pi)
        near = np.hypot(tx - end_x, ty - end_y) < 0.05
        heading_score = np.where(near, 1.0, 1.0 - bearing / np.pi)
        clear_score = np.minimum(clearance, p.clearance_cap) / p.clearance_cap
        speed_score = v / self.max_speed
        # Progress: how much closer to the target the arc ends, per the best possible.
        progress = (math.hypot(tx, ty) - np.hypot(tx - end_x, ty - end_y)) / (
            self.max_speed * p.horizon)
        # Absolute scores in [0, 1]: normalising over the candidates (as the paper does) blows
        # tiny differences up to the full range, and a robot with an obstacle ahead then prefers
        # standing still to losing a centimetre of clearance.
        score = (p.heading_weight * heading_score + p.progress_weight * progress
                 + p.clearance_weight * clear_score + p.speed_weight * speed_score)
        best = int(np.argmax(score))
        self.last_clearance = float(clearance[best])
        return float(v[best]), float(w[best])

    def track(self, v0: float, w0: float, obstacles: np.ndarray, v_ref: float,
              w_ref: float, velocities: np.ndarray | None = None) -> tuple[float, float]:
        """The admissible (v, omega) nearest to a reference command (a safety filter).

        A path follower proposes (v_ref, w_ref); if its arc is safe it is (nearly) what runs,
        otherwise the closest safe arc, slower or veering, with clearance breaking ties.
        """
        p = self.params
        found = self.candidates(v0, w0, obstacles, max(v_ref, 0.0), velocities)
        if found is None:
            self.last_clearance = 0.0
            return 0.0, 0.0
        v, w, _, _, _, clearance = found
        if len(v) == 0:
            return 0.0, 0.0
        v_ref = min(max(v_ref, float(v.min())), float(v.max()))
        w_ref = min(max(w_ref, float(w.min())), float(w.max()))
        # The window's grid may not hold the reference itself: pick the closest candidate,
        # but send the reference when that candidate is the clipped reference's neighbour.
        miss = np.abs(v - v_ref) / self.max_speed + np.abs(w - w_ref) / self.max_omega
        clear_score = np.minimum(clearance, p.clearance_cap) / p.clearance_cap
        score = -miss + 0.05 * p.clearance_weight * clear_score
        best = int(np.argmax(score))
        self.last_clearance = float(clearance[best])
        if miss[best] <= 1.0 / max(p.v_samples, p.w_samples) and clearance[best] >= p.safety:
            return v_ref, w_ref  # the reference is as safe as its neighbour: follow it exactly
        return float(v[best]), float(w[best])


def free_runs(points: np.ndarray, radius: float, directions: np.ndarray,
              max_length: float) -> np.ndarray:
    """How far [m] a disc of ``radius`` at the origin can slide straight along each direction
    [rad] before it touches one of ``points`` (robot frame), capped at ``max_length``."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(pts) == 0:
        return np.full(len(directions), max_length)
    ux, uy = np.cos(directions)[:, None], np.sin(directions)[:, None]
    along = ux * pts[None, :, 0] + uy * pts[None, :, 1]
    lateral = np.abs(ux * pts[None, :, 1] - uy * pts[None, :, 0])
    # Points behind the direction of travel never block it, even when closer than ``radius``.
    blocking = (lateral < radius) & (along > 0.0)
    contact = along - np.sqrt(np.maximum(radius * radius - lateral * lateral, 0.0))
    contact = np.where(blocking, np.maximum(contact, 0.0), np.inf)
    return np.minimum(contact.min(axis=1), max_length)


@numba.njit(cache=True, nogil=True)
def arc_distances(x: np.ndarray, y: np.ndarray, points: np.ndarray, moving_x: np.ndarray,
                  moving_y: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """Distance [m] from each arc sample (``x``, ``y``: (m, k)) to the nearest of ``points``
    (n, 2) and of the moving points at that sample's time (``moving_x``, ``moving_y``:
    (k, n'))."""
    m, k = x.shape
    out = np.empty((m, k))
    for a in range(m):
        for j in range(k):
            sx, sy = x[a, j], y[a, j]
            near2 = np.inf
            for i in range(len(points)):
                dx, dy = sx - points[i, 0], sy - points[i, 1]
                near2 = min(near2, dx * dx + dy * dy)
            for i in range(moving_x.shape[1]):
                dx, dy = sx - moving_x[j, i], sy - moving_y[j, i]
                near2 = min(near2, dx * dx + dy * dy)
            out[a, j] = math.sqrt(near2)
    return out
