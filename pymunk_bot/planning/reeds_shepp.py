"""Reeds-Shepp paths: the shortest path between two poses for a car that drives forward and
backward with a minimum turning radius (Reeds & Shepp, Pacific J. Math. 145(2), 1990).

We use the CSC and CCC families with cusps (the closed forms of the paper's section 8, under the
paper's time-flip, reflection and backwards symmetries), which hold the manoeuvres a parking
car needs (reverse in with opposite locks, pull forward). Every candidate is integrated and kept
only if it really ends at the goal pose, so a formula that does not apply to a case is dropped,
never followed. Segment lengths are signed: negative means driving in reverse.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

END_TOLERANCE = 1e-6  # in units of the radius

Word = tuple[tuple[float, float, float], str]  # (signed lengths in radius units, kinds)


def _mod2pi(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _polar(x: float, y: float) -> tuple[float, float]:
    return math.hypot(x, y), math.atan2(y, x)


def _lsl(x: float, y: float, phi: float) -> Word | None:
    u, t = _polar(x - math.sin(phi), y - 1.0 + math.cos(phi))
    if t >= 0.0:
        v = _mod2pi(phi - t)
        if v >= 0.0:
            return (t, u, v), "LSL"
    return None


def _lsr(x: float, y: float, phi: float) -> Word | None:
    u1, t1 = _polar(x + math.sin(phi), y - 1.0 - math.cos(phi))
    if u1 * u1 >= 4.0:
        u = math.sqrt(u1 * u1 - 4.0)
        t = _mod2pi(t1 + math.atan2(2.0, u))
        v = _mod2pi(t - phi)
        if t >= 0.0 and v >= 0.0:
            return (t, u, v), "LSR"
    return None


def _lxrxl(x: float, y: float, phi: float) -> Word | None:
    """L+ R- L+ (two cusps)."""
    u1, theta = _polar(x - math.sin(phi), y - 1.0 + math.cos(phi))
    if u1 <= 4.0:
        a = math.acos(0.25 * u1)
        t = _mod2pi(a + theta + math.pi / 2)
        u = _mod2pi(math.pi - 2 * a)
        v = _mod2pi(phi - t - u)
        return (t, -u, v), "LRL"
    return None


def _lxrl(x: float, y: float, phi: float) -> Word | None:
    """L+ R- L- (one cusp)."""
    u1, theta = _polar(x - math.sin(phi), y - 1.0 + math.cos(phi))
    if u1 <= 4.0:
        a = math.acos(0.25 * u1)
        t = _mod2pi(a + theta + math.pi / 2)
        u = _mod2pi(math.pi - 2 * a)
        v = _mod2pi(-phi + t + u)
        return (t, -u, -v), "LRL"
    return None


def _lrxl(x: float, y: float, phi: float) -> Word | None:
    """L+ R+ L- (one cusp)."""
    u1, theta = _polar(x - math.sin(phi), y - 1.0 + math.cos(phi))
    if u1 <= 4.0:
        u = math.acos(1.0 - u1 * u1 * 0.125)
        a = math.asin(2.0 * math.sin(u) / u1) if u1 > 1e-12 else 0.0
        t = _mod2pi(-a + theta + math.pi / 2)
        v = _mod2pi(t - u - phi)
        return (t, u, -v), "LRL"
    return None


_CSC: list[Callable[[float, float, float], Word | None]] = [_lsl, _lsr]
_CCC: list[Callable[[float, float, float], Word | None]] = [_lxrxl, _lxrl, _lrxl]
_SWAP = str.maketrans("LR", "RL")


def _candidates(x: float, y: float, phi: float) -> list[Word]:
    """Every word under the symmetries: time-flip (reverse), reflection (mirror), backwards."""
    out: list[Word] = []

    def add(word: Word | None, flip: bool, reflect: bool, backwards: bool) -> None:
        if word is None:
            return
        lengths, kinds = word
        if flip:
            lengths = tuple(-v for v in lengths)  # type: ignore[assignment]
        if reflect:
            kinds = kinds.translate(_SWAP)
        if backwards:
            lengths, kinds = lengths[::-1], kinds[::-1]
        out.append((lengths, kinds))

    for fn, backwards_too in [(f, False) for f in _CSC] + [(f, True) for f in _CCC]:
        for backwards in ((False, True) if backwards_too else (False,)):
            if backwards:
                bx = x * math.cos(phi) + y * math.sin(phi)
                by = x * math.sin(phi) - y * math.cos(phi)
            else:
                bx, by = x, y
            add(fn(bx, by, phi), False, False, backwards)
            add(fn(-bx, by, -phi), True, False, backwards)
            add(fn(bx, -by, -phi), False, True, backwards)
            add(fn(-bx, -by, phi), True, True, backwards)
    return out


def _advance(pose, kind: str, length: float, radius: float):
    """Move along one segment; ``length`` [m] signed (negative: reverse)."""
    x, y, th = pose
    if kind == "S":
        return (x + length * math.cos(th), y + length * math.sin(th), th)
    sign = 1.0 if kind == "L" else -1.0
    turn = sign * length / radius
    return (x + sign * radius * (math.sin(th + turn) - math.sin(th)),
            y - sign * radius * (math.cos(th + turn) - math.cos(th)), th + turn)


def shortest(start, goal, radius: float) -> list[tuple[str, float]] | None:
    """Segments [(kind, signed length [m])] of the shortest verified path, or None."""
    c, s = math.cos(start[2]), math.sin(start[2])
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    x, y = (c * dx + s * dy) / radius, (-s * dx + c * dy) / radius
    phi = goal[2] - start[2]
    best, best_len = None, math.inf
    for lengths, kinds in _candidates(x, y, phi):
        total = sum(abs(v) for v in lengths) * radius
        if total >= best_len:
            continue
        segs = [(k, v * radius) for k, v in zip(kinds, lengths) if abs(v) > 1e-10]
        pose = tuple(start)
        for kind, length in segs:
            pose = _advance(pose, kind, length, radius)
        heading_error = abs(_mod2pi(pose[2] - goal[2]))
        if (math.hypot(pose[0] - goal[0], pose[1] - goal[1]) <= END_TOLERANCE * max(1.0, radius)
                and heading_error <= END_TOLERANCE):
            best, best_len = segs, total
    return best


def sample(start, segments: list[tuple[str, float]], radius: float,
           spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """(poses (n, 3), direction (n,) +1/-1) along a path every ``spacing`` metres at most."""
    poses, direction = [], []
    pose = tuple(start)
    for kind, length in segments:
        n = max(1, math.ceil(abs(length) / spacing))
        for k in range(1, n + 1):
            poses.append(_advance(pose, kind, length * k / n, radius))
            direction.append(1.0 if length > 0 else -1.0)
        pose = _advance(pose, kind, length, radius)
    return np.array(poses).reshape(-1, 3), np.array(direction)
