"""Commands from outside (``/cmd_vel``, ``/goal_pose``) -> the robot's public command API.

Network threads (the rosbridge server, the Foxglove server) only :meth:`CommandInbox.put`;
the simulation applies what arrived after each step (the inbox is a simulation observer), so
a robot changes only between steps, as teleop in the viewer does.

The watchdog: a robot driven by ``/cmd_vel`` keeps its last command until ``timeout`` seconds
of wall-clock time pass without a new one (a real base driver guards its link the same way);
then it is stopped and given back to its controller, which drives on if it has one.

A command may carry ``reply(level, message)``, the way back to whoever sent it (a rosbridge
client's ``status``): a command the robot refuses is told there (else to ``report``). A
``/cmd_vel`` lateral speed on a drive that cannot move sideways is ignored (the drive keeps
the rest), and said once each time /cmd_vel takes the robot over.
"""
from __future__ import annotations

import collections
import math
import time
from dataclasses import dataclass, field, replace
from typing import Callable, Optional

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.ros2.jsonmsg import BadMessage, parse_pose_stamped, parse_twist
from pymunk_bot.ros2.names import DEFAULT_COMMAND_TIMEOUT, MAP_FRAME

MAX_TIMEOUT = 3600.0  # [s]
MAX_PENDING = 10_000  # commands waiting for the next step; more are dropped (a flood)


def check_timeout(timeout: float) -> float:
    """``timeout`` if usable as the watchdog's [s], else a one-line ScenarioError."""
    if not (math.isfinite(timeout) and 0 < timeout <= MAX_TIMEOUT):
        raise ScenarioError("--cmd-timeout", "", f"must be > 0 and <= {MAX_TIMEOUT:g} s "
                                                 f"(got {timeout:g})")
    return timeout


Reply = Callable[[str, str], None]  # (level "error" or "warning", message) to the sender


@dataclass(frozen=True)
class Drive:
    """Drive ``robot`` at body-frame ``v`` [m/s], ``omega`` [rad/s], ``vy`` [m/s]."""

    robot: str
    v: float
    omega: float
    vy: float = 0.0
    reply: Optional[Reply] = field(default=None, compare=False)


@dataclass(frozen=True)
class Goal:
    """Send ``robot``'s controller to (``x``, ``y``) [m] in the map frame."""

    robot: str
    x: float
    y: float
    reply: Optional[Reply] = field(default=None, compare=False)


def command_of(robot: str, what: str, message, reply: Reply | None = None) -> Drive | Goal:
    """The command in a client's JSON ``message`` on ``robot``'s ``what`` topic ("cmd_vel":
    a Twist, "goal_pose": a PoseStamped in the map frame); BadMessage if it does not fit.
    ``reply``: where a refusal of it goes (see the module's docstring)."""
    if what == "cmd_vel":
        v, omega, vy = parse_twist(message)
        return Drive(robot, v, omega, vy, reply)
    x, y, frame = parse_pose_stamped(message)
    if frame not in ("", MAP_FRAME):
        raise BadMessage(f"msg.header.frame_id must be '{MAP_FRAME}' (got '{frame}')")
    return Goal(robot, x, y, reply)


class CommandInbox:
    """Thread-safe inbox of :class:`Drive` and :class:`Goal` commands, applied to the
    simulation after each step, with the ``/cmd_vel`` watchdog."""

    def __init__(self, timeout: float = DEFAULT_COMMAND_TIMEOUT,
                 clock: Callable[[], float] = time.monotonic,
                 report: Callable[[str], None] = print) -> None:
        self.timeout = check_timeout(timeout)  # [s] wall
        self.clock = clock
        self.report = report  # one line per event worth telling the user
        self._pending: collections.deque = collections.deque()  # append/popleft are atomic
        self._driven: dict[str, float] = {}  # robot -> wall time of its last /cmd_vel
        self._told_sideways: set[str] = set()  # driven robots told their vy is ignored

    def put(self, command: Drive | Goal) -> bool:
        """Queue a command (any thread); False when the inbox is full (dropped)."""
        if len(self._pending) >= MAX_PENDING:
            return False
        self._pending.append(command)
        return True

    def attach(self, sim) -> "CommandInbox":
        if self not in sim.observers:
            sim.observers.append(self)
        return self

    def on_reset(self, sim) -> None:
        self._driven.clear()  # a reset rebuilds the robots: nobody holds them any more
        self._told_sideways.clear()

    def __call__(self, sim) -> None:
        """After a step: apply what arrived, then let the watchdog release quiet robots."""
        pending = self._pending
        while pending:  # only this thread takes from the queue
            command = pending.popleft()
            robot = sim.robots.get(command.robot)
            if robot is None:  # checked on arrival; only a reset can remove a robot
                continue
            try:
                if isinstance(command, Drive):
                    command = self._forward_only(robot, command)
                    robot.set_velocity(command.v, command.omega, command.vy)
                    if command.robot not in self._driven:
                        self.report(f"{command.robot}: driven by /cmd_vel (back to its controller "
                                    f"after {self.timeout:g} s without a command)")
                    self._driven[command.robot] = self.clock()
                else:
                    robot.set_nav_goal((command.x, command.y))
                    self.release(sim, command.robot, quiet=True)
                    if robot.overridden:  # held by something else (the viewer's teleop)
                        robot.clear_command()
                    self.report(f"{command.robot}: goal ({command.x:.2f}, {command.y:.2f}) m")
            except ValueError as exc:  # a drive that cannot take this command
                self._tell(command, "error", f"{command.robot}: command refused: {exc}")
        if self._driven:
            now = self.clock()
            for name, last in list(self._driven.items()):
                if now - last > self.timeout:
                    self.release(sim, name)

    def _tell(self, command: Drive | Goal, level: str, line: str) -> None:
        if command.reply is not None:
            command.reply(level, line)
        else:
            self.report(line)

    def _forward_only(self, robot, command: Drive) -> Drive:
        """``command`` without its lateral speed if ``robot``'s drive cannot move sideways
        (said once while /cmd_vel holds the robot)."""
        if command.vy == 0.0 or robot.spec.holonomic:
            return command
        if command.robot not in self._told_sideways:
            self._told_sideways.add(command.robot)
            self._tell(command, "warning", f"{command.robot}: linear.y = {command.vy:g} m/s "
                       f"ignored: a {robot.spec.drive} drive cannot move sideways")
        return replace(command, vy=0.0)

    def release(self, sim, name: str, quiet: bool = False) -> None:
        """Stop robot ``name`` and give it back to its controller, if /cmd_vel holds it."""
        self._told_sideways.discard(name)
        if self._driven.pop(name, None) is None:
            return
        robot = sim.robots[name]
        if robot.overridden:
            robot.set_velocity(0.0, 0.0)  # without a controller, it would keep the last command
            robot.clear_command()
        if not quiet:
            self.report(f"{name}: no /cmd_vel for {self.timeout:g} s: stopped, back to its "
                        "controller")

    @property
    def driven(self) -> list[str]:
        """The robots /cmd_vel holds now."""
        return list(self._driven)
