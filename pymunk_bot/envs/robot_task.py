"""One robot's view of the navigation task: its action, observation and reward, written once
(:func:`outcomes`) for one robot (:meth:`RobotTask.outcome`) or many of one scenario at once.

The observation and the action scaling are :mod:`pymunk_bot.policy.io`'s (the ``policy``
controller uses them too); the reward is :class:`~pymunk_bot.envs.task.RewardWeights`'. With
plan guidance the observation's goal features come from :class:`~pymunk_bot.planning.guidance.
PlanGuide` (as the controller's do), and so does the reward's progress term: progress along
the path (the guided distance: to the lookahead point plus the path beyond it), not the straight
line, which would punish heading for a door. ``distance_to_goal``, arrival and termination keep
the final goal's. With ``observation="crowd_state"`` the observation is
:mod:`pymunk_bot.policy.crowd_io`'s (the humans' true states, no LiDAR) and the reward's
clearance is the gap to the nearest human's body, what that observation sees.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from pymunk_bot.config.guidance import PlanGuidanceConfig
from pymunk_bot.planning.guidance import PlanGuide
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.robots.command import STOP
from pymunk_bot.policy.crowd_io import (
    OBSERVATIONS, CrowdObservationBuilder, crowd_observation_bounds, crowd_observation_size,
    nearest_gap,
)
from pymunk_bot.policy.io import (
    ActionScale, ObservationBuilder, action_size, goal_features, observation_bounds,
    observation_size,
)
from pymunk_bot.envs.step_rows import step_rows
from pymunk_bot.envs.task import RewardWeights

if TYPE_CHECKING:
    from pymunk_bot.robots.robot import Robot

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
                 pose_source: str = "ground_truth",
                 plan_guidance: PlanGuidanceConfig | None = None,
                 control_period: float = 0.1, observation: str = "lidar") -> None:
        """``plan_guidance``: goal features along a path (planned on the map :meth:`start`
        is given); ``control_period`` [s] between observations (counts its replan period);
        ``observation``: "lidar" (:mod:`pymunk_bot.policy.io`) or "crowd_state"
        (:mod:`pymunk_bot.policy.crowd_io`, needs the robot's ``crowd_state`` sensor)."""
        if pose_source not in ("ground_truth", "odometry"):
            raise ValueError(f"pose_source must be 'ground_truth' or 'odometry' (got {pose_source!r})")
        if observation not in OBSERVATIONS:
            raise ValueError(f"observation must be one of {OBSERVATIONS} (got {observation!r:.60})")
        crowd_config = getattr(robot_config, "crowd_state", None)
        if observation == "crowd_state":
            if crowd_config is None:
                raise ValueError(f"observation='crowd_state' reads robot '{robot_config.name}''s "
                                 "crowd_state sensor: add `crowd_state: {}` to the robot")
            if plan_guidance is not None:
                raise ValueError("plan_guidance shapes the LiDAR observation's goal features: "
                                 "it does not apply to observation='crowd_state'")
        self.observation = observation
        # humans of the crowd observation (0: the LiDAR observation)
        self.humans = 0 if crowd_config is None or observation == "lidar" \
            else int(crowd_config.max_humans)
        self.name = robot_config.name
        self.weights = weights
        self.weight_row = weights.as_array()  # what step_rows reads
        self.pose_source = pose_source
        self.holonomic = getattr(robot_config, "drive", "diff") == "omni"
        self.beams = robot_config.lidar.beams
        self.max_range = robot_config.lidar.max_range  # [m]
        self.action_size = action_size(self.holonomic)
        self.obs_size = (observation_size(self.beams, self.holonomic) if not self.humans
                         else crowd_observation_size(self.humans, self.holonomic))
        self.robot: Robot | None = None  # bound by start()
        self.radius = 0.0  # [m] the robot's, from start()
        self._lidar: Any = None  # the robot's LiDAR, from start()
        self.scale: ActionScale | None = None  # the robot's limits, from start()
        self.builder: ObservationBuilder | None = None
        self.crowd_builder: CrowdObservationBuilder | None = None  # crowd_state observation
        self._crowd: Any = None  # the robot's crowd_state sensor, from start()
        self.previous = np.zeros((1, self.action_size))  # the last clipped action
        self.contact_time = 0.0  # [s] in contact this episode
        self._distance = 0.0  # [m] to the (guided) goal at the last observation
        self._collisions = 0
        self._start_collisions = 0
        self.plan_guidance = plan_guidance
        self.guide = None if plan_guidance is None else PlanGuide(
            plan_guidance, float(robot_config.radius), control_period)

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
        if self.humans:
            return crowd_observation_bounds(self.humans, self.holonomic)
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
        """Distance [m] to the goal at the last observation, along the path with plan guidance
        (progress is measured from it)."""
        return self._distance

    @property
    def last_collisions(self) -> int:
        """Contact episodes counted at the last observation."""
        return self._collisions

    @property
    def start_collisions(self) -> int:
        """Contact episodes counted when the episode started."""
        return self._start_collisions

    def remember(self, distance: float, collisions: int, contact_time: float) -> None:
        """What the step just observed [m, episodes, s], for the next step's progress and
        contacts (:func:`outcomes` tells each task)."""
        self._distance, self._collisions, self.contact_time = distance, collisions, contact_time

    def start(self, robot: Robot, world_map: MapInfo | None = None) -> None:
        """Bind to the (re)built robot and remember where the episode starts; ``world_map``:
        what plan guidance plans on (needed with it)."""
        if self.guide is not None:
            if world_map is None:
                raise ValueError(f"robot '{self.name}' has plan guidance: start() needs the "
                                 "map to plan on")
            self.guide.set_map(world_map)
            self.guide.restart()
        self.robot = robot
        self.radius = robot.radius  # [m] of the disc holding its footprint
        self._lidar = robot.lidar  # read every step: the handle's lookup once per episode
        self.scale = ActionScale.of(robot.spec)
        angles = robot.lidar.angles
        if self.builder is None or not np.array_equal(self.builder.angles, angles):
            self.builder = ObservationBuilder(angles, self.max_range, self.holonomic)
        if self.humans:
            self._crowd = robot.sensor("crowd_state")
            if self._crowd is None:  # a drawn scenario whose robot lost the sensor
                raise ValueError(f"observation='crowd_state': robot '{self.name}' has no "
                                 "crowd_state sensor")
            self.crowd_builder = CrowdObservationBuilder(self.humans, self.scale, self.radius)
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
        ranges = self._lidar.ranges
        assert ranges is not None  # a scan is taken at the start of every episode
        return ranges

    def clearance_ranges(self) -> np.ndarray:
        """What the reward's clearance is measured from [m]: the LiDAR ranges, or with the
        crowd observation the distance from the robot's centre to the nearest human's body
        (inf with none in sight), one number."""
        if not self.humans:
            return self.ranges()
        x, y, _ = self.pose()
        return np.array([nearest_gap((x, y), 0.0, self._crowd.reading)])

    def observe(self, out: np.ndarray | None = None, where: Where | None = None) -> np.ndarray:
        """The observation (:mod:`pymunk_bot.policy.io`, or :mod:`pymunk_bot.policy.crowd_io`
        with ``observation="crowd_state"``), written into ``out`` if given; ``where``:
        :meth:`where`, if already read this step."""
        assert self.builder is not None, "call start() first"
        obs = np.empty(self.obs_size, dtype=np.float32) if out is None else out
        where = self.where() if where is None else where
        features = self.goal_seen(where, goal_features(*where))
        if self.guide is not None:  # progress is measured along the path from here
            self._distance = features[0]
        if self.crowd_builder is not None:
            self.fill_crowd(obs, where, features)
        else:
            self.builder.fill(obs[None], self.ranges()[None], [features], self.previous)
        return obs

    def fill_crowd(self, out: np.ndarray, where: Sequence[float],
                   features: tuple[float, float, float]) -> None:
        """Write the crowd observation into ``out`` (one row) from the pose and goal features
        the task sees (``where``: x, y, theta first) and the crowd_state sensor's reading
        now."""
        assert self.crowd_builder is not None, "the crowd observation: call start() first"
        self.crowd_builder.fill(out, where[:3], features, self.previous, self._crowd.reading)

    def goal_seen(self, where: Where, features: tuple[float, float, float]
                  ) -> tuple[float, float, float]:
        """The goal features the observation shows: the final goal's ``features``, or with
        plan guidance the guided goal's (call once per observation: it counts them)."""
        if self.guide is None:
            return features
        self.bound()
        return self.guide.features(*where, self._lidar.latest)

    def state(self, where: Where | None = None) -> dict[str, np.ndarray]:
        """The robot's state as :func:`outcomes` reads it (``Replicas.robot_states``' keys), one
        row: the pose the task sees, its goal, contact episodes, goal reached; ``where``:
        :meth:`where`, if already read this step."""
        x, y, theta, gx, gy = self.where() if where is None else where
        robot = self.bound()
        return {"x": np.array([x]), "y": np.array([y]), "theta": np.array([theta]),
                "goal_x": np.array([gx]), "goal_y": np.array([gy]),
                "collisions": np.array([robot.collisions], dtype=np.int64),
                "reached": np.array([robot.goal_reached])}

    def outcome(self, elapsed: float, terminate_on_collision: bool = False,
                where: Where | None = None, obs: np.ndarray | None = None
                ) -> tuple[float, bool, dict]:
        """(reward, terminated, info) for the control step just taken (``elapsed`` seconds),
        by :func:`outcomes` (the one implementation, for one robot as for many); ``where``:
        :meth:`where`, if already read this step; ``obs``: the observation is written here
        too (a row of the observation size)."""
        rewards, terminated, info = outcomes([self], self.state(where), elapsed,
                                             terminate_on_collision,
                                             None if obs is None else obs[None])
        return (float(rewards[0]), bool(terminated[0]),
                {key: value[0].item() for key, value in info.items()})


def outcomes(tasks: list[RobotTask], states: dict[str, np.ndarray], elapsed: float,
             terminate_on_collision: bool, obs: np.ndarray | None
             ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """The reward, end and info of the control step just taken (``elapsed`` seconds) for
    tasks of one scenario, from their robots' states (``Replicas.robot_states``, or
    :meth:`RobotTask.state` for one): (rewards, terminated, info arrays); each row of ``obs``
    gets the task's observation (:meth:`RobotTask.observe`) if given."""
    first = tasks[0]
    assert first.builder is not None, "call start() first"
    goals = [goal_features(x, y, t, gx, gy) for x, y, t, gx, gy in zip(
        states["x"].tolist(), states["y"].tolist(), states["theta"].tolist(),
        states["goal_x"].tolist(), states["goal_y"].tolist())]
    distance = np.array([g[0] for g in goals])
    collisions, reached = states["collisions"], states["reached"]
    before = np.array([(task.last_distance, task.last_collisions, task.contact_time,
                        task.start_collisions) for task in tasks]).reshape(-1, 4)
    seen, along = goals, distance  # what the observation shows; what progress is measured on
    if first.guide is not None:  # once per step, observed or not: the guide counts steps
        seen = [task.goal_seen(where, features) for task, where, features in zip(
            tasks, zip(states["x"].tolist(), states["y"].tolist(),
                       states["theta"].tolist(), states["goal_x"].tolist(),
                       states["goal_y"].tolist()), goals)]
        along = np.array([g[0] for g in seen])
    # np.stack's own cost is 5 us
    ranges = np.array([task.clearance_ranges() for task in tasks])
    n = len(tasks)
    rewards, contact_time, clearance = np.empty(n), np.empty(n), np.empty(n)
    new_collisions = np.empty(n, dtype=np.int64)
    success, terminated = np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.bool_)
    step_rows(elapsed, terminate_on_collision, first.weight_row, along, collisions,
              before, np.array([touching(task.bound()) for task in tasks]), ranges,
              np.array([task.radius for task in tasks]), reached, rewards, new_collisions,
              contact_time, clearance, success, terminated)
    for task, d, c, t in zip(tasks, along.tolist(), collisions.tolist(),
                             contact_time.tolist()):
        task.remember(d, c, t)
    if obs is not None and first.crowd_builder is not None:
        for row, task, where, features in zip(obs, tasks, zip(
                states["x"].tolist(), states["y"].tolist(), states["theta"].tolist()), seen):
            task.fill_crowd(row, where, features)
    elif obs is not None:
        first.builder.fill(obs, ranges, seen, np.concatenate([task.previous for task in tasks]))
    info = {"distance_to_goal": distance, "collisions": collisions,
            "new_collisions": new_collisions, "contact_time": contact_time,
            "clearance": clearance, "goal_reached": reached, "is_success": success}
    return rewards, terminated, info
