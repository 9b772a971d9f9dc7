"""The navigation task, free of any RL library: scenario preparation, observation, reward.

The Gymnasium env, the vector env and the PettingZoo env all use these pieces, so one robot
sees, acts and is rewarded the same way in all three. Units: metres, seconds, radians.

Observation (float32), for a robot with B LiDAR beams::

    [0, B)   LiDAR ranges / max_range          in [0, 1]   (1: no return)
    B        goal distance / arena diagonal    in [0, 1]
    B+1, B+2 cos, sin of the goal bearing      in [-1, 1]  (bearing in the robot frame)
    B+3      forward speed / v_max             in [-1, 1]
    B+4      yaw rate / omega_max              in [-1, 1]
    B+5      lateral speed / vy_max            in [-1, 1]  (omni drives only)

Action (float32 in [-1, 1]): (v, omega) or (v, omega, vy) for omni drives, scaled by the
drive's limits (see :func:`drive_limits`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from ..config import ScenarioConfig, load_scenario, parse_scenario, scenario_data
from ..errors import ScenarioError

if TYPE_CHECKING:
    from ..robot import Robot

MAX_BEAMS = 4096  # an observation larger than this is a mistake, not a sensor
GOAL_SAMPLE_TRIES = 2000  # random goals tried before giving up on a crowded arena
GOAL_MIN_DISTANCE = 1.0  # [m] a random goal at least this far from the start


@dataclass(frozen=True)
class RewardWeights:
    """Reward per control step = progress * (metres closer to the goal)
    + collision * (new contact episodes) + time * (seconds elapsed) + success (once, on arrival)."""

    progress: float = 1.0  # per metre of progress toward the goal
    collision: float = -1.0  # per new contact episode
    time: float = -0.1  # per simulated second
    success: float = 10.0  # on reaching the goal

    @classmethod
    def from_any(cls, value: "RewardWeights | Mapping[str, float] | None") -> "RewardWeights":
        """Weights as given, from a mapping of some of their names, or the defaults (None)."""
        if value is None:
            return cls()
        if isinstance(value, cls):
            return value
        if not isinstance(value, Mapping):
            raise TypeError(f"reward must be RewardWeights or a mapping of weights (got {value!r})")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(value) - known)
        if unknown:
            raise ValueError(f"unknown reward weight(s) {unknown}; valid: {sorted(known)}")
        weights = {k: float(v) for k, v in value.items()}
        if not all(math.isfinite(v) for v in weights.values()):
            raise ValueError(f"reward weights must be finite (got {weights})")
        return cls(**weights)


def drive_limits(robot_config) -> tuple[float, float, float | None]:
    """(v_max [m/s], omega_max [rad/s], vy_max [m/s] or None) that an action of 1 commands.

    A diff drive turns fastest on the spot: omega_max = 2 * max_wheel_speed / track_width.
    """
    drive = getattr(robot_config, "drive", "diff")
    if drive == "diff":
        v = float(robot_config.max_wheel_speed)
        return v, 2.0 * v / float(robot_config.track_width), None
    v = float(robot_config.max_speed)
    if drive == "omni":
        return v, float(robot_config.max_angular_speed), v
    # ackermann: the tightest circle is wheelbase / tan(max_steer)
    return v, v * math.tan(float(robot_config.max_steer)) / float(robot_config.wheelbase), None


def arena_size(config: ScenarioConfig) -> tuple[float, float]:
    """(width, height) [m] of the arena (parse_scenario fills ``world.size`` in from a map)."""
    if config.world.size is None:
        raise ValueError(f"scenario '{config.name}': the world has neither a size nor a map")
    width, height = config.world.size
    return width, height


def load_config(scenario: str | Path | dict | ScenarioConfig | None) -> tuple[ScenarioConfig, str]:
    """(config, source name) from a path, shipped name, dict, config or None (built-in)."""
    if isinstance(scenario, ScenarioConfig):
        return scenario, f"scenario '{scenario.name}'"
    if isinstance(scenario, dict):
        return parse_scenario(scenario, "<dict>"), "<dict>"
    return load_scenario(scenario), "default" if scenario is None else str(scenario)


def prepare_scenario(config: ScenarioConfig, source: str, agents: list[str] | None,
                     lidar: Mapping[str, Any] | None, control_period: float,
                     need_goal: bool = True) -> tuple[ScenarioConfig, list[str]]:
    """The scenario the agents drive: their controllers removed, a LiDAR that scans once per
    control period (overrides from ``lidar``), a goal each. Returns (config, agent names).

    Errors name the key path, as for a scenario file.
    """
    data = scenario_data(config, exclude_unset=True)  # unset keys stay unset (no localizer)
    names = [r["name"] for r in data["robots"]]
    agents = names[:1] if agents is None else list(agents)
    for name in agents:
        if name not in names:
            raise ScenarioError(source, "robots", f"no robot named '{name}' (robots: {names})")
    overrides = dict(lidar or {})
    for name in agents:
        index = names.index(name)
        robot = data["robots"][index]
        controller = robot.pop("controller", None) or {}
        if robot.get("goal") is None and controller.get("goal") is not None:
            robot["goal"] = {"position": controller["goal"]}
        if need_goal and robot.get("goal") is None:
            raise ScenarioError(source, f"robots[{index}].goal",
                                "the navigation task needs a goal (or random_goal=True)")
        scan = dict(robot.get("lidar") or {})
        scan["rate"] = 1.0 / control_period  # one fresh scan per action
        scan.update(overrides)
        robot["lidar"] = scan
    prepared = parse_scenario(data, source)
    for name in agents:
        lidar_config = prepared.robots[names.index(name)].lidar
        if lidar_config is None:  # given to every agent above
            raise ScenarioError(source, f"robots[{names.index(name)}].lidar", "missing")
        beams = lidar_config.beams
        if beams > MAX_BEAMS:
            raise ScenarioError(source, f"robots[{names.index(name)}].lidar.beams",
                                f"at most {MAX_BEAMS} beams in an observation (got {beams})")
    return prepared, agents


def sample_goal(sim, robot, rng: np.random.Generator) -> tuple[float, float]:
    """A goal in free space: clear of every obstacle by the robot's radius and a margin, and
    at least GOAL_MIN_DISTANCE from the robot."""
    import pymunk

    world = sim.world
    clearance = robot.radius + 0.1  # [m]
    everything = pymunk.ShapeFilter()
    x0, y0 = robot.pose[:2]
    for _ in range(GOAL_SAMPLE_TRIES):
        x = float(rng.uniform(clearance, world.width - clearance))
        y = float(rng.uniform(clearance, world.height - clearance))
        if math.hypot(x - x0, y - y0) < GOAL_MIN_DISTANCE:
            continue
        if world.space.point_query_nearest((x, y), clearance, everything) is None:
            return x, y
    raise RuntimeError(f"no free goal found in {GOAL_SAMPLE_TRIES} tries: the arena is too "
                       "crowded for random_goal")


class RobotTask:
    """One robot's view of the navigation task inside a running simulation.

    Call :meth:`start` after the simulation is (re)built, :meth:`act` before the physics
    advances and :meth:`observe` / :meth:`outcome` after.
    """

    def __init__(self, robot_config, arena: tuple[float, float], weights: RewardWeights,
                 pose_source: str = "ground_truth") -> None:
        if pose_source not in ("ground_truth", "odometry"):
            raise ValueError(f"pose_source must be 'ground_truth' or 'odometry' (got {pose_source!r})")
        self.name = robot_config.name
        self.weights = weights
        self.pose_source = pose_source
        self.v_max, self.omega_max, self.vy_max = drive_limits(robot_config)
        self.beams = robot_config.lidar.beams
        self.max_range = robot_config.lidar.max_range  # [m]
        self.diagonal = math.hypot(*arena)  # [m]
        self.action_size = 2 if self.vy_max is None else 3
        self.obs_size = self.beams + 5 + (self.vy_max is not None)
        self.robot: Robot | None = None  # bound by start()
        self._distance = 0.0  # [m] to the goal at the last observation
        self._collisions = 0

    # ------------------------------------------------------------------ spaces (as arrays)
    def obs_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        low = np.full(self.obs_size, -1.0, dtype=np.float32)
        high = np.ones(self.obs_size, dtype=np.float32)
        low[: self.beams + 1] = 0.0  # ranges and goal distance are never negative
        return low, high

    # ------------------------------------------------------------------ episode
    def bound(self) -> Robot:
        """The robot :meth:`start` bound the task to."""
        if self.robot is None:
            raise RuntimeError(f"the task of robot '{self.name}' has not started: call start()")
        return self.robot

    def goal(self) -> tuple[float, float]:
        """The robot's goal [m]."""
        goal = self.bound().goal
        if goal is None:
            raise RuntimeError(f"robot '{self.name}' has no goal: the navigation task needs one")
        return goal

    @property
    def last_distance(self) -> float:
        """Distance to the goal [m] at the last observation (progress is measured from it)."""
        return self._distance

    @property
    def last_collisions(self) -> int:
        """Contact episodes counted at the last observation."""
        return self._collisions

    def remember(self, distance: float, collisions: int) -> None:
        """What the step just observed, for the next step's progress and new contacts."""
        self._distance, self._collisions = distance, collisions

    def start(self, robot: Robot) -> None:
        """Bind to the (re)built robot and remember where the episode starts."""
        self.robot = robot
        self._distance = self.goal_distance()
        self._collisions = robot.collisions

    def act(self, action: np.ndarray) -> None:
        """Command the normalised body velocity (clipped to [-1, 1])."""
        values = np.asarray(action, dtype=np.float64).reshape(-1).tolist()
        if len(values) != self.action_size or not all(map(math.isfinite, values)):
            raise ValueError(f"action must be {self.action_size} finite numbers (got {action!r})")
        self.command([min(1.0, max(-1.0, value)) for value in values])

    def command(self, a: list[float]) -> None:
        """Command a checked, clipped normalised action (``action_size`` floats in [-1, 1])."""
        robot = self.bound()
        if self.vy_max is None:
            robot.set_velocity(a[0] * self.v_max, a[1] * self.omega_max)
        else:
            robot.set_velocity(a[0] * self.v_max, a[1] * self.omega_max, a[2] * self.vy_max)

    def stop(self) -> None:
        """Hold still (an agent whose episode is over stays in the world as an obstacle)."""
        robot = self.bound()
        if self.vy_max is None:
            robot.set_velocity(0.0, 0.0)
        else:
            robot.set_velocity(0.0, 0.0, 0.0)

    def pose(self) -> tuple[float, float, float]:
        """(x, y, theta) the task sees [m, m, rad]: the truth, or the odometry estimate."""
        robot = self.bound()
        if self.pose_source == "ground_truth":
            body = robot.body
            x, y = body.position
            return x, y, body.angle
        x, y, theta = robot.odometry.pose.tolist()
        return x, y, theta

    def where(self) -> tuple[float, float, float, float, float]:
        """(x, y, theta) the task sees and the goal (x, y), read once [m, m, rad, m, m]."""
        x, y, theta = self.pose()
        gx, gy = self.goal()
        return x, y, theta, gx, gy

    def goal_distance(self) -> float:
        x, y, _, gx, gy = self.where()
        return _length(gx - x, gy - y)

    def observe(self, out: np.ndarray | None = None,
                where: tuple[float, float, float, float, float] | None = None,
                ranges: bool = True) -> np.ndarray:
        """The observation vector (see the module docstring), written into ``out`` if given;
        ``where``: :meth:`where`, if already read this step; ``ranges=False`` leaves the
        LiDAR part of ``out`` to the caller (:meth:`fill_ranges` does it for many)."""
        obs = np.empty(self.obs_size, dtype=np.float32) if out is None else out
        robot, b = self.bound(), self.beams
        if ranges or out is None:
            self.fill_ranges(obs[None], [self])
        x, y, theta, gx, gy = self.where() if where is None else where
        body = robot.body
        angle = theta if self.pose_source == "ground_truth" else body.angle
        c, s = math.cos(angle), math.sin(angle)
        vx, vy = body.velocity
        bearing = math.atan2(gy - y, gx - x) - theta
        tail = [*_pose_features(self, _length(gx - x, gy - y), math.cos(bearing),
                                math.sin(bearing), c * vx + s * vy, body.angular_velocity)]
        if self.vy_max is not None:
            tail.append(_bounded((-s * vx + c * vy) / self.vy_max))
        obs[b:] = tail
        return obs

    @staticmethod
    def fill_ranges(obs: np.ndarray, tasks: list["RobotTask"]) -> None:
        """The LiDAR part of each row of ``obs`` (float32), from its task's latest scan;
        the tasks' beam counts and ranges agree."""
        first = tasks[0]
        b = first.beams
        scans = [task.bound().lidar.latest.ranges for task in tasks]
        obs[:, :b] = scans[0] if len(scans) == 1 else np.stack(scans)
        obs[:, :b] /= first.max_range  # ranges lie in [min_range, max_range]: no clipping

    def outcome(self, elapsed: float, terminate_on_collision: bool = False,
                where: tuple[float, float, float, float, float] | None = None
                ) -> tuple[float, bool, dict]:
        """(reward, terminated, info) for the control step just taken (``elapsed`` seconds);
        ``where``: :meth:`where`, if already read this step."""
        robot = self.bound()
        x, y, _, gx, gy = self.where() if where is None else where
        distance = _length(gx - x, gy - y)
        collisions = robot.collisions
        new_collisions = collisions - self._collisions
        reached = robot.goal_reached
        reward = _reward(self.weights, self._distance - distance, new_collisions, elapsed, reached)
        self._distance = distance
        self._collisions = collisions
        info = {"distance_to_goal": distance, "collisions": collisions,
                "new_collisions": new_collisions, "goal_reached": reached,
                "is_success": reached}
        return float(reward), bool(reached or (terminate_on_collision and new_collisions > 0)), info


