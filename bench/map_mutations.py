"""Seeded mutations that give a scenario a map file: a ROS map (YAML + image) or an SVG plan.

Each mutation returns the scenario's YAML text and the files to write beside it ({name: bytes},
None for a folder).
Most maps fit the scenario (the shipped robots' poses stay meaningful, so runs happen); the rest
are broken on purpose: bad keys and values in the map YAML, images that are empty, truncated,
huge by their header, folders or devices; SVGs with degenerate viewBoxes, shapes far beyond the
plan, extreme transforms, thousands of tiny paths, broken XML.
"""
from __future__ import annotations

import io
from typing import Any, Callable

import numpy as np
import yaml

MAP_SCALE = 0.01  # [m per SVG user unit], the SVG default


def _pick(rng: np.random.Generator, items: list) -> Any:
    return items[int(rng.integers(len(items)))]


def _world(data: dict) -> tuple[float, float]:
    size = data.get("world", {}).get("size") or [6.0, 4.0]
    try:
        return float(size[0]), float(size[1])
    except (TypeError, ValueError, IndexError):
        return 6.0, 4.0


def _with_map(data: dict, name: str, **extra: Any) -> str:
    world = dict(data.get("world") or {})
    world.pop("size", None)
    world["map"] = name
    world.update(extra)
    data["world"] = world
    return yaml.safe_dump(data)


def _pixels(rng: np.random.Generator, rows: int, cols: int) -> np.ndarray:
    """Mostly a free room (254) with a few occupied blocks (0); else all occupied, all unknown
    or noise. (The map's edge is a wall already.)"""
    image = np.full((rows, cols), 254, dtype=np.uint8)
    kind = int(rng.integers(8))
    if kind == 0:
        image[:] = 0  # all occupied
    elif kind == 1:
        image[:] = 205  # all unknown
    elif kind == 2:
        image = rng.integers(0, 256, (rows, cols)).astype(np.uint8)  # noise
    else:
        for _ in range(int(rng.integers(0, 8))):
            r, c = int(rng.integers(rows)), int(rng.integers(cols))
            image[r:r + int(rng.integers(1, 6)), c:c + int(rng.integers(1, 6))] = 0
    return image


def _pgm(image: np.ndarray) -> bytes:
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(image, mode="L").save(buffer, format="PPM")
    return buffer.getvalue()


def ros_map(data: dict, rng: np.random.Generator, stem: str) -> tuple[str, dict[str, bytes | None]]:
    """A ROS map covering the scenario's arena, with one of its keys or its image broken (or
    none)."""
    width, height = _world(data)
    resolution = float(_pick(rng, [0.05, 0.1, 0.02]))
    cols, rows = max(1, round(width / resolution)), max(1, round(height / resolution))
    image_name = f"{stem}.pgm"
    meta: dict[str, Any] = {"image": image_name, "resolution": resolution,
                            "origin": [0.0, 0.0, 0.0], "negate": 0,
                            "occupied_thresh": 0.65, "free_thresh": 0.196}
    files: dict[str, bytes | None] = {image_name: _pgm(_pixels(rng, min(rows, 4000), min(cols, 4000)))}
    kind = int(rng.integers(12))
    if kind == 1:
        meta["origin"] = _pick(rng, [[0.0, 0.0], [0, 0, 0, 0], ["a", 0, 0], [0, 0, 0.5], None])
    elif kind == 2:
        meta["resolution"] = _pick(rng, [0, -1, 1e-300, 1e300, float("nan"), "x", 1e-6])
    elif kind == 3:
        meta["image"] = _pick(rng, ["/dev/zero", "/etc/passwd", ".", "missing.pgm", "", 5,
                                    "../../../../../../etc/hostname"])
    elif kind == 4:
        whole = files[image_name] or b""
        files[image_name] = whole[: int(rng.integers(len(whole)))]
    elif kind == 5:  # a header claiming a huge image over a few bytes
        files[image_name] = b"P5\n100000 100000\n255\n" + bytes(100)
    elif kind == 6:
        meta[_pick(rng, ["negate", "mode", "occupied_thresh", "free_thresh"])] = _pick(
            rng, [2, -1, "scale", "raw", "nope", 0.9, 1.5, None])
    elif kind == 7:
        meta["imagee"] = meta.pop("image")
    elif kind == 8:
        files[image_name] = None  # the image is a folder
    elif kind == 9:
        meta["resolution"] = float(_pick(rng, [0.001, 5.0, 100.0]))  # extent far from the arena
    files[f"{stem}.map.yaml"] = yaml.safe_dump(meta).encode()
    return _with_map(data, f"{stem}.map.yaml"), files


