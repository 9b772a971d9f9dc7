"""Trajectories in the TUM RGB-D format, which evo (``evo_ape``, ``evo_rpe``) and most SLAM
tools read: one pose per line, ``t x y z qx qy qz qw`` (time [s], position [m], unit
quaternion), ``#`` comments. A planar pose (x, y, theta) is z = 0 and the rotation of theta
about z: q = (0, 0, sin(theta / 2), cos(theta / 2)).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from pymunk_bot.outcomes.results import write_atomic

MAX_TUM_BYTES = 1 << 30  # a file larger than this is refused on reading (1 GiB)


def tum_text(times: np.ndarray, poses: np.ndarray, comment: str = "") -> str:
    """The TUM lines of ``poses`` (n, 3) [m, m, rad] at ``times`` (n,) [s]."""
    times, poses = np.asarray(times, dtype=float), np.asarray(poses, dtype=float)
    if poses.ndim != 2 or poses.shape[1] != 3 or times.shape != (poses.shape[0],):
        raise ValueError(f"need (n,) times and (n, 3) poses (got {times.shape} and {poses.shape})")
    half = 0.5 * poses[:, 2]
    zeros = np.zeros_like(half)
    rows = np.column_stack([times, poses[:, 0], poses[:, 1], zeros, zeros, zeros,
                            np.sin(half), np.cos(half)])
    head = "".join(f"# {line}\n" for line in comment.splitlines())
    head += "# t x y z qx qy qz qw\n"
    return head + "".join(f"{r[0]:.6f} " + " ".join(f"{v:.9g}" for v in r[1:]) + "\n"
                          for r in rows.tolist())


def write_tum(path: str | Path, times: np.ndarray, poses: np.ndarray, comment: str = "") -> None:
    """Write ``poses`` (n, 3) at ``times`` (n,) [s] as a TUM file, atomically."""
    write_atomic(path, tum_text(times, poses, comment).encode("ascii"))


def read_tum(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """(times (n,) [s], planar poses (n, 3)) of a TUM file; theta is the yaw of the quaternion
    (roll, pitch and z are dropped). ValueError naming the file and line for bad input."""
    path = Path(path)
    if path.stat().st_size > MAX_TUM_BYTES:
        raise ValueError(f"{path}: larger than {MAX_TUM_BYTES} bytes")
    times, poses = [], []
    with path.open(encoding="ascii", errors="replace") as f:
        for number, line in enumerate(f, 1):
            text = line.strip()
            if not text or text.startswith("#"):
                continue
            try:
                t, x, y, _z, qx, qy, qz, qw = (float(v) for v in text.replace(",", " ").split())
            except ValueError:
                raise ValueError(f"{path}: line {number}: expected 8 numbers "
                                 f"'t x y z qx qy qz qw' (got {text[:60]!r})") from None
            times.append(t)
            yaw = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
            poses.append((x, y, yaw))
    return np.asarray(times, dtype=float), np.asarray(poses, dtype=float).reshape(-1, 3)


TRAJECTORY_RATE = 50.0  # [Hz] poses recorded per second (at most one per tick)
KINDS = ("truth", "odometry", "estimate")  # <robot>.<kind>.tum


class TrajectoryRecorder:
    """Every robot's true pose, odometry and localizer estimate, sampled at TRAJECTORY_RATE
    (a simulation observer: ``sim.observers.append(recorder)``, or :meth:`attach`)."""

    def __init__(self, rate: float = TRAJECTORY_RATE) -> None:
        if not (np.isfinite(rate) and rate > 0):
            raise ValueError(f"rate must be a finite number > 0 Hz (got {rate!r})")
        self.period = 1.0 / rate  # [s]
        self.times: list[float] = []
        self._due = 0.0  # [s] when the next pose is due
        self.rows: dict[str, dict[str, list]] = {}

    def attach(self, sim) -> "TrajectoryRecorder":
        """Record ``sim`` from its present state on, at every step it takes."""
        sim.attach(self)  # on_reset now, then every step
        return self

    def on_reset(self, sim) -> None:
        """Forget what was recorded; start over from ``sim``'s present state."""
        self.times = []
        self.rows = {name: {kind: [] for kind in KINDS} for name in sim.robots}
        self._sample(sim)

    def __call__(self, sim) -> None:
        if sim.time >= self._due - 1e-9:
            self._sample(sim)

    def _sample(self, sim) -> None:
        """One row per robot and kind, at the time now; the next is due one period on."""
        now = float(sim.time)
        self._due = (np.floor(now / self.period + 1e-9) + 1.0) * self.period  # [s] next on the grid
        self.times.append(now)
        for name, robot in sim.robots.items():
            rows = self.rows[name]
            rows["truth"].append(np.array(robot.pose, dtype=float))
            rows["odometry"].append(np.array(robot.odometry.pose, dtype=float))
            rows["estimate"].append(np.array(robot.localizer.pose, dtype=float))

    def poses(self, robot: str, kind: str) -> np.ndarray:
        """(n, 3) poses of ``robot``'s ``kind`` (one of KINDS), one per entry of ``times``."""
        return np.asarray(self.rows[robot][kind], dtype=float).reshape(-1, 3)

    def write(self, directory: str | Path, scenario: str = "") -> list[Path]:
        """DIR/<robot>.<kind>.tum for every robot and kind, each written atomically."""
        written = []
        times = np.asarray(self.times)
        for name in self.rows:
            for kind in KINDS:
                path = Path(directory) / f"{name}.{kind}.tum"
                write_tum(path, times, self.poses(name, kind),
                          comment=f"pymunk-bot {scenario}: {name}'s {kind} pose".strip())
                written.append(path)
        return written
