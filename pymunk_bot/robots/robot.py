"""A robot handle: what users hold (``sim.robots["r1"]``). Its state lives in the world's arrays
and pymunk bodies; a reset rebinds the same handle to the rebuilt state, so it stays valid."""
from __future__ import annotations

import math
import numbers
from typing import Any, Callable

import numpy as np
import pymunk

from pymunk_bot.robots.command import Command
from pymunk_bot.config.schema import RobotConfig
from pymunk_bot.robots.progress import reach_goals, travel_rows
from pymunk_bot.robots.readings import RobotSpec
from pymunk_bot.robots.rows import OWN, Rows


def real_number(name: str, value: Any) -> float:
    """``value`` as a finite float; TypeError for text or booleans (as the scenario's YAML
    refuses them), ValueError for NaN and infinities. ``name`` is the argument in messages."""
    if type(value) is float and math.isfinite(value):  # the usual case, without ABC checks
        return value
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number (got {type(value).__name__} {value!r:.40})")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite (got {number})")
    return number


class RobotsByName(dict):
    """``sim.robots``: the robots by name; a missing name says which names there are."""

    def __missing__(self, name: Any) -> Any:
        import difflib

        known = ", ".join(map(repr, self)) or "none"
        near = difflib.get_close_matches(str(name), [str(k) for k in self], n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise KeyError(f"no robot named {name!r:.80}{hint}; the robots are: {known:.400}")


class Fleet:
    """Every robot's per-tick bookkeeping: distance, goal, contact episodes, as arrays indexed
    by robot, advanced by compiled passes (``robots/progress.py``) however many; and who
    drives each (``by_hand``, ``observes``, ``constant``, ``holds_constant``: the simulation
    asks controllers by these rows)."""

    ROWS = ("xy", "distance", "collisions", "goal", "tolerance", "time_to_goal",
            "distance_to_goal")
    # (x0, y0, x1, y1) [m] of the arena, for checking goals set from code (build sets it)
    extent: tuple[float, float, float, float] | None = None

    def __init__(self, configs: list[RobotConfig], rows: Rows = OWN) -> None:
        n = len(configs)
        self.configs = configs
        self.stacked_in: tuple[Fleet, int] | None = None  # (stack, first row) while stacked
        goal = np.full((n, 2), np.nan)  # task goal [m]; NaN: none
        tolerance = np.full(n, 0.2)  # [m]
        for i, c in enumerate(configs):
            if c.goal is not None:
                goal[i] = c.goal.position
                tolerance[i] = c.goal.tolerance
        hold = rows.hold
        self.xy = hold("xy", np.array([c.pose[:2] for c in configs], dtype=float).reshape(n, 2))
        self.distance = hold("distance", np.zeros(n))  # true path length [m]
        self.collisions = hold("collisions", np.zeros(n, dtype=np.int64))  # contact episodes
        self.goal, self.tolerance = hold("goal", goal), hold("tolerance", tolerance)
        self.time_to_goal = hold("time_to_goal", np.full(n, np.nan))  # [s]; NaN: not reached
        # path length when reached [m]
        self.distance_to_goal = hold("distance_to_goal", np.full(n, np.nan))
        # Held by a command set by hand (its controller waits); whether its controller reads
        # an observation; whether it gives one command for ever (Controller.constant), and
        # that command is held (kept by the robot's handle: Robot.controller, Robot.command,
        # and the simulation). Lists: a tick reads a few items of them, where numpy costs more.
        self.by_hand = [False] * n
        self.observes = [False] * n
        self.constant = [False] * n
        self.holds_constant = [False] * n
        self._now = np.zeros(1)  # [s] the tick's time, as reach_goals takes it
        self.watch_unreached()
        if rows.fresh:
            self.advance(self.xy, 0.0)  # goals started inside are reached at t = 0

    @classmethod
    def stacked(cls, parts: list["Fleet"], rows: Rows) -> "Fleet":
        """The fleets of copies as one, on ``rows`` (the whole of the rows the parts hold:
        :mod:`pymunk_bot.robots.rows`); ``advance`` then takes each robot's time [s] as an
        array."""
        whole = cls([c for part in parts for c in part.configs], rows)
        offset = 0
        for part in parts:
            part.stacked_in = (whole, offset)
            offset += part.goal.shape[0]
        return whole

    def watch_unreached(self) -> None:
        """Every goal not reached yet is pending."""
        self._pending = np.flatnonzero(~np.isnan(self.goal[:, 0]) & np.isnan(self.time_to_goal))
        self._refresh_targets()

    def watch_goal(self, i: int) -> None:
        """Robot ``i`` has a new goal: not reached yet, and checked every tick from now."""
        self.time_to_goal[i] = self.distance_to_goal[i] = np.nan
        self._pending = np.union1d(self._pending, [i])
        self._refresh_targets()
        if self.stacked_in is not None:  # stacked: the stack checks the goals
            whole, offset = self.stacked_in
            whole.watch_goal(offset + i)

    def _refresh_targets(self) -> None:
        """The pending goals as ``advance`` reads them: their goals and squared tolerances."""
        p = self._pending
        self._pending_goal, self._pending_tolerance2 = self.goal[p], self.tolerance[p] ** 2
        self._reached = np.empty(p.shape[0], dtype=np.bool_)  # reach_goals' flags
        self.goals_pending = p.shape[0] > 0  # some robot has a goal it has not reached yet

    def advance(self, xy: np.ndarray, time: Any) -> None:
        """Bookkeeping after a tick at ``time`` [s] (one for all, or an array with each robot's),
        from every robot's new position, (n, 2) [m] (copied: the caller may reuse it)."""
        travel_rows(xy, self.xy, self.distance)
        self.arrive(time)

    def arrive(self, time: Any) -> None:
        """The goals reached at ``time`` [s] (one for all, or an array with each robot's) by
        the robots at their positions now (``xy``: after the tick's travel)."""
        if not self.goals_pending:
            return
        p = self._pending
        if isinstance(time, np.ndarray):
            times = time
        else:
            times = self._now
            times[0] = time
        reached = self._reached
        if reach_goals(self.xy, self.distance, p, self._pending_goal, self._pending_tolerance2,
                       times, self.time_to_goal, self.distance_to_goal, reached):
            self._pending = p[~reached]
            self._refresh_targets()


class MissingSensorError(AttributeError):
    """A robot read for a sensor it was not given (``hasattr(robot, "lidar")`` is then False)."""

    def __init__(self, robot: str, kind: str, fitted: list[str]) -> None:
        have = ", ".join(fitted) if fitted else "none"
        super().__init__(f"robot '{robot}' has no {kind}: add `{kind}:` to its entry under "
                         f"`robots:` in the scenario (its sensors: {have})")
        self.robot, self.kind = robot, kind


class Robot:
    """A simulated robot: ``pose`` is ground truth; its sensors and localizer give what it knows.

    Made by :mod:`pymunk_bot.engine.build`; attributes: ``config``, ``name``, ``spec``, ``body`` and
    ``shape`` (pymunk), ``drive``, ``odometry``, ``sensors`` (``lidar``, ``imu``, ``bumper``),
    ``controller``, ``localizer``, ``metrics``.
    """

    config: RobotConfig
    name: str
    spec: RobotSpec
    body: pymunk.Body
    shape: pymunk.Shape  # the first of ``shapes``
    shapes: list[pymunk.Shape]  # the footprint's convex pieces
    control: pymunk.Body
    drive: Any
    odometry: Any
    localizer: Any
    metrics: Any

    # Called when the robot is moved outside the physics (a teleport); build sets it.
    on_moved: Callable[[], None] | None = None

    def __init__(self, name: str) -> None:
        self.name = name

    def bind(self, fleet: Fleet, index: int, drive_group: Any, drive_index: int) -> None:
        """Point this handle at freshly built state: row ``index`` of ``fleet`` and robot
        ``drive_index`` of ``drive_group`` (build calls this, at every reset too)."""
        name = self.name
        self.__dict__.clear()
        self.name = name
        self._fleet, self._i = fleet, index
        self._drive_group, self._di = drive_group, drive_index
        self.sensors: list = []  # everything with update(time), in the order they read
        self._fitted: dict[str, Any] = {}  # "lidar", "imu", "bumper" -> the sensor
        self.controller = None
        self.localizer = None
        self.mapper: Any = None  # builds an occupancy grid from this robot's LiDAR, if configured
        self.metrics = None
        self.localization_score: Any = None  # estimate vs truth, when the scenario names a localizer
        self.nav_goal: tuple[float, float] | None = None  # where the controller drives
        self._followed: Any = None  # the controller's command the drive holds now (follow)

    # ------------------------------------------------------------------ sensors
    def sensor(self, kind: str) -> Any | None:
        """The robot's sensor of this kind ("lidar", "imu", "bumper"), or None if it has none
        (``robot.lidar`` raises instead: for code that handles robots without one)."""
        return self._fitted.get(kind)

    def fit(self, kind: str, sensor: Any) -> None:
        """Mount ``sensor`` as the robot's ``kind`` (the sensor factories call this)."""
        self._fitted[kind] = sensor

    def _fitted_sensor(self, kind: str) -> Any:
        sensor = self._fitted.get(kind)
        if sensor is None:
            raise MissingSensorError(self.name, kind, sorted(self._fitted))
        return sensor

    @property
    def lidar(self) -> Any:
        """The robot's LiDAR (``lidar.latest``, ``lidar.scan()``); MissingSensorError, an
        AttributeError naming the scenario key to add, if it has none."""
        return self._fitted_sensor("lidar")

    @property
    def imu(self) -> Any:
        """The robot's IMU (``imu.reading``); MissingSensorError if it has none."""
        return self._fitted_sensor("imu")

    @property
    def bumper(self) -> Any:
        """The robot's bumper (every robot has one)."""
        return self._fitted_sensor("bumper")

    # ------------------------------------------------------------------ state
    @property
    def radius(self) -> float:
        """Radius of the disc that holds the robot's footprint [m]."""
        return self.spec.radius

    @property
    def pose(self) -> np.ndarray:
        """Ground-truth pose [x, y, theta] (theta unwrapped: it counts whole turns)."""
        p = self.body.position
        return np.array([p.x, p.y, self.body.angle])

    @property
    def velocity(self) -> np.ndarray:
        """Ground-truth (v forward [m/s], omega [rad/s]) of the body."""
        vx, vy = self.body.velocity
        theta = self.body.angle
        return np.array([vx * math.cos(theta) + vy * math.sin(theta), self.body.angular_velocity])

    @property
    def distance(self) -> float:
        """True path length so far [m]."""
        return float(self._fleet.distance[self._i])

    @property
    def collisions(self) -> int:
        """Contact episodes so far (a begin of contact with anything)."""
        return self._fleet.collisions.item(self._i)

    @property
    def goal(self) -> tuple[float, float] | None:
        """The task goal [m] (None: none)."""
        x, y = self._fleet.goal[self._i].tolist()
        return None if math.isnan(x) else (x, y)

    @property
    def goal_tolerance(self) -> float:
        return self._fleet.tolerance.item(self._i)

    @property
    def time_to_goal(self) -> float | None:
        """Simulated time when the goal was first reached [s] (0: started inside it); None: not yet."""
        t = self._fleet.time_to_goal.item(self._i)
        return None if math.isnan(t) else t

    @property
    def distance_to_goal(self) -> float | None:
        """Path length when the goal was reached [m]; None: not yet."""
        d = self._fleet.distance_to_goal.item(self._i)
        return None if math.isnan(d) else d

    @property
    def goal_reached(self) -> bool:
        return not math.isnan(self._fleet.time_to_goal.item(self._i))

    def set_goal(self, position: tuple[float, float], tolerance: float | None = None) -> None:
        """A new task goal (e.g. a click in the viewer); the controller drives there too.
        TypeError for text, ValueError for a point outside the arena or a bad ``tolerance``."""
        x, y = self._point_in_arena("goal", position)
        if tolerance is not None and real_number("tolerance", tolerance) <= 0:
            raise ValueError(f"tolerance must be > 0 m (got {tolerance!r})")
        fleet, i = self._fleet, self._i
        fleet.goal[i] = (x, y)
        if tolerance is not None:
            fleet.tolerance[i] = tolerance
        self.nav_goal = (x, y)
        fleet.watch_goal(i)

    def set_nav_goal(self, position: tuple[float, float]) -> None:
        """Send the controller somewhere (e.g. a click in the viewer) without changing the task:
        expectations still judge the scenario's goal."""
        self.nav_goal = self._point_in_arena("goal", position)

    def _point_in_arena(self, name: str, position: Any) -> tuple[float, float]:
        """(x, y) [m] of a point given from code: two finite numbers inside the arena."""
        if isinstance(position, (str, bytes)) or len(position) != 2:
            raise TypeError(f"{name} must be (x, y) in metres (got {position!r:.60})")
        x, y = real_number(f"{name}[0]", position[0]), real_number(f"{name}[1]", position[1])
        extent = self._fleet.extent
        if extent is not None:
            x0, y0, x1, y1 = extent
            if not (x0 <= x <= x1 and y0 <= y <= y1):
                raise ValueError(f"{name} ({x:g}, {y:g}) is outside the arena "
                                 f"[{x0:g}, {x1:g}] x [{y0:g}, {y1:g}] m")
        return x, y

    def teleport(self, x: float, y: float, theta: float) -> None:
        """Move the robot to (x [m], y [m], theta [rad]) at once and stop it: a kidnapping. Its
        odometry is not told (it goes on from where it was), nor its localizer; contacts
        re-solve at the next step if it lands touching something. ValueError outside the arena."""
        x, y = self._point_in_arena("teleport", (x, y))
        theta = real_number("theta", theta)
        if self.on_moved is not None:
            self.on_moved()  # adaptive substeps look anew before a tick may skip them
        for body in (self.body, self.control):
            body.position = (x, y)
            body.angle = theta
            body.velocity = (0.0, 0.0)
            body.angular_velocity = 0.0
        for shape in self.shapes:  # in the Space that holds them (their body may step apart)
            if shape.space is not None:
                shape.space.reindex_shape(shape)
        # The jump is no distance travelled. In place: a stacked copy's rows are views of
        # the stack's, which does the copies' bookkeeping.
        self._fleet.xy[self._i] = (x, y)

    def readings(self) -> dict:
        """Latest readings of the sensors beyond LiDAR and odometry, by name (e.g. "imu")."""
        lidar = self.sensor("lidar")
        return {s.name: s.reading for s in self.sensors if s is not lidar}

    # ------------------------------------------------------------------ commands
    def set_velocity(self, v: float, omega: float, vy: float = 0.0) -> None:
        """Drive at body-frame forward speed ``v`` [m/s], yaw rate ``omega`` [rad/s] and lateral
        speed ``vy`` [m/s] (omni drives only) until :meth:`clear_command`; the controller waits.
        TypeError for text (``"0.5"``), as the scenario's YAML refuses it."""
        self.command(Command(real_number("v", v), real_number("omega", omega),
                             real_number("vy", vy)))

    def set_wheel_speeds(self, left: float, right: float) -> None:
        """Diff drive: these wheel speeds [m/s] until :meth:`clear_command`; the controller waits."""
        if not hasattr(self._drive_group, "set_wheel_speeds"):
            raise ValueError(f"a {self.config.drive} drive has no wheel speeds; use set_velocity")
        left, right = real_number("left", left), real_number("right", right)
        self._drive_group.set_wheel_speeds(self._di, left, right)  # raises before taking over
        self._fleet.by_hand[self._i], self._followed = True, None

    def command(self, command: Command) -> None:
        """Drive with this :class:`Command` until :meth:`clear_command`; the controller waits."""
        self._drive_group.set_command(self._di, command)  # raises before taking over
        self._fleet.by_hand[self._i], self._followed = True, None

    def clear_command(self) -> None:
        """Give the robot back to its controller."""
        self._fleet.by_hand[self._i], self._followed = False, None
        self._fleet.holds_constant[self._i] = False  # a constant controller is asked again

    def take_over(self) -> None:
        """A command set for this robot's drive outside its handle (the vector env's batched
        commands) holds it, as :meth:`command` does; the controller waits."""
        self._fleet.by_hand[self._i], self._followed = True, None

    def follow(self, command: Any) -> None:
        """Drive with the controller's ``command`` (the simulation asks the controller only
        while no command set by hand holds the robot: see :attr:`overridden`). The very
        command the drive already holds (commands are immutable; a controller that holds
        one returns the same object) is not set again: a fleet's idle controllers cost less."""
        if command is not self._followed:
            self._drive_group.set_command(self._di, command)
            self._followed = command

    def count_collision(self) -> None:
        """A contact episode of this robot began (the world's contact handler calls this)."""
        self._fleet.collisions[self._i] += 1

    clear_wheel_speeds = clear_command  # the name before every drive took body velocities

    @property
    def overridden(self) -> bool:
        """True while a command set by hand (or teleop) holds the robot."""
        return self._fleet.by_hand[self._i]

    @property
    def controller(self) -> Any:
        """What drives this robot when no command set by hand holds it (None: nothing)."""
        return self._controller

    @controller.setter
    def controller(self, controller: Any) -> None:
        # Whether it reads an observation is read now, once: a fleet's controllers are then
        # asked by rows (a controller of the same shape that is no Controller subclass observes).
        fleet, i = self._fleet, self._i
        self._controller = controller
        fleet.observes[i] = getattr(controller, "observes", True)
        fleet.constant[i] = not fleet.observes[i] and getattr(controller, "constant", False)
        fleet.holds_constant[i] = False
