"""Omnidirectional drive (mecanum or three-wheel omni): body velocity (vx, vy, omega) in the
robot frame. The norm of (vx, vy) is limited by ``max_speed`` and its change by ``max_accel``;
omega by ``max_angular_speed`` and ``max_angular_accel``. As in the diff drive, the motors lag
their command by one substep (see drives/diff.py).
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from pymunk_bot.robots.command import Command
from pymunk_bot.geometry.footprint import of_robot
from pymunk_bot.robots.readings import RobotSpec
from pymunk_bot.robots.drives.base import DriveGroup, limit_step
from pymunk_bot.robots.rows import OWN, Rows

OMNI3_ANGLES = (math.pi / 2, math.pi / 2 + 2 * math.pi / 3, math.pi / 2 + 4 * math.pi / 3)


def wheel_matrix(layout: str, distance: float) -> np.ndarray:
    """Rim speeds of the wheels [m/s] = this @ (vx, vy, omega); 4 rows, unused ones zero.

    mecanum (rollers at 45 deg): front-left, front-right, rear-left, rear-right, ``distance``
    = half length + half width of the wheel rectangle. omni3: wheels at 90, 210 and 330 deg
    around the centre, ``distance`` from it, each rolling tangentially."""
    m = np.zeros((4, 3))
    if layout == "mecanum":
        d = distance
        m[:] = [[1, -1, -d], [1, 1, d], [1, 1, -d], [1, -1, d]]
    else:
        for k, a in enumerate(OMNI3_ANGLES):
            m[k] = (-math.sin(a), math.cos(a), distance)
    return m


class OmniDriveGroup(DriveGroup):
    """Every omnidirectional robot of a world."""

    name = "omni"
    holonomic = True
    ROWS = ("target", "current", "travel")

    def __init__(self, configs: Sequence[Any], rows: Rows = OWN) -> None:
        super().__init__(configs)
        self.max_v = np.array([c.max_speed for c in configs], dtype=float)  # [m/s]
        self.max_w = np.array([c.max_angular_speed for c in configs], dtype=float)  # [rad/s]
        self.max_accel = np.array([c.max_accel for c in configs], dtype=float)  # [m/s^2]
        self.max_alpha = np.array([c.max_angular_accel for c in configs], dtype=float)
        self.wheels = np.array([wheel_matrix(c.wheels, c.wheel_distance) for c in configs])
        self.target = rows.hold("target", np.zeros((self.n, 3)))  # (vx, vy, omega), limited
        self.current = rows.hold("current", np.zeros((self.n, 3)))  # acceleration-limited twist
        self.travel = rows.hold("travel", np.zeros((self.n, 4)))  # rim travel since taken [m]

    def set_command(self, i: int, command: Any) -> None:
        if not isinstance(command, Command):
            raise ValueError("an omni drive takes a Command (v, omega, vy), not wheel speeds")
        vx, vy = command.v, command.vy
        norm = math.hypot(vx, vy)
        if norm > self.max_v[i]:
            vx, vy = vx * self.max_v[i] / norm, vy * self.max_v[i] / norm
        omega = min(self.max_w[i], max(-self.max_w[i], command.omega))
        self.target[i] = (vx, vy, omega)

    def command_of(self, i: int) -> Command:
        vx, vy, omega = self.target[i]
        return Command(float(vx), float(omega), float(vy))

    def advance(self, h: float) -> tuple[Any, Any, Any]:
        self.travel += np.einsum("nkj,nj->nk", self.wheels, self.current) * h
        delta = self.target[:, :2] - self.current[:, :2]
        norm = np.hypot(delta[:, 0], delta[:, 1])
        step = self.max_accel * h
        scale = np.where(norm > step, step / np.maximum(norm, 1e-300), 1.0)
        self.current[:, :2] += delta * scale[:, None]
        limit_step(self.current[:, 2], self.target[:, 2], self.max_alpha * h)
        c = self.current
        return c[:, 0].copy(), c[:, 1].copy(), c[:, 2].copy()


    def joint_limits(self, i: int, mass: float, moment: float) -> tuple[float, float]:
        reach = of_robot(self.configs[i]).bounding_radius
        force = mass * (2.0 * self.max_accel[i] + self.max_v[i] * self.max_w[i])
        return force, mass * reach * reach * 2.0 * self.max_alpha[i] + force * reach

    def max_speed(self, i: int) -> float:
        return float(self.max_v[i])

    def fastest(self, spin: np.ndarray, seconds: float) -> float:
        vx, vy, omega = self.current.T
        gain = (self.max_accel + self.max_alpha * spin) * seconds
        return float((np.hypot(vx, vy) + np.abs(omega) * spin + gain).max(initial=0.0))

    def spec(self, i: int) -> RobotSpec:
        c = self.configs[i]
        return RobotSpec(c.name, of_robot(c).bounding_radius, 0.0, float(self.max_v[i]),
                         float(self.max_accel[i]), drive=self.name, max_speed=float(self.max_v[i]),
                         max_omega=float(self.max_w[i]), holonomic=True,
                         footprint=of_robot(c))

    def handle(self, i: int) -> "OmniDrive":
        return OmniDrive(self, i)


class OmniDrive:
    """One robot's view of its omnidirectional drive (``robot.drive``)."""

    def __init__(self, group: OmniDriveGroup, index: int) -> None:
        self._group = group
        self._i = index
        self.max_speed = float(group.max_v[index])  # [m/s]
        self.max_angular_speed = float(group.max_w[index])  # [rad/s]

    @property
    def twist(self) -> tuple[float, float, float]:
        """(vx [m/s], vy [m/s], omega [rad/s]) the motors drive now, robot frame."""
        vx, vy, w = self._group.current[self._i]
        return float(vx), float(vy), float(w)

    @property
    def command(self) -> Command:
        return self._group.command_of(self._i)

    @property
    def target(self) -> tuple[float, float]:
        """Commanded (vx, vy) [m/s] (run logs keep this where a diff drive logs wheel speeds)."""
        vx, vy, _ = self._group.target[self._i]
        return float(vx), float(vy)

    @property
    def wheel_speeds(self) -> tuple[float, float]:
        """(vx, vy) the motors drive now [m/s], robot frame."""
        vx, vy, _ = self._group.current[self._i]
        return float(vx), float(vy)
