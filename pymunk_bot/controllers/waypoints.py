"""Waypoint following with regulated pure pursuit; ``loop: true`` patrols the points forever."""
from __future__ import annotations

import math

import numpy as np

from pymunk_bot.config.controllers import PursuitConfig, WaypointsControllerConfig
from pymunk_bot.geometry.plane import wrap_angle
from pymunk_bot.planning.steering import car_pursue, holonomic_toward
from pymunk_bot.planning.pursuit import PathTracker, PursuitGains, pursue, round_corners
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec


def pursuit_gains(config: PursuitConfig, robot: RobotSpec, max_speed: float,
                  lookahead: float | None = None) -> PursuitGains:
    """The tracker gains a pursuit section describes, for this robot."""
    car = robot.min_turn_radius > 0
    return PursuitGains(lookahead=lookahead or config.lookahead, max_speed=max_speed,
                        lookahead_time=config.lookahead_time,
                        # A car's corners are no tighter than its turning circle.
                        corner_radius=max(config.corner_radius, robot.min_turn_radius),
                        lateral_accel=config.lateral_accel,
                        decel=config.decel,
                        # Only a diff drive turns on the spot.
                        rotate_threshold=config.rotate_threshold if robot.drive == "diff" else math.pi,
                        track_width=robot.track_width if robot.drive == "diff" else 0.0,
                        drive="ackermann" if car else ("omni" if robot.holonomic else "diff"),
                        min_turn_radius=robot.min_turn_radius, max_omega=robot.max_omega)


class PathFollower:
    """Drives along a polyline: rounded corners, a speed profile, pure pursuit, a clean stop."""

    def __init__(self, points, loop: bool, gains: PursuitGains, corner_radius: float,
                 period: float = 0.1) -> None:
        self.gains = gains
        self.period = period  # [s] between commands
        self.keep_heading: float | None = None  # omni "keep": the heading to hold [rad]
        self.tracker = PathTracker(round_corners(points, corner_radius, loop), loop, gains)

    def carrot(self, pose) -> tuple[np.ndarray, float, float]:
        """(steering point, speed limit [m/s], distance to the end [m]; inf on a loop)."""
        g, tracker = self.gains, self.tracker
        x, y = float(pose[0]), float(pose[1])
        tracker.update(x, y, window=max(1.0, 2.0 * g.lookahead))
        speed = max(tracker.speed_at(tracker.s), g.min_speed)
        # A shorter lookahead where the profile is slow (bends) follows them more tightly.
        lookahead = min(g.lookahead, max(g.min_lookahead, g.lookahead_time * speed))
        if tracker.loop:
            return tracker.point_at(tracker.s + lookahead), speed, math.inf
        end = tracker.points[-1]
        to_end = math.hypot(end[0] - x, end[1] - y)
        if tracker.remaining() > max(lookahead, to_end):
            # Far along the path from the end, though maybe close to it in space (a route
            # that ends where it starts): what is left to drive is the path, not the gap.
            to_end = tracker.remaining()
        # Brake to a stop at the end point itself: v <= sqrt(2 a d), proportional when close.
        speed = min(speed, math.sqrt(2.0 * g.decel * to_end), 1.5 * to_end)
        if tracker.remaining() > lookahead:
            return tracker.point_at(tracker.s + lookahead), speed, to_end
        return np.asarray(end), speed, to_end

    def drive(self, pose) -> tuple[Command, float]:
        """(the command for this robot's drive, distance left to the end [m]; inf on a loop)."""
        g = self.gains
        if g.drive == "diff":
            v, omega, to_end = self.command(pose)
            return Command(v, omega), to_end
        carrot, speed, to_end = self.carrot(pose)
        if g.drive == "omni":
            tracker = self.tracker
            ahead = tracker.point_at(tracker.s + g.lookahead) - tracker.point_at(tracker.s)
            face = math.atan2(ahead[1], ahead[0]) if np.hypot(*ahead) > 1e-6 else None
            if self.keep_heading is not None:
                face = self.keep_heading
            return holonomic_toward(pose, carrot, speed, face, g.max_omega, self.period), to_end
        return car_pursue(pose, carrot, speed, g.min_turn_radius), to_end

    def command(self, pose) -> tuple[float, float, float]:
        """(v, omega, distance left to the end [m]) for the pose; the distance is inf on a loop."""
        carrot, speed, to_end = self.carrot(pose)
        g = self.gains
        if self.tracker.loop or self.tracker.remaining() > g.min_lookahead + 1e-9 and not (
                np.allclose(carrot, self.tracker.points[-1])):
            return (*pursue(pose, carrot, g, speed), to_end)
        # The last stretch: the arc through a close end point can ask for a huge curvature, so
        # turn toward it in proportion and drive only while roughly facing it.
        x, y = float(pose[0]), float(pose[1])
        bearing = wrap_angle(math.atan2(carrot[1] - y, carrot[0] - x) - float(pose[2]))
        return speed * max(0.0, math.cos(bearing)), g.k_turn * bearing, to_end


class WaypointsController(Controller):
    """Follows ``points`` in order from wherever the robot starts; stops at the last one."""

    def __init__(self, config: WaypointsControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config, robot)
        self.gains = pursuit_gains(config.pursuit, robot, self.max_speed)
        self.corner_radius = config.pursuit.corner_radius
        self.points = [tuple(p) for p in config.points]
        self.lead_in: PathFollower | None = None  # from the start pose to the first point
        self.follower: PathFollower | None = None

    def debug_path(self):
        path = list(self.points)
        return path + [path[0]] if self.config.loop and len(path) > 1 else path

    def compute(self, obs: Observation) -> Command:
        hold = self.hold_until_localized(obs)  # localize before driving (Controller)
        if hold is not None:
            return hold
        x, y, _ = obs.pose
        if self.follower is None:
            start = (float(x), float(y))
            if self.config.loop:
                self.lead_in = PathFollower([start, self.points[0]], False, self.gains, 0.0,
                                            1.0 / self.rate)
                self.follower = PathFollower(self.points, True, self.gains, self.corner_radius,
                                             1.0 / self.rate)
            else:
                self.follower = PathFollower([start] + self.points, False, self.gains,
                                             self.corner_radius, 1.0 / self.rate)
            if self.config.pursuit.heading == "keep":
                for each in (self.lead_in, self.follower):
                    if each is not None:
                        each.keep_heading = float(obs.pose[2])
        follower = self.follower
        if self.lead_in is not None:
            # Join the loop once its first point is within a lookahead.
            if math.hypot(self.points[0][0] - x, self.points[0][1] - y) > self.gains.lookahead:
                follower = self.lead_in
            else:
                self.lead_in = None
        command, left = follower.drive(obs.pose)
        tolerance = self.config.tolerance if self.config.tolerance is not None else obs.goal_tolerance
        if follower is self.follower and not self.config.loop and (
                left <= 0.5 * tolerance or (left <= tolerance and follower.tracker.remaining() < 1e-6)):
            self.status, self.message = "arrived", "reached the last waypoint"
            return STOP
        self.status = "running"
        if self.config.loop and self.lead_in is None:
            self.message = f"patrolling, lap {self.follower.tracker.laps + 1}"
        return command
