"""What a run log keeps of localization: the estimate per step, the particle cloud and the
built map at a low rate, so `replay` and `plot --kind localization` can show them.

Per robot that names a ``localization`` or ``mapping``: the estimate (T, 3) and its covariance
(T, 3, 3) at every logged step; particles (at most ``MAX_PARTICLES`` of them, float32) every
``PARTICLE_PERIOD``; the map being built every ``MAP_PERIOD``, and always its last state. All
are plain arrays in the .npz under ``loc.<robot>.*`` (docs/viewer.md lists them).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pymunk_bot.maps.grid import OccupancyGrid

PARTICLE_PERIOD = 0.2  # [s] between logged particle clouds
MAX_PARTICLES = 1000  # particles kept per logged cloud (an even subsample of the filter's)
MAP_PERIOD = 1.0  # [s] between logged map snapshots
MAX_MAP_SNAPSHOTS = 300  # beyond this, earlier snapshots are thinned (every other one dropped)
_EMPTY3 = np.empty((0, 3))


@dataclass
class LocalizationTrack:
    """One robot's localization over a run (arrays aligned with the log's steps)."""

    estimate: np.ndarray  # (T, 3) [m, m, rad]
    covariance: np.ndarray  # (T, 3, 3)
    particle_time: np.ndarray  # (K,) [s]
    particle_start: np.ndarray  # (K + 1,) row offsets of each cloud in ``particles``
    particles: np.ndarray  # (P, 3) all clouds, one after the other
    map_time: np.ndarray  # (S,) [s]
    maps: np.ndarray  # (S, rows, cols) int8 occupancy (-1 unknown, 0..100)
    map_resolution: float = 0.0  # [m]; 0 when the robot builds no map
    map_origin: tuple[float, float] = (0.0, 0.0)  # [m]

    def cloud_at(self, time: float) -> np.ndarray | None:
        """The particles logged last at or before ``time`` [s], or None."""
        k = int(np.searchsorted(self.particle_time, time + 1e-9, side="right")) - 1
        if k < 0:
            return None
        return self.particles[self.particle_start[k]:self.particle_start[k + 1]]

    def map_at(self, time: float) -> OccupancyGrid | None:
        """The map as it was built at ``time`` [s] (its last snapshot before), or None."""
        k = int(np.searchsorted(self.map_time, time + 1e-9, side="right")) - 1
        if k < 0 or self.map_resolution <= 0:
            return None
        return OccupancyGrid(self.maps[k], self.map_resolution, self.map_origin)

    def arrays(self, prefix: str) -> dict[str, np.ndarray]:
        """The track as named arrays for an .npz."""
        return {f"{prefix}.{key}": np.asarray(getattr(self, key)) for key in (
            "estimate", "covariance", "particle_time", "particle_start", "particles",
            "map_time", "maps")} | {
            f"{prefix}.map_frame": np.array([self.map_resolution, *self.map_origin])}

    @classmethod
    def from_arrays(cls, files: dict, prefix: str) -> "LocalizationTrack":
        frame = files[f"{prefix}.map_frame"]
        track = cls(**{key: files[f"{prefix}.{key}"] for key in (
            "estimate", "covariance", "particle_time", "particle_start", "particles",
            "map_time", "maps")}, map_resolution=float(frame[0]),
                    map_origin=(float(frame[1]), float(frame[2])))
        if track.particle_start.size != track.particle_time.size + 1 or (
                track.maps.shape[0] != track.map_time.size):
            raise ValueError(f"{prefix}: particle or map arrays do not fit together")
        return track


class LocalizationRecorder:
    """Samples the robots that localize or map, once per logged step (see RunLogger)."""

    def __init__(self, sim) -> None:
        self._robots = [r for r in sim.robots.values()
                        if getattr(r, "localization_score", None) is not None
                        or getattr(r, "mapper", None) is not None]
        self._rows: dict[str, dict[str, list]] = {
            r.name: {"estimate": [], "covariance": [], "particle_time": [], "clouds": [],
                     "map_time": [], "maps": []} for r in self._robots}
        self._last_map: dict[str, OccupancyGrid] = {}

    def __call__(self, sim) -> None:
        for robot in self._robots:
            rows = self._rows[robot.name]
            localizer = robot.localizer
            rows["estimate"].append(np.array(localizer.pose, dtype=float))
            rows["covariance"].append(np.array(localizer.covariance, dtype=float))
            if not rows["particle_time"] or sim.time >= rows["particle_time"][-1] + PARTICLE_PERIOD - 1e-9:
                particles = localizer.debug().get("particles")
                if particles is not None and len(particles):
                    rows["particle_time"].append(sim.time)
                    rows["clouds"].append(_thin(np.asarray(particles, dtype=float)))
            if robot.mapper is not None:
                grid = robot.mapper.grid
                self._last_map[robot.name] = grid
                if not rows["map_time"] or sim.time >= rows["map_time"][-1] + MAP_PERIOD - 1e-9:
                    rows["map_time"].append(sim.time)
                    rows["maps"].append(grid.data.copy())
                    if len(rows["maps"]) > MAX_MAP_SNAPSHOTS:
                        rows["map_time"][:-1] = rows["map_time"][:-1:2]
                        rows["maps"][:-1] = rows["maps"][:-1:2]

    def tracks(self, end_time: float) -> dict[str, LocalizationTrack]:
        """What was recorded, the last map included as it stands at ``end_time`` [s]."""
        out = {}
        for robot in self._robots:
            rows = self._rows[robot.name]
            clouds = rows["clouds"]
            start = np.concatenate([[0], np.cumsum([len(c) for c in clouds])]).astype(np.int64)
            map_time, maps = list(rows["map_time"]), list(rows["maps"])
            last = self._last_map.get(robot.name)
            if last is not None and (not map_time or map_time[-1] < end_time):
                map_time.append(end_time)
                maps.append(last.data.copy())
            out[robot.name] = LocalizationTrack(
                estimate=np.array(rows["estimate"], dtype=float).reshape(-1, 3),
                covariance=np.array(rows["covariance"], dtype=float).reshape(-1, 3, 3),
                particle_time=np.array(rows["particle_time"], dtype=float),
                particle_start=start,
                particles=(np.concatenate(clouds) if clouds else _EMPTY3).astype(np.float32),
                map_time=np.array(map_time, dtype=float),
                maps=(np.stack(maps) if maps else np.empty((0, 0, 0))).astype(np.int8),
                map_resolution=float(last.resolution) if last is not None else 0.0,
                map_origin=(float(last.origin[0]), float(last.origin[1])) if last is not None
                else (0.0, 0.0))
        return out


def _thin(particles: np.ndarray) -> np.ndarray:
    """At most MAX_PARTICLES, evenly spread over the filter's (its order is already random)."""
    if len(particles) <= MAX_PARTICLES:
        return particles[:, :3]
    pick = np.linspace(0, len(particles) - 1, MAX_PARTICLES).round().astype(np.intp)
    return particles[pick, :3]
