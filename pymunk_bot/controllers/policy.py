"""``controller: {type: policy, path: nav.npz}``: a trained policy drives the robot.

At every tick (``rate``, 10 Hz by default: the env's 0.1 s control period) the policy sees the
observation ``pymunk_bot/Navigation-v0`` builds (:mod:`pymunk_bot.policy.io`: the latest LiDAR
scan, the goal from the pose estimate, its previous action) and its action is scaled as the env
scales it. Give the robot ``localization: ground_truth`` to see the pose the env shows by
default (``pose_source="ground_truth"``); with the default odometry it sees what the env shows
with ``pose_source="odometry"``. Within the stop radius of the goal it stops ("arrived").

A policy that returns a NaN or infinite action, or gets no closer to the goal for
``give_up_after`` seconds, fails the run (status "failed", the reason in the result's
``controller_message``); a file that cannot drive the robot (missing, malformed,
the wrong input size for the robot's LiDAR) is refused when the scenario is checked.

With ``plan_guidance`` (or a policy file that records it) the goal the policy sees is a point
along an A* path on the scenario's map (:mod:`pymunk_bot.planning.guidance`), exactly as the
env computes it with the same setting; arriving and giving up still measure the final goal.

A policy file that records the ``crowd_state`` observation (or ``observation: crowd_state``
for an ONNX file) sees the nearest humans' true states instead of the LiDAR
(:mod:`pymunk_bot.policy.crowd_io`, as the env builds it with ``observation="crowd_state"``):
the robot needs the ``crowd_state`` sensor.
"""
from __future__ import annotations

import numpy as np

from pymunk_bot.config.controllers import PolicyControllerConfig
from pymunk_bot.planning.guidance import PlanGuide
from pymunk_bot.planning.map import MapInfo
from pymunk_bot.policy.crowd_io import CrowdObservationBuilder, humans_of
from pymunk_bot.policy.files import PolicyFileError, guidance_for, load_policy, observation_for
from pymunk_bot.policy.io import ActionScale, ObservationBuilder, goal_features
from pymunk_bot.controllers.base import STOP, Command, Controller, Observation, RobotSpec


class PolicyController(Controller):
    """Runs a policy file (``.npz`` MLP or ``.onnx``) on the env's observation."""

    def __init__(self, config: PolicyControllerConfig, robot: RobotSpec) -> None:
        super().__init__(config)
        self.rate = float(config.rate)
        self.path = config.path
        try:
            self.policy = load_policy(config.resolved_path)
            guidance = guidance_for(self.policy, config.plan_guidance)
            observation = observation_for(self.policy, config.observation)
        except PolicyFileError as exc:  # the file changed since the scenario was checked
            raise ValueError(f"policy '{config.path}': {exc}") from None
        # The scenario's map is given (set_map) only to a plan-guided policy.
        self.needs_map = guidance is not None
        self.guide = None if guidance is None else PlanGuide(guidance, robot.radius,
                                                             1.0 / self.rate)
        self.scale = ActionScale.of(robot)
        self.tolerance = config.tolerance  # [m]; None: the goal's
        self.previous = np.zeros((1, self.scale.size))  # the last clipped action
        self._builder: ObservationBuilder | None = None
        self._obs: np.ndarray | None = None
        self.crowd: CrowdObservationBuilder | None = None  # the crowd_state observation
        if observation == "crowd_state":
            humans = self.policy.crowd_humans or humans_of(self.policy.inputs,
                                                           self.scale.vy_max is not None)
            if humans is None:  # refused when the scenario is checked (misfit)
                raise ValueError(f"policy '{config.path}': its input size says no number of "
                                 "humans of the crowd_state observation")
            self.crowd = CrowdObservationBuilder(humans, self.scale, robot.radius)
            self._obs = np.empty((1, self.crowd.size), dtype=np.float32)

    def set_map(self, world_map: MapInfo) -> None:
        """Plan on the scenario's map (called when the policy is plan-guided)."""
        if self.guide is not None:
            self.guide.set_map(world_map)

    def compute(self, obs: Observation) -> Command:
        if self.status == "failed":
            return STOP
        if obs.goal is None or (obs.scan is None and self.crowd is None):
            return self._fail("a policy needs a goal, and a LiDAR scan unless it sees the "
                              "crowd_state observation")
        x, y, theta = obs.pose.tolist()
        features = goal_features(x, y, theta, obs.goal[0], obs.goal[1])
        tolerance = obs.goal_tolerance if self.tolerance is None else self.tolerance
        if features[0] <= tolerance:
            self.status, self.message = "arrived", ""
            return STOP
        if self.gave_up(obs, -float(features[0])):
            return STOP
        self.status = "running"
        if self.crowd is not None:
            return self._act_on_crowd(obs, features)
        assert obs.scan is not None  # checked above
        if self._builder is None or self._obs is None:
            self._builder = ObservationBuilder(obs.scan.angles, obs.scan.max_range,
                                               self.scale.vy_max is not None)
            self._obs = np.empty((1, self._builder.size), dtype=np.float32)
        if obs.scan.ranges.size != self._builder.beams:
            return self._fail(f"the scan has {obs.scan.ranges.size} beams, the policy was "
                              f"built for {self._builder.beams}")
        if self.guide is not None:  # the goal seen along the plan, as the env shows it
            features = self.guide.features(x, y, theta, obs.goal[0], obs.goal[1], obs.scan)
        self._builder.fill(self._obs, obs.scan.ranges[None], [features], self.previous)
        return self._act()

    def _act_on_crowd(self, obs: Observation, features: tuple[float, float, float]
                      ) -> Command:
        """The policy's command on the crowd_state observation."""
        assert self.crowd is not None and self._obs is not None
        crowd = obs.extra.get("crowd_state")
        if crowd is None:
            return self._fail("the policy sees the crowd_state observation: the robot needs "
                              "the crowd_state sensor")
        self.crowd.fill(self._obs[0], obs.pose.tolist(), features, self.previous, crowd)
        return self._act()

    def _act(self) -> Command:
        """The policy's command on the observation just written (``self._obs``)."""
        assert self._obs is not None
        try:
            action = self.policy.act(self._obs)[0]
        except PolicyFileError as exc:  # checked with the scenario; a model can still refuse
            return self._fail(f"policy '{self.path}': {exc}")
        try:
            clipped = self.scale.clipped(action)
        except ValueError:
            return self._fail(f"policy '{self.path}' returned {np.array2string(action)}: "
                              f"not {self.scale.size} finite numbers")
        self.previous[0] = clipped
        return self.scale.command(clipped)

    def _fail(self, reason: str) -> Command:
        self.status, self.message = "failed", reason
        return STOP
