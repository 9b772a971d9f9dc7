"""ROS map_server maps: a YAML file naming a PGM/PNG image, read into an ``OccupancyGrid``.

Pixels are interpreted exactly as ROS 2's Nav2 ``map_server`` (``map_io.cpp``) does:

- ``shade`` is the mean of the red, green and blue channels on a 0..1 scale (a grey image: the
  grey level); in ``trinary`` mode an image with an alpha channel averages alpha in too.
- ``occ = 1 - shade``, or ``occ = shade`` with ``negate: 1``.
- ``trinary``: ``occ > occupied_thresh`` -> 100 (occupied), ``occ < free_thresh`` -> 0 (free),
  anything else -> -1 (unknown).
- ``scale``: a pixel that is not fully opaque -> -1; otherwise as trinary, except that values
  between the thresholds become ``rint(100 * (occ - free) / (occupied - free))``.
- ``raw``: the value is ``round(255 * shade)`` itself when it lies in 0..100, else -1 (``negate``
  does not apply, as in Nav2).

Images are stored top row first; the grid is stored bottom row first (row 0 at ``origin``).
"""
from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import yaml

from pymunk_bot.config.messages import clip
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.outcomes.results import write_atomic
from pymunk_bot.maps.grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

MODES = ("trinary", "scale", "raw")
KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode")
DEFAULT_OCCUPIED_THRESH = 0.65  # [probability], map_server's documented default
DEFAULT_FREE_THRESH = 0.196  # [probability]: a written map's unknown grey (205) stays unknown
MAX_SIDE = 20_000  # [pixels] per side of a map image
MAX_CELLS = 64_000_000  # [pixels] in a map image (8000 x 8000)
MAX_RESOLUTION = 100.0  # [m] per cell
# Image formats a map may be in (Pillow reads them all; Nav2's map_server reads these too).
IMAGE_SUFFIXES = (".pgm", ".png", ".ppm", ".pnm", ".pbm", ".bmp", ".jpg", ".jpeg", ".tif", ".tiff",
                  ".gif")
# What a written map's pixels are, as Nav2's map_saver writes them (trinary).
PIXEL_OCCUPIED, PIXEL_FREE, PIXEL_UNKNOWN = 0, 254, 205


class _Problem:
    """Builds the one-line errors: the scenario (or map) file, the key path, then the problem."""

    def __init__(self, yaml_path: Path, source: str | None, key_path: str) -> None:
        self.yaml_path = yaml_path
        self.source = source
        self.key_path = key_path

    def __call__(self, key: str, problem: str) -> ScenarioError:
        if self.source is None:  # the map file itself is what the user named
            return ScenarioError(str(self.yaml_path), key, problem)
        where = f"{self.yaml_path}: {key}: " if key else f"{self.yaml_path}: "
        return ScenarioError(self.source, self.key_path, where + problem)


def read_ros_map(path: str | Path, source: str | None = None,
                 key_path: str = "world.map") -> OccupancyGrid:
    """Read a ROS map_server YAML and its image into an occupancy grid.

    ``source`` and ``key_path`` name where the map was referenced (e.g. the scenario file and
    ``world.map``) for error messages; with no ``source`` the errors name the map file itself.
    Raises ``ScenarioError`` for every problem. The map's origin yaw must be 0.
    """
    yaml_path = Path(path)
    fail = _Problem(yaml_path, source, key_path)
    meta = _read_yaml(yaml_path, fail)
    image_path = Path(meta["image"])
    if not image_path.is_absolute():
        image_path = yaml_path.parent / image_path
    shade, alpha = _read_image(image_path, fail)
    values = classify(shade, alpha, meta["mode"], meta["negate"], meta["occupied_thresh"],
                      meta["free_thresh"])
    origin = (float(meta["origin"][0]), float(meta["origin"][1]))
    return OccupancyGrid(np.ascontiguousarray(values[::-1]), meta["resolution"], origin)