def _reward(w: RewardWeights, progress: Any, new_collisions: Any, elapsed: float,
            reached: Any) -> Any:
    """The reward of a control step, for one robot (floats) or many (arrays), the same floats:
    progress toward the goal [m], new contact episodes, time [s] and arrival."""
    return (w.progress * progress + w.collision * new_collisions + w.time * elapsed
            + w.success * reached)


def _bounded(value: Any) -> Any:
    """``value`` kept to [-1, 1] (a float, or an array elementwise): contacts can push a robot
    past its own limits for a moment."""
    return np.minimum(1.0, np.maximum(-1.0, value)) if isinstance(value, np.ndarray) else (
        min(1.0, max(-1.0, value)))


def _pose_features(task: "RobotTask", distance: Any, cos_bearing: Any, sin_bearing: Any,
                   forward: Any, omega: Any) -> tuple[Any, Any, Any, Any, Any]:
    """The observation's goal and motion features, for one robot (floats) or many (arrays):
    goal distance over the arena's diagonal (a goal may lie outside the arena: at most 1), the
    goal bearing's cos and sin, forward speed [m/s] and yaw rate [rad/s] over their limits."""
    scaled = distance / task.diagonal
    near = min(1.0, scaled) if not isinstance(scaled, np.ndarray) else np.minimum(1.0, scaled)
    return (near, cos_bearing, sin_bearing, _bounded(forward / task.v_max),
            _bounded(omega / task.omega_max))


