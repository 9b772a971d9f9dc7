"""Following a polyline: rounded corners, a speed profile, progress tracking and pure pursuit.

Pure pursuit (Coulter, "Implementation of the Pure Pursuit Path Tracking Algorithm", CMU-RI-TR-
92-01, 1992) steers along the arc through a "carrot" point one lookahead distance ahead on the
path: curvature = 2 sin(alpha) / L. On a polyline with sharp corners that arc overshoots the
corner (the robot reaches the new leg at an angle and crosses it), so corners are first rounded
with circular fillets tangent to both legs, which lie inside the corner. The speed follows a
profile, as in Regulated Pure Pursuit (Macenski et al., 2023): limited by lateral acceleration
on each bend and by the wheel speed a turn needs, with braking planned backwards from every bend
and from the end. Turns the fillets cannot round (hairpins) are taken on the spot.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from pymunk_bot.geometry.plane import wrap_angle
from pymunk_bot.planning.paths import densify

Point = tuple[float, float]
PROFILE_SPACING = 0.1  # [m] longest segment of a tracked path


def round_corners(points: Sequence[Point], radius: float, loop: bool = False,
                  spacing: float = 0.05) -> list[Point]:
    """The polyline with each corner replaced by a circular arc of up to ``radius`` metres.

    An arc is tangent to both legs and starts at most 45 % of each leg from the corner, so
    neighbouring fillets never overlap; arcs are sampled every ``spacing`` metres.
    """
    pts: list[Point] = [(float(p[0]), float(p[1])) for p in points]
    pts = [p for k, p in enumerate(pts) if k == 0 or math.dist(p, pts[k - 1]) > 1e-9]
    if loop and len(pts) > 1 and math.dist(pts[0], pts[-1]) < 1e-9:
        pts.pop()
    n = len(pts)
    if n < 3 or radius <= 0:
        return pts + ([pts[0]] if loop and n > 1 else [])
    out: list[Point] = []
    indices = range(n) if loop else range(1, n - 1)
    if not loop:
        out.append(pts[0])
    for k in indices:
        a, b, c = np.array(pts[k - 1]), np.array(pts[k]), np.array(pts[(k + 1) % n])
        u, w = b - a, c - b
        lu, lw = float(np.hypot(*u)), float(np.hypot(*w))
        u, w = u / lu, w / lw
        turn = math.atan2(u[0] * w[1] - u[1] * w[0], float(u @ w))
        if abs(turn) < 1e-6 or abs(turn) > math.pi - 1e-3:
            out.append((b[0], b[1]))  # straight on, or a full reversal: keep the vertex
            continue
        tangent = min(radius * math.tan(abs(turn) / 2.0), 0.45 * lu, 0.45 * lw)
        r = tangent / math.tan(abs(turn) / 2.0)
        start = b - u * tangent
        normal = np.array([-u[1], u[0]]) * math.copysign(1.0, turn)  # toward the turn's centre
        centre = start + normal * r
        phi0 = math.atan2(start[1] - centre[1], start[0] - centre[0])
        steps = max(2, math.ceil(abs(turn) * r / spacing))
        for i in range(steps + 1):
            phi = phi0 + turn * i / steps
            out.append((centre[0] + r * math.cos(phi), centre[1] + r * math.sin(phi)))
    if loop:
        out.append(out[0])
    else:
        out.append(pts[-1])
    return out


@dataclass(frozen=True)
class PursuitGains:
    """Tuning of path following (units next to each). The defaults shared with the scenario's
    ``pursuit`` section (:class:`~pymunk_bot.config.controllers.PursuitConfig`) are its own."""

    lookahead: float = 0.6  # [m] at full speed
    lookahead_time: float = 0.4  # [s]; lookahead = speed * this, between the min and the max
    min_lookahead: float = 0.2  # [m]
    max_speed: float = 1.0  # [m/s]
    corner_radius: float = 0.5  # [m] fillet radius of waypoint corners
    lateral_accel: float = 0.6  # [m/s^2] on bends: v <= sqrt(a * radius)
    decel: float = 1.0  # [m/s^2] planned braking ahead of bends and the end
    rotate_threshold: float = 1.2  # [rad]; larger heading errors are turned on the spot
    k_turn: float = 3.0  # [1/s] turn rate per radian of heading error when turning on the spot
    track_width: float = 0.3  # [m]; a turn takes wheel speed from driving
    min_speed: float = 0.05  # [m/s] the profile never asks for less (except at the end)
    drive: str = "diff"  # how a target point becomes a command (see planning/steering.py)
    min_turn_radius: float = 0.0  # [m]; a car's tightest circle
    max_omega: float = math.inf  # [rad/s]


class PathTracker:
    """Arc-length progress along a polyline (or a closed loop), moving forward only, with a
    speed profile.

    Projecting the robot only onto the stretch just ahead of its last progress keeps it from
    skipping to a later part of a path that comes back near itself (a patrol loop, a maze).
    """

    def __init__(self, points: Sequence[Point], loop: bool, gains: PursuitGains) -> None:
        pts: list[Point] = [(float(p[0]), float(p[1])) for p in points]
        if not pts:
            raise ValueError("a path needs at least one point")
        self.loop = loop and len(pts) >= 3
        if self.loop and math.dist(pts[0], pts[-1]) > 1e-9:
            pts.append(pts[0])
        if len(pts) == 1:
            pts.append(pts[0])
        # Vertices every PROFILE_SPACING at most: the speed profile is interpolated between
        # vertices, and braking (a square root of distance) needs the samples.
        self.points = np.asarray(densify(pts, PROFILE_SPACING))
        seg = np.diff(self.points, axis=0)
        self.seg_len = np.hypot(seg[:, 0], seg[:, 1])
        self.cum = np.concatenate([[0.0], np.cumsum(self.seg_len)])
        self.length = float(self.cum[-1])
        self.s = 0.0  # progress [m]; on a loop it keeps counting laps
        self.gains = gains
        self.speed = self._profile()

    @property
    def laps(self) -> int:
        return int(self.s // self.length) if self.loop and self.length > 0 else 0

    def _wrap(self, s):
        if self.loop and self.length > 0:
            return np.mod(s, self.length)
        return np.clip(s, 0.0, self.length)

    def points_at(self, s) -> np.ndarray:
        """Path points ``s`` metres from the start (wrapping on loops, clamped otherwise)."""
        s = self._wrap(np.atleast_1d(np.asarray(s, dtype=float)))
        x = np.interp(s, self.cum, self.points[:, 0])
        y = np.interp(s, self.cum, self.points[:, 1])
        return np.column_stack([x, y])

    def point_at(self, s: float) -> np.ndarray:
        return self.points_at(s)[0]

    def speed_at(self, s: float) -> float:
        """The profile's speed limit [m/s] at progress ``s``."""
        return float(np.interp(self._wrap(s), self.cum, self.speed))

    def update(self, x: float, y: float, window: float) -> float:
        """Advance the progress to the nearest path point within ``window`` metres ahead."""
        if self.length > 0:
            samples = self.s + np.linspace(0.0, window, max(2, int(window / 0.02) + 1))
            if not self.loop:
                samples = np.minimum(samples, self.length)
            pts = self.points_at(samples)
            k = int(np.argmin((pts[:, 0] - x) ** 2 + (pts[:, 1] - y) ** 2))
            self.s = float(samples[k])
        return self.s

    def remaining(self) -> float:
        """Metres left to the end (inf on a loop)."""
        return math.inf if self.loop else self.length - self.s

    def _profile(self) -> np.ndarray:
        """Speed limit at each vertex: bends (lateral acceleration, wheel share), then braking."""
        g = self.gains
        n = len(self.points)
        limit = np.full(n, g.max_speed)
        if n >= 3:
            seg = np.diff(self.points, axis=0)
            heading = np.arctan2(seg[:, 1], seg[:, 0])
            turn = np.abs((np.diff(heading) + np.pi) % (2 * np.pi) - np.pi)
            around = 0.5 * (self.seg_len[:-1] + self.seg_len[1:])
            curvature = turn / np.maximum(around, 1e-9)
            bend = np.minimum(np.sqrt(g.lateral_accel / np.maximum(curvature, 1e-9)),
                              g.max_speed / (1.0 + 0.5 * g.track_width * curvature))
            # A turn sharper than the pursuer will follow is taken on the spot: stop there.
            bend[turn > g.rotate_threshold] = 0.0
            limit[1:-1] = np.minimum(limit[1:-1], np.maximum(bend, np.where(
                turn > g.rotate_threshold, 0.0, g.min_speed)))
            if self.loop:
                first = math.atan2(seg[0, 1], seg[0, 0])
                last = math.atan2(seg[-1, 1], seg[-1, 0])
                closing = abs(wrap_angle(first - last))
                k = closing / max(0.5 * (self.seg_len[0] + self.seg_len[-1]), 1e-9)
                v = min(math.sqrt(g.lateral_accel / max(k, 1e-9)),
                        g.max_speed / (1.0 + 0.5 * g.track_width * k))
                limit[0] = limit[-1] = 0.0 if closing > g.rotate_threshold else max(v, g.min_speed)
        if not self.loop:
            limit[-1] = 0.0
        # Braking: v_i <= sqrt(v_{i+1}^2 + 2 a ds), backwards (twice around a loop).
        passes = 2 if self.loop else 1
        for _ in range(passes):
            for i in range(n - 2, -1, -1):
                limit[i] = min(limit[i], math.sqrt(limit[i + 1] ** 2 + 2 * g.decel * self.seg_len[i]))
            if self.loop:
                limit[-1] = limit[0] = min(limit[0], limit[-1])
        return limit


def pursue(pose: Sequence[float] | np.ndarray, carrot: Sequence[float] | np.ndarray,
           gains: PursuitGains, speed: float) -> tuple[float, float]:
    """(v [m/s], omega [rad/s]) that drive at ``speed`` along the arc through ``carrot``."""
    x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
    dx, dy = float(carrot[0]) - x, float(carrot[1]) - y
    distance = math.hypot(dx, dy)
    if distance < 1e-9:
        return 0.0, 0.0
    alpha = wrap_angle(math.atan2(dy, dx) - theta)
    if abs(alpha) > gains.rotate_threshold:
        return 0.0, gains.k_turn * alpha
    curvature = 2.0 * math.sin(alpha) / distance
    # Slow down while the heading is still far off (after turning on the spot, say).
    v = min(gains.max_speed, speed) * max(0.0, math.cos(alpha))
    return v, v * curvature
