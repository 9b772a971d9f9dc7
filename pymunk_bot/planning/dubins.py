"""Dubins paths: the shortest forward path between two poses with a minimum turning radius
(Dubins 1957; the closed forms of Shkel & Lumelsky, "Classification of the Dubins set",
Robotics and Autonomous Systems 34, 2001). Each candidate word is integrated and kept only if
it really ends at the goal pose, so a numerically bad case is dropped, never followed.

A path driven entirely in reverse between two poses is the forward path between the same
poses with both headings turned by pi (:func:`reverse_path`).
"""
from __future__ import annotations

import math

import numpy as np

TWO_PI = 2 * math.pi
END_TOLERANCE = 1e-6  # [m, rad], in units of the radius


def _mod(a: float) -> float:
    return a % TWO_PI


def _words(alpha: float, beta: float, d: float):
    """(word, (t, p, q)) candidates in normalised units (radius 1)."""
    sa, sb, ca, cb = math.sin(alpha), math.sin(beta), math.cos(alpha), math.cos(beta)
    cab = math.cos(alpha - beta)
    out = []
    p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)
    if p2 >= 0:
        tmp = math.atan2(cb - ca, d + sa - sb)
        out.append(("LSL", (_mod(-alpha + tmp), math.sqrt(p2), _mod(beta - tmp))))
    p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)
    if p2 >= 0:
        tmp = math.atan2(ca - cb, d - sa + sb)
        out.append(("RSR", (_mod(alpha - tmp), math.sqrt(p2), _mod(-beta + tmp))))
    p2 = -2 + d * d + 2 * cab + 2 * d * (sa + sb)
    if p2 >= 0:
        p = math.sqrt(p2)
        tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out.append(("LSR", (_mod(-alpha + tmp), p, _mod(-_mod(beta) + tmp))))
    p2 = -2 + d * d + 2 * cab - 2 * d * (sa + sb)
    if p2 >= 0:
        p = math.sqrt(p2)
        tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out.append(("RSL", (_mod(alpha - tmp), p, _mod(beta - tmp))))
    tmp = (6 - d * d + 2 * cab + 2 * d * (sa - sb)) / 8
    if abs(tmp) <= 1:
        p = _mod(TWO_PI - math.acos(tmp))
        t = _mod(alpha - math.atan2(ca - cb, d - sa + sb) + p / 2)
        out.append(("RLR", (t, p, _mod(alpha - beta - t + p))))
    tmp = (6 - d * d + 2 * cab + 2 * d * (-sa + sb)) / 8
    if abs(tmp) <= 1:
        p = _mod(TWO_PI - math.acos(tmp))
        t = _mod(-alpha - math.atan2(ca - cb, d + sa - sb) + p / 2)
        out.append(("LRL", (t, p, _mod(beta - alpha - t + p))))
    return out


def _advance(pose, kind: str, length: float, radius: float):
    x, y, th = pose
    if kind == "S":
        return (x + length * math.cos(th), y + length * math.sin(th), th)
    turn = (1 if kind == "L" else -1) * length / radius
    return (x + radius * (math.sin(th + turn) - math.sin(th)) * (1 if kind == "L" else -1),
            y - radius * (math.cos(th + turn) - math.cos(th)) * (1 if kind == "L" else -1),
            th + turn)


def shortest(start, goal, radius: float) -> list[tuple[str, float]] | None:
    """Segments [(kind "L"/"S"/"R", length [m])] of the shortest Dubins path, or None."""
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    d = math.hypot(dx, dy) / radius
    phi = math.atan2(dy, dx)
    alpha, beta = _mod(start[2] - phi), _mod(goal[2] - phi)
    best, best_len = None, math.inf
    for word, lengths in _words(alpha, beta, d):
        total = sum(lengths) * radius
        if total >= best_len:
            continue
        segs = [(k, v * radius) for k, v in zip(word, lengths)]
        pose = tuple(start)
        for kind, length in segs:
            pose = _advance(pose, kind, length, radius)
        heading_error = abs((pose[2] - goal[2] + math.pi) % TWO_PI - math.pi)
        if math.hypot(pose[0] - goal[0], pose[1] - goal[1]) <= END_TOLERANCE * max(1.0, radius) \
                and heading_error <= END_TOLERANCE:
            best, best_len = segs, total
    return best


def sample(start, segments: list[tuple[str, float]], radius: float, spacing: float) -> np.ndarray:
    """Poses (n, 3) along a path every ``spacing`` metres at most, ending at its end."""
    out = []
    pose = tuple(start)
    for kind, length in segments:
        n = max(1, math.ceil(length / spacing))
        for k in range(1, n + 1):
            out.append(_advance(pose, kind, length * k / n, radius))
        pose = _advance(pose, kind, length, radius)
    return np.array(out).reshape(-1, 3)


def reverse_path(start, goal, radius: float, spacing: float) -> np.ndarray | None:
    """Poses of the shortest path from ``start`` to ``goal`` driven entirely in reverse."""
    flip = (start[0], start[1], start[2] + math.pi)
    segs = shortest(flip, (goal[0], goal[1], goal[2] + math.pi), radius)
    if segs is None:
        return None
    poses = sample(flip, segs, radius, spacing)
    poses[:, 2] -= math.pi
    return poses