def _length(dx: float, dy: float) -> float:
    """|(dx, dy)| [m], as :func:`outcomes` computes it on arrays (math.hypot rounds
    differently)."""
    return math.sqrt(dx * dx + dy * dy)


def outcomes(tasks: list[RobotTask], states: dict[str, np.ndarray], elapsed: float,
             terminate_on_collision: bool, obs: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """:meth:`RobotTask.outcome` and the pose part of :meth:`RobotTask.observe` for many
    tasks of one scenario at once (ground-truth pose, no lateral speed), from their robots'
    states (``Replicas.robot_states``): (rewards, terminated, info arrays), each row of
    ``obs`` given its tail. The same floats as task by task."""
    first, w = tasks[0], tasks[0].weights
    dx, dy = states["goal_x"] - states["x"], states["goal_y"] - states["y"]
    distance = np.sqrt(dx * dx + dy * dy)
    collisions, reached = states["collisions"], states["reached"]
    new_collisions = collisions - np.array([task.last_collisions for task in tasks],
                                           dtype=np.int64)
    before = np.array([task.last_distance for task in tasks])
    rewards = _reward(w, before - distance, new_collisions, elapsed, reached)
    terminated = reached | (terminate_on_collision & (new_collisions > 0))
    for task, d, c in zip(tasks, distance.tolist(), collisions.tolist()):
        task.remember(d, c)
    # The bearing and heading through math, robot by robot, as observe takes them.
    theta = states["theta"]
    trig = np.array([(math.cos(b), math.sin(b), math.cos(t), math.sin(t))
                     for b, t in zip(_bearings(dy, dx, theta), theta.tolist())]).reshape(-1, 4)
    c, s = trig[:, 2], trig[:, 3]
    features = _pose_features(first, distance, trig[:, 0], trig[:, 1],
                              c * states["vx"] + s * states["vy"], states["omega"])
    obs[:, first.beams:first.beams + 5] = np.column_stack(features)
    info = {"distance_to_goal": distance, "collisions": collisions,
            "new_collisions": new_collisions, "goal_reached": reached,
            "is_success": reached.copy()}
    return rewards, terminated, info


def _bearings(dy: np.ndarray, dx: np.ndarray, theta: np.ndarray) -> list[float]:
    """Goal bearings in the robot frame [rad], through math.atan2 as observe takes them."""
    return [math.atan2(y, x) - t for y, x, t in zip(dy.tolist(), dx.tolist(), theta.tolist())]


def robot_result(sim, name: str) -> dict:
    """The result fields of one robot (``Simulation.result()``'s robots entry) plus ``passed``."""
    result = sim.result()
    fields_ = dict(result["robots"][name])
    fields_["passed"] = result["passed"]
    return fields_