def classify(shade: np.ndarray, alpha: np.ndarray | None, mode: str, negate: bool,
             occupied_thresh: float, free_thresh: float) -> np.ndarray:
    """Occupancy values (int8, image row order) of pixels, by map_server's rules.

    ``shade``: mean of the red, green and blue channels, 0..1; ``alpha``: 0..1 opacity, or None
    for an image without an alpha channel.
    """
    if mode == "trinary" and alpha is not None:  # Nav2 averages alpha in with R, G and B here
        shade = (3.0 * shade + alpha) / 4.0
    if mode == "raw":
        raw = np.rint(shade * 255.0)
        return np.where((raw >= 0) & (raw <= 100), raw, UNKNOWN).astype(np.int8)
    occ = shade if negate else 1.0 - shade
    values = np.full(shade.shape, UNKNOWN, dtype=np.int8)
    if mode == "scale":
        between = (occ >= free_thresh) & (occ <= occupied_thresh)
        scaled = np.rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        values[between] = scaled[between].astype(np.int8)
    values[occ > occupied_thresh] = OCCUPIED
    values[occ < free_thresh] = FREE
    if mode == "scale" and alpha is not None:
        values[alpha < 1.0] = UNKNOWN
    return values


def _read_yaml(yaml_path: Path, fail: _Problem) -> dict:
    if not yaml_path.is_file():
        raise fail("", "map file not found" if not yaml_path.exists() else "not a file")
    try:
        doc = yaml.safe_load(yaml_path.read_text(encoding="utf-8"))
    except yaml.MarkedYAMLError as exc:
        line = exc.problem_mark.line + 1 if exc.problem_mark else None
        raise fail("", f"YAML syntax error: {exc.problem} (line {line})") from None
    except (yaml.YAMLError, OSError, UnicodeDecodeError) as exc:
        raise fail("", f"cannot read the map file: {exc}") from None
    if not isinstance(doc, dict):
        raise fail("", "a ROS map YAML must be a mapping with image, resolution and origin")
    for key in doc:
        if key not in KEYS:
            from difflib import get_close_matches

            near = get_close_matches(str(key), KEYS, n=1)
            hint = f" (did you mean '{near[0]}'?)" if near else f" (known: {', '.join(KEYS)})"
            raise fail(str(key), "unknown key" + hint)
    for key in ("image", "resolution", "origin"):
        if key not in doc:
            raise fail(key, "required key is missing")
    if not isinstance(doc["image"], str) or not doc["image"].strip():
        raise fail("image", f"must be the image file name (got {doc['image']!r})")
    meta = {"image": doc["image"], "mode": doc.get("mode", "trinary")}
    meta["resolution"] = _number(doc["resolution"], "resolution", fail)
    if not 0 < meta["resolution"] <= MAX_RESOLUTION:
        raise fail("resolution", f"must be > 0 and <= {MAX_RESOLUTION:g} m per cell "
                                 f"(got {meta['resolution']:g})")
    origin = doc["origin"]
    if not isinstance(origin, list) or len(origin) != 3:
        raise fail("origin", f"must be three numbers [x, y, yaw] (got {clip(repr(origin))})")
    meta["origin"] = [_number(v, f"origin[{i}]", fail) for i, v in enumerate(origin)]
    if meta["origin"][2] != 0.0:
        raise fail("origin[2]", f"a rotated map is not supported: yaw must be 0 (got "
                                f"{meta['origin'][2]:g})")
    negate = doc.get("negate", 0)
    if negate not in (0, 1) or isinstance(negate, float):
        raise fail("negate", f"must be 0 or 1 (got {negate!r})")
    meta["negate"] = bool(negate)
    for key, default in (("occupied_thresh", DEFAULT_OCCUPIED_THRESH),
                         ("free_thresh", DEFAULT_FREE_THRESH)):
        meta[key] = _number(doc.get(key, default), key, fail)
        if not 0.0 <= meta[key] <= 1.0:
            raise fail(key, f"must be in [0, 1] (got {meta[key]:g})")
    if meta["free_thresh"] >= meta["occupied_thresh"]:
        raise fail("free_thresh", f"must be below occupied_thresh ({meta['occupied_thresh']:g}) "
                                  f"(got {meta['free_thresh']:g})")
    if meta["mode"] not in MODES:
        raise fail("mode", f"must be one of {', '.join(MODES)} (got {meta['mode']!r})")
    return meta


def _number(value, key: str, fail: _Problem) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(key, f"must be a number (got {value!r})")
    if not math.isfinite(value):
        raise fail(key, f"must be finite (got {value})")
    return float(value)


