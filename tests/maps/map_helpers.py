"""Map fixtures written in tmp dirs: images with Pillow, YAML by hand."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image


def write_map(tmp: Path, pixels: np.ndarray, name: str = "map", image_format: str = "pgm",
              extra: str = "", mode_img: str | None = None, **keys) -> Path:
    """Write ``pixels`` (image rows, top first) and a map YAML; returns the YAML path."""
    image = tmp / f"{name}.{image_format}"
    Image.fromarray(np.asarray(pixels), mode=mode_img).save(image)
    meta = {"image": image.name, "resolution": 0.05, "origin": "[0.0, 0.0, 0.0]", **keys}
    text = "".join(f"{k}: {v}\n" for k, v in meta.items()) + extra
    yaml_path = tmp / f"{name}.yaml"
    yaml_path.write_text(text)
    return yaml_path


def turtlebot_map(size: int = 384) -> np.ndarray:
    """A TurtleBot3-world-like map image (uint8, top row first): unknown grey (205) outside a
    closed wall ring, free (254) inside, with a 3-cell wall and nine round pillars."""
    pixels = np.full((size, size), 205, dtype=np.uint8)
    a, b = size // 4, 3 * size // 4
    pixels[a:b, a:b] = 0
    pixels[a + 3:b - 3, a + 3:b - 3] = 254
    yy, xx = np.mgrid[:size, :size]
    for i in range(1, 4):
        for j in range(1, 4):
            cy, cx = a + i * (b - a) // 4, a + j * (b - a) // 4
            pixels[(yy - cy) ** 2 + (xx - cx) ** 2 < 16] = 0
    return pixels


def cast(space, origin, angle: float, max_range: float = 30.0) -> float:
    """Range along one ray with pymunk's own query (the reference)."""
    import math

    import pymunk

    end = (origin[0] + max_range * math.cos(angle), origin[1] + max_range * math.sin(angle))
    hit = space.segment_query_first(tuple(origin), end, 0.0, pymunk.ShapeFilter())
    return max_range if hit is None else hit.alpha * max_range
