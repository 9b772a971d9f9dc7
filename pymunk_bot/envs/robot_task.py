"""One robot's view of the navigation task: its action, observation and reward, for one robot
(:meth:`RobotTask.outcome`) or many of one scenario at once (:func:`outcomes`), the same floats.

The observation and the action scaling are :mod:`pymunk_bot.policy_io`'s (the ``policy``
controller uses them too); the reward is :class:`~pymunk_bot.envs.task.RewardWeights`'.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..command import STOP
from ..policy_io import (
    ActionScale, ObservationBuilder, action_size, goal_features, observation_bounds,
    observation_size,
)
from .task import RewardWeights

if TYPE_CHECKING:
    from ..robot import Robot

Where = tuple[float, float, float, float, float]  # x, y, theta of the robot, goal x, y


def touching(robot: "Robot") -> bool:
    """True while the robot's body touches something (after the last physics substep).

    A body lists only the arbiters its last step solved, and Chipmunk solves an arbiter only
    when it has contact points: any arbiter is a contact (reading the points costs ~10 us each)."""
    found: list[bool] = []
    robot.body.each_arbiter(lambda arbiter: found.append(True))
    return bool(found)


class RobotTask:
    """One robot's view of the navigation task inside a running simulation.

    Call :meth:`start` after the simulation is (re)built, :meth:`act` before the physics
    advances and :meth:`observe` / :meth:`outcome` after.
    """

    def __init__(self, robot_config, weights: RewardWeights,
                 pose_source: str = "ground_truth") -> None:
        if pose_source not in ("ground_truth", "odometry"):
            raise ValueError(f"pose_source must be 'ground_truth' or 'odometry' (got {pose_source!r})")
        self.name = robot_config.name
        self.weights = weights
        self.pose_source = pose_source
        self.holonomic = getattr(robot_config, "drive", "diff") == "omni"
        self.beams = robot_config.lidar.beams
        self.max_range = robot_config.lidar.max_range  # [m]
        self.action_size = action_size(self.holonomic)
        self.obs_size = observation_size(self.beams, self.holonomic)
        self.robot: Robot | None = None  # bound by start()
        self.radius = 0.0  # [m] the robot's, from start()
        self._lidar: Any = None  # the robot's LiDAR, from start()
        self.scale: ActionScale | None = None  # the robot's limits, from start()
        self.builder: ObservationBuilder | None = None
        self.previous = np.zeros((1, self.action_size))  # the last clipped action
        self.contact_time = 0.0  # [s] in contact this episode
        self._distance = 0.0  # [m] to the goal at the last observation
        self._collisions = 0
        self._start_collisions = 0

    @property
    def v_max(self) -> float:
        """Forward speed [m/s] an action of 1 commands."""
        return self._scale().v_max

    @property
    def omega_max(self) -> float:
        """Yaw rate [rad/s] an action of 1 commands."""
        return self._scale().omega_max

    def _scale(self) -> ActionScale:
        if self.scale is None:
            raise RuntimeError(f"the task of robot '{self.name}' has not started: call start()")
        return self.scale

    def obs_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) of the observation (float32)."""
        return observation_bounds(self.beams, self.holonomic)

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

    @property
    def start_collisions(self) -> int:
        """Contact episodes counted when the episode started."""
        return self._start_collisions

    @property
    def contact_free(self) -> bool:
        """No contact so far this episode."""
        return self.contact_time == 0.0 and self._collisions == self._start_collisions

    def remember(self, distance: float, collisions: int, contact_time: float) -> None:
        """What the step just observed [m, episodes, s], for the next step's progress and
        contacts (:func:`outcomes` tells each task)."""
        self._distance, self._collisions, self.contact_time = distance, collisions, contact_time

    def start(self, robot: Robot) -> None:
        """Bind to the (re)built robot and remember where the episode starts."""
        self.robot = robot
        self.radius = robot.radius  # [m] of the disc holding its footprint
        self._lidar = robot.lidar  # read every step: the handle's lookup once per episode
        self.scale = ActionScale.of(robot.spec)
        angles = robot.lidar.angles
        if self.builder is None or not np.array_equal(self.builder.angles, angles):
            self.builder = ObservationBuilder(angles, self.max_range, self.holonomic)
        self.previous[:] = 0.0
        self.contact_time = 0.0
        self._distance = self.goal_distance()
        self._collisions = self._start_collisions = robot.collisions

    def act(self, action: Any) -> None:
        """Command the normalised body velocity (clipped to [-1, 1])."""
        assert self.scale is not None, "call start() first"
        self.command(self.scale.clipped(action))

    def command(self, a: Sequence[float]) -> None:
        """Command a checked, clipped normalised action (``action_size`` floats in [-1, 1])."""
        assert self.scale is not None, "call start() first"
        self.previous[0] = a
        self.bound().command(self.scale.command(a))

    def stop(self) -> None:
        """Hold still (an agent whose episode is over stays in the world as an obstacle)."""
        self.bound().command(STOP)

    def pose(self) -> tuple[float, float, float]:
        """(x, y, theta) the task sees [m, m, rad]: the truth, or the odometry estimate."""
        robot = self.bound()
        if self.pose_source == "ground_truth":
            body = robot.body
            x, y = body.position
            return x, y, body.angle
        x, y, theta = robot.odometry.pose.tolist()
        return x, y, theta

    def where(self) -> Where:
        """(x, y, theta) the task sees and the goal (x, y), read once [m, m, rad, m, m]."""
        x, y, theta = self.pose()
        gx, gy = self.goal()
        return x, y, theta, gx, gy

    def goal_distance(self) -> float:
        """Distance from the pose the task sees to the goal [m]."""
        return goal_features(*self.where())[0]

    def ranges(self) -> np.ndarray:
        """The latest LiDAR ranges [m] (one scan per control period)."""
        self.bound()
        return self._lidar.latest.ranges

    def observe(self, out: np.ndarray | None = None, where: Where | None = None) -> np.ndarray:
        """The observation (:mod:`pymunk_bot.policy_io`), written into ``out`` if given;
        ``where``: :meth:`where`, if already read this step."""
        assert self.builder is not None, "call start() first"
        obs = np.empty(self.obs_size, dtype=np.float32) if out is None else out
        features = goal_features(*(self.where() if where is None else where))
        self.builder.fill(obs[None], self.ranges()[None], [features], self.previous)
        return obs

    def outcome(self, elapsed: float, terminate_on_collision: bool = False,
                where: Where | None = None) -> tuple[float, bool, dict]:
        """(reward, terminated, info) for the control step just taken (``elapsed`` seconds);
        ``where``: :meth:`where`, if already read this step."""
        robot = self.bound()
        distance = goal_features(*(self.where() if where is None else where))[0]
        collisions = robot.collisions
        new_collisions = collisions - self._collisions
        contact = elapsed if (new_collisions > 0 or touching(robot)) else 0.0
        clearance = float(self.ranges().min()) - robot.radius
        reached = robot.goal_reached
        progress = self._distance - distance
        self.remember(distance, collisions, self.contact_time + contact)
        success = reached and self.contact_free
        reward = _reward(self.weights, progress, new_collisions, contact, clearance, elapsed,
                         success)
        info = {"distance_to_goal": distance, "collisions": collisions,
                "new_collisions": new_collisions, "contact_time": self.contact_time,
                "clearance": clearance, "goal_reached": reached, "is_success": success}
        return float(reward), bool(reached or (terminate_on_collision and contact > 0)), info


