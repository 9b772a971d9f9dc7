"""Differential drive: wheel speeds -> a kinematic control body that pulls the robot body.

The tank pattern (see docs/physics.md): a PivotJoint and a GearJoint with max_bias = 0 and a
force cap tie the dynamic robot body to a kinematic control body whose velocity we set. In free
space the robot follows the command exactly; against a wall the cap limits the push, so the robot
stops, slides or pushes with real contact response.

pymunk integrates positions before it solves velocities, so a velocity given to the control body
in one substep moves the robot in the next. The drive therefore commands each substep for the
heading the robot will have one substep later, and the wheel speeds it reports (what the encoders
see) are the ones the body is moving with now: the motor lags its command by one substep.
"""
from __future__ import annotations

import math

import pymunk


def sinc_half(x: float) -> float:
    """sin(x/2) / (x/2): chord length of an arc over its arc length."""
    half = 0.5 * x
    return 1.0 - half * half / 6.0 if abs(half) < 1e-4 else math.sin(half) / half


class DiffDrive:
    """Two wheels ``track_width`` apart, each limited in speed and acceleration."""

    def __init__(self, space: pymunk.Space, body: pymunk.Body, track_width: float,
                 max_wheel_speed: float, max_accel: float) -> None:
        self.body = body
        self.track_width = track_width
        self.max_wheel_speed = max_wheel_speed
        self.max_accel = max_accel
        self.target = (0.0, 0.0)  # commanded wheel speeds, after the speed limit [m/s]
        self.commanded = (0.0, 0.0)  # acceleration-limited speeds sent to the motors [m/s]
        self.wheel_speeds = (0.0, 0.0)  # speeds the wheels turn at during this substep [m/s]
        self.control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        # Enough force to follow the fastest allowed change of speed and the tightest turn, with
        # margin: the tangential wheel acceleration plus the centripetal v*omega <= v_max^2 / L.
        force = body.mass * (2.0 * max_accel + max_wheel_speed ** 2 / track_width)
        self.pivot = pymunk.PivotJoint(self.control, body, (0, 0), (0, 0))
        self.pivot.max_bias = 0.0
        self.pivot.max_force = force
        self.gear = pymunk.GearJoint(self.control, body, 0.0, 1.0)
        self.gear.max_bias = 0.0
        self.gear.max_force = force * track_width / 2.0
        space.add(self.control, self.pivot, self.gear)

    def set_wheel_speeds(self, left: float, right: float) -> None:
        """Command wheel speeds [m/s]; both are scaled by one factor so the turn radius is kept."""
        if not (math.isfinite(left) and math.isfinite(right)):
            raise ValueError(f"wheel speeds must be finite (got {left}, {right})")
        peak = max(abs(left), abs(right))
        if peak > self.max_wheel_speed:
            scale = self.max_wheel_speed / peak
            left, right = left * scale, right * scale
        self.target = (left, right)

    def before_substep(self, h: float) -> None:
        """Advance the motors by one substep of h seconds and steer the control body."""
        self.wheel_speeds = self.commanded
        step = self.max_accel * h
        (l0, r0), (lt, rt) = self.commanded, self.target
        left = l0 + min(step, max(-step, lt - l0))
        right = r0 + min(step, max(-step, rt - r0))
        self.commanded = (left, right)
        v = 0.5 * (left + right)
        omega = (right - left) / self.track_width
        body, control = self.body, self.control
        # Heading when this command takes effect, then the middle of that substep: moving along
        # the chord at v * sinc keeps the robot exactly on the commanded arc.
        heading = body.angle + body.angular_velocity * h + 0.5 * omega * h
        speed = v * sinc_half(omega * h)
        # The control body's position and angle never matter: both joints act at the centres
        # and, with max_bias = 0, only on velocities, so there is nothing to wind up.
        control.velocity = (speed * math.cos(heading), speed * math.sin(heading))
        control.angular_velocity = omega