def svg_map(data: dict, rng: np.random.Generator, stem: str) -> tuple[str, dict[str, bytes | None]]:
    """An SVG plan covering the scenario's arena (a few boxes and walls), or a broken one."""
    width, height = _world(data)
    w, h = width / MAP_SCALE, height / MAP_SCALE  # [user units]
    view = f"0 0 {w:g} {h:g}"
    shapes = [f'<rect x="{rng.uniform(0, w):.1f}" y="{rng.uniform(0, h):.1f}" width="20" '
              f'height="20"/>' for _ in range(int(rng.integers(0, 6)))]
    shapes.append(f'<line x1="0" y1="{h / 2:g}" x2="{w / 3:g}" y2="{h / 2:g}" stroke="black" '
                  'stroke-width="4"/>')
    extra: dict[str, Any] = {}
    kind = int(rng.integers(12))
    if kind == 1:
        view = _pick(rng, ["0 0 0 0", "0 0 -5 10", "0 0 nan 5", "0 0 inf 1", "1 2 3", "a b c d",
                           "0 0 1e-300 1e-300", "0 0 1e300 1e300"])
    elif kind == 2:
        radius = _pick(rng, ["1e12", "1e7", "1e300", "-5", "nan"])
        shapes.append(f'<circle cx="{w / 2:g}" cy="{h / 2:g}" r="{radius}" fill="none" '
                      'stroke="black" stroke-width="2"/>')
    elif kind == 3:
        shapes += [f'<path d="M{(i * 7) % w:.0f} {(i * 13) % h:.0f} l1 0 l0 1 z"/>'
                   for i in range(int(_pick(rng, [500, 5000, 25000])))]
    elif kind == 4:
        transform = _pick(rng, ["scale(1e-300)", "scale(1e300)", "scale(0)", "rotate(nan)",
                                "matrix(0 0 0 0 0 0)", "translate(1e300 0)"])
        shapes = [f'<g transform="{transform}">{"".join(shapes)}</g>']
    elif kind == 5:
        shapes.append(f'<path d="M 10 10 A {_pick(rng, ["1e12", "0", "1e-12"])} 5 0 1 1 '
                      f'{w - 10:g} {h - 10:g}" stroke="black" fill="none"/>')
    elif kind == 6:
        shapes.append(f'<rect x="10" y="10" width="{w / 4:g}" height="{h / 4:g}" '
                      f'stroke="black" stroke-width="{_pick(rng, ["1e9", "0", "-3", "nan"])}"/>')
    elif kind == 7:
        extra["map_scale"] = _pick(rng, [1e-9, 1e6, 0.0, -1.0, 1e-300])
    text = f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{view}">{"".join(shapes)}</svg>'
    if kind == 8:
        text = text[: int(rng.integers(len(text)))]  # broken XML
    elif kind == 9:
        text = ""
    name = f"{stem}.svg"
    return _with_map(data, name, **extra), {name: text.encode()}


MAP_MUTATIONS: list[Callable[[dict, np.random.Generator, str], tuple[str, dict[str, bytes | None]]]] = [
    ros_map, svg_map,
]