def _reward(w: RewardWeights, progress: Any, new_collisions: Any, contact: Any, clearance: Any,
            elapsed: float, success: Any) -> Any:
    """The reward of a control step, for one robot (floats) or many (arrays), the same floats:
    progress toward the goal [m], new contact episodes, seconds in contact, clearance [m],
    time [s] and contact-free arrival."""
    crowding = np.minimum(1.0, np.maximum(0.0, 1.0 - clearance / w.clearance_margin))
    return (w.progress * progress + w.collision * new_collisions + w.contact * contact
            + w.clearance * elapsed * crowding + w.time * elapsed + w.success * success)


def outcomes(tasks: list[RobotTask], states: dict[str, np.ndarray], elapsed: float,
             terminate_on_collision: bool, obs: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """:meth:`RobotTask.outcome` and :meth:`RobotTask.observe` for many tasks of one scenario
    at once (ground-truth pose), from their robots' states (``Replicas.robot_states``):
    (rewards, terminated, info arrays), each row of ``obs`` written. The same floats as task
    by task."""
    first, w = tasks[0], tasks[0].weights
    assert first.builder is not None, "call start() first"
    goals = [goal_features(x, y, t, gx, gy) for x, y, t, gx, gy in zip(
        states["x"].tolist(), states["y"].tolist(), states["theta"].tolist(),
        states["goal_x"].tolist(), states["goal_y"].tolist())]
    distance = np.array([g[0] for g in goals])
    collisions, reached = states["collisions"], states["reached"]
    before = np.array([(task.last_distance, task.last_collisions, task.contact_time,
                        task.start_collisions) for task in tasks]).reshape(-1, 4)
    new_collisions = collisions - before[:, 1].astype(np.int64)
    hit = (new_collisions > 0) | np.array([touching(task.bound()) for task in tasks])
    contact = np.where(hit, elapsed, 0.0)
    ranges = np.stack([task.ranges() for task in tasks])
    radius = np.array([task.radius for task in tasks])
    clearance = ranges.min(axis=1) - radius
    contact_time = before[:, 2] + contact
    success = reached & (contact_time == 0.0) & (collisions == before[:, 3])
    rewards = _reward(w, before[:, 0] - distance, new_collisions, contact, clearance, elapsed,
                      success)
    terminated = reached | (terminate_on_collision & (contact > 0))
    for task, d, c, t in zip(tasks, distance.tolist(), collisions.tolist(),
                             contact_time.tolist()):
        task.remember(d, c, t)
    previous = np.concatenate([task.previous for task in tasks])
    first.builder.fill(obs, ranges, goals, previous)
    info = {"distance_to_goal": distance, "collisions": collisions,
            "new_collisions": new_collisions, "contact_time": contact_time,
            "clearance": clearance, "goal_reached": reached, "is_success": success}
    return rewards, terminated, info
