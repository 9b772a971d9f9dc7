"""Car-like (Ackermann) steering: the bicycle model through the middle of the rear axle.

The pose point is the rear-axle middle, which moves only along the heading: its twist is
(v, 0, v tan(delta) / wheelbase). Speed is limited by ``max_speed`` and ``max_accel``, the
steering angle delta by ``max_steer`` and slewed at ``max_steer_rate``. A body velocity command
(v, omega) asks for the circle of radius v / omega, i.e. delta = atan(wheelbase * omega / v);
a delta beyond ``max_steer`` is clipped, so the tightest circle is wheelbase / tan(max_steer).
As in the diff drive, the motors lag their command by one substep (see drives/diff.py).
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


class AckermannDriveGroup(DriveGroup):
    """Every car-like robot of a world."""

    name = "ackermann"
    ROWS = ("target_speed", "target_steer", "speed", "steer", "driven_speed", "driven_steer",
            "travel")

    def __init__(self, configs: Sequence[Any], rows: Rows = OWN) -> None:
        super().__init__(configs)
        self.wheelbase = np.array([c.wheelbase for c in configs], dtype=float)  # [m]
        self.track = np.array([c.track_width for c in configs], dtype=float)  # [m]
        self.max_steer = np.array([c.max_steer for c in configs], dtype=float)  # [rad]
        self.steer_rate = np.array([c.max_steer_rate for c in configs], dtype=float)  # [rad/s]
        self.max_v = np.array([c.max_speed for c in configs], dtype=float)  # [m/s]
        self.max_accel = np.array([c.max_accel for c in configs], dtype=float)  # [m/s^2]
        self._min_radius = np.array([c.min_turn_radius() for c in configs])  # [m]
        hold, n = rows.hold, self.n
        self.target_speed = hold("target_speed", np.zeros(n))  # [m/s] after the limit
        self.target_steer = hold("target_steer", np.zeros(n))  # [rad] after the limit
        self.speed = hold("speed", np.zeros(n))  # acceleration-limited rear-axle speed [m/s]
        self.steer = hold("steer", np.zeros(n))  # slew-limited steering angle [rad]
        # what the rear wheels did in the last substep [m/s, rad]
        self.driven_speed = hold("driven_speed", np.zeros(n))
        self.driven_steer = hold("driven_steer", np.zeros(n))
        # Encoder input per robot: rear-left, rear-right travel [m] and the integral of
        # tan(delta) over the distance driven [m] (what a steering sensor sees along the way).
        self.travel = hold("travel", np.zeros((n, 3)))

    # ------------------------------------------------------------------ commands
    def set_steering(self, i: int, speed: float, steer: float) -> None:
        """Robot ``i`` drives at ``speed`` [m/s] (negative: reverse) with steering angle
        ``steer`` [rad] (positive: left), each clipped to its limit."""
        speed, steer = float(speed), float(steer)
        if not (math.isfinite(speed) and math.isfinite(steer)):
            raise ValueError(f"speed and steering angle must be finite (got {speed}, {steer})")
        self.target_speed[i] = min(self.max_v[i], max(-self.max_v[i], speed))
        self.target_steer[i] = min(self.max_steer[i], max(-self.max_steer[i], steer))

    def set_command(self, i: int, command: Any) -> None:
        if not isinstance(command, Command):
            raise ValueError("an ackermann drive takes a Command (v, omega), not wheel speeds")
        if command.vy != 0.0:
            raise ValueError(f"an ackermann drive cannot move sideways (vy = {command.vy:g})")
        v, omega = command.v, command.omega
        if abs(v) > 1e-9:
            steer = math.atan(self.wheelbase[i] * omega / v)
        elif omega != 0.0:  # a car cannot turn on the spot: turn the wheels and wait
            steer = math.copysign(float(self.max_steer[i]), omega)
        else:
            steer = float(self.target_steer[i])
        self.set_steering(i, v, steer)

    def command_of(self, i: int) -> Command:
        v = float(self.target_speed[i])
        return Command(v, v * math.tan(self.target_steer[i]) / float(self.wheelbase[i]))

    # ------------------------------------------------------------------ physics
    def advance(self, h: float) -> tuple[Any, Any, Any]:
        self.driven_speed[:] = self.speed
        self.driven_steer[:] = self.steer
        ds = self.speed * h
        tan_steer = np.tan(self.steer)
        half_turn = 0.5 * self.track * tan_steer / self.wheelbase  # rear wheel offset ratio
        self.travel[:, 0] += ds * (1.0 - half_turn)
        self.travel[:, 1] += ds * (1.0 + half_turn)
        self.travel[:, 2] += ds * tan_steer
        limit_step(self.speed, self.target_speed, self.max_accel * h)
        limit_step(self.steer, self.target_steer, self.steer_rate * h)
        omega = self.speed * np.tan(self.steer) / self.wheelbase
        return self.speed.copy(), np.zeros(self.n), omega


    # ------------------------------------------------------------------ set-up
    def min_turn_radius(self, i: int) -> float:
        return float(self.wheelbase[i] / math.tan(self.max_steer[i]))

    def joint_limits(self, i: int, mass: float, moment: float) -> tuple[float, float]:
        # Tangential acceleration plus the centripetal v^2 / R_min, with margin.
        force = mass * (2.0 * self.max_accel[i] + self.max_v[i] ** 2 / self.min_turn_radius(i))
        reach = max(of_robot(self.configs[i]).bounding_radius, 0.5 * float(self.wheelbase[i]))
        return force, force * reach

    def max_speed(self, i: int) -> float:
        return float(self.max_v[i])

    def fastest(self, spin: np.ndarray, seconds: float) -> float:
        # At any steering angle: omega <= v / R_min, so a point is at most 1 + spin / R_min
        # times as fast as the rear axle (as in top_speed).
        speed = np.maximum(np.abs(self.speed), np.abs(self.driven_speed)) + self.max_accel * seconds
        return float((speed * (1.0 + spin / self._min_radius)).max(initial=0.0))

    def spec(self, i: int) -> RobotSpec:
        c = self.configs[i]
        return RobotSpec(c.name, of_robot(c).bounding_radius, float(self.track[i]),
                         float(self.max_v[i]), float(self.max_accel[i]), drive=self.name,
                         max_speed=float(self.max_v[i]),
                         max_omega=float(self.max_v[i]) / self.min_turn_radius(i),
                         holonomic=False, min_turn_radius=self.min_turn_radius(i),
                         footprint=of_robot(c))

    def handle(self, i: int) -> "AckermannDrive":
        return AckermannDrive(self, i)


class AckermannDrive:
    """One robot's view of its car-like drive (``robot.drive``)."""

    def __init__(self, group: AckermannDriveGroup, index: int) -> None:
        self._group = group
        self._i = index
        self.wheelbase = float(group.wheelbase[index])  # [m]
        self.max_steer = float(group.max_steer[index])  # [rad]
        self.max_speed = float(group.max_v[index])  # [m/s]
        self.min_turn_radius = group.min_turn_radius(index)  # [m]

    @property
    def steering_angle(self) -> float:
        """The front wheels' (bicycle) steering angle now [rad], positive to the left."""
        return float(self._group.steer[self._i])

    @property
    def speed(self) -> float:
        """Speed of the rear-axle middle now [m/s] (negative in reverse)."""
        return float(self._group.speed[self._i])

    @property
    def command(self) -> Command:
        return self._group.command_of(self._i)

    def _rear(self, speed: float, steer: float) -> tuple[float, float]:
        half_turn = 0.5 * float(self._group.track[self._i]) * math.tan(steer) / self.wheelbase
        return speed * (1.0 - half_turn), speed * (1.0 + half_turn)

    @property
    def target(self) -> tuple[float, float]:
        """(left, right) rear-wheel speeds the command asks for [m/s] (as a diff drive's)."""
        g = self._group
        return self._rear(float(g.target_speed[self._i]), float(g.target_steer[self._i]))

    @property
    def wheel_speeds(self) -> tuple[float, float]:
        """(left, right) rear-wheel speeds in the last substep [m/s]."""
        g = self._group
        return self._rear(float(g.driven_speed[self._i]), float(g.driven_steer[self._i]))

    def set_steering(self, speed: float, steer: float) -> None:
        """Drive at ``speed`` [m/s] with steering angle ``steer`` [rad] (both clipped)."""
        self._group.set_steering(self._i, speed, steer)