def _read_image(image_path: Path, fail: _Problem) -> tuple[np.ndarray, np.ndarray | None]:
    """(shade, alpha) of every pixel on a 0..1 scale, image row order (top row first)."""
    try:
        from PIL import Image, UnidentifiedImageError
    except ImportError:  # pragma: no cover - Pillow comes with matplotlib and imageio
        raise fail("image", "reading map images needs Pillow: pip install Pillow") \
            from None
    if not image_path.exists():
        raise fail("image", f"image file not found: {clip(str(image_path))}")
    if image_path.is_dir():
        raise fail("image", f"{clip(str(image_path))} is a directory, not an image file")
    if not image_path.is_file():  # a device, FIFO or socket: reading it may never end
        raise fail("image", f"{clip(str(image_path))} is not a regular file")
    if image_path.suffix.lower() not in IMAGE_SUFFIXES:
        raise fail("image", f"must be an image file ({', '.join(IMAGE_SUFFIXES)}) "
                            f"(got {clip(str(image_path))})")
    try:
        with Image.open(image_path) as img:
            width, height = img.size
            if width < 1 or height < 1 or width > MAX_SIDE or height > MAX_SIDE \
                    or width * height > MAX_CELLS:
                raise fail("image", f"{image_path.name} is {width} x {height} pixels; at most "
                                    f"{MAX_SIDE} per side and {MAX_CELLS:,} in all")
            return _pixels(img)
    except ScenarioError:
        raise
    except Image.DecompressionBombError:
        raise fail("image", f"{image_path.name} has more than {MAX_CELLS:,} pixels") from None
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:
        raise fail("image", f"cannot read {image_path.name} as an image: {exc}") from None


def _pixels(img) -> tuple[np.ndarray, np.ndarray | None]:
    mode = img.mode
    if mode in ("I", "I;16", "I;16B", "I;16L", "I;16N"):  # 16-bit grey (Pillow scales to 65535)
        return np.asarray(img, dtype=np.float64) / 65535.0, None
    if mode in ("1", "L"):
        return np.asarray(img.convert("L"), dtype=np.float64) / 255.0, None
    has_alpha = mode in ("LA", "La", "PA", "RGBA", "RGBa") or "transparency" in img.info
    rgba = np.asarray(img.convert("RGBA" if has_alpha else "RGB"), dtype=np.float64)
    if not has_alpha:
        return rgba.mean(axis=2) / 255.0, None
    return rgba[..., :3].mean(axis=2) / 255.0, rgba[..., 3] / 255.0


def write_ros_map(grid: OccupancyGrid, out_yaml: str | Path,
                  occupied_thresh: float = DEFAULT_OCCUPIED_THRESH,
                  free_thresh: float = DEFAULT_FREE_THRESH) -> Path:
    """Write ``grid`` as a ROS map: ``out_yaml`` plus a binary PGM beside it (same stem).

    Pixels follow Nav2's map_saver in trinary mode: 0 (black) occupied, 254 free, 205 unknown;
    a cell counts as occupied at ``>= rint(100 * occupied_thresh)`` percent and as free at
    ``<= rint(100 * free_thresh)``. Both files are written atomically, the image first. Returns
    the image path.
    """
    from PIL import Image

    out_yaml = Path(out_yaml)
    image_path = out_yaml.with_suffix(".pgm")
    data = np.asarray(grid.data)
    pixels = np.full(data.shape, PIXEL_UNKNOWN, dtype=np.uint8)
    pixels[(data >= 0) & (data <= round(100 * free_thresh))] = PIXEL_FREE
    pixels[data >= round(100 * occupied_thresh)] = PIXEL_OCCUPIED
    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(pixels[::-1]), mode="L").save(buffer, format="PPM")
    write_atomic(image_path, buffer.getvalue())
    meta = {
        "image": image_path.name,
        "mode": "trinary",
        "resolution": float(grid.resolution),
        "origin": [float(grid.origin[0]), float(grid.origin[1]), 0.0],
        "negate": 0,
        "occupied_thresh": float(occupied_thresh),
        "free_thresh": float(free_thresh),
    }
    write_atomic(out_yaml, yaml.safe_dump(meta, sort_keys=False, default_flow_style=None).encode("utf-8"))
    return image_path
