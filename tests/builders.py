"""Scenario mappings built in code for tests (import as ``from builders import robot``)."""
from __future__ import annotations


def scenario(robots: list[dict], obstacles: list[dict] | None = None, size=(20.0, 20.0),
             **extra) -> dict:
    """A scenario mapping with sensible defaults; ``extra`` adds top-level keys or world keys."""
    world = {"size": list(size)}
    for key in ("dt", "substeps", "duration", "wall_friction"):
        if key in extra:
            world[key] = extra.pop(key)
    return {"name": "test", "world": world, "obstacles": obstacles or [], "robots": robots, **extra}


def robot(pose, **keys) -> dict:
    return {"name": keys.pop("name", "r"), "pose": list(pose), **keys}


def wheels(left: float, right: float) -> dict:
    return {"type": "wheels", "left": left, "right": right}
