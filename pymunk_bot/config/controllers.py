"""Controller sections (`controller: {type: ...}`), one model per controller type.

docs/navigation.md lists every key with its unit and default; keep the two in step.
"""
from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator, Field, PrivateAttr, ValidationInfo, field_serializer, model_validator,
)

from pymunk_bot.config.class_path import check_class_path
from pymunk_bot.config.guidance import PlanGuidanceConfig
from pymunk_bot.config.types import (
    MAX_WAYPOINTS, Accel, Distance, Duration, Float, Gain, NonNegativeFloat, PositiveFloat,
    PositiveInt, PositiveShort, Rate, Section, Short, Speed, Vec2,
)


class _DrivingConfig(Section):
    """Keys every path- or goal-driving controller shares."""

    rate: Rate = 10.0  # [Hz]
    max_speed: Speed | None = None  # [m/s]; None = the robot's max wheel speed
    tolerance: Distance | None = None  # [m] stop radius; None = the goal's tolerance


class _GoalConfig(_DrivingConfig):
    goal: Vec2 | None = None  # [m]; None = the robot's goal


class WheelsControllerConfig(Section):
    """Constant wheel speeds."""

    type: Literal["wheels"]
    left: Annotated[Float, Field(ge=-100, le=100)] = 0.0  # [m/s]
    right: Annotated[Float, Field(ge=-100, le=100)] = 0.0  # [m/s]
    rate: Rate = 10.0  # [Hz]


class VelocityControllerConfig(Section):
    """A constant body velocity, for any drive."""

    type: Literal["velocity"]
    v: Float = 0.0  # forward [m/s]
    omega: Float = 0.0  # yaw rate [rad/s]
    vy: Float = 0.0  # lateral [m/s], omni drives only
    rate: PositiveFloat = 10.0  # [Hz]


class GoToGoalControllerConfig(_GoalConfig):
    """Proportional steering toward a point: v = k_rho * distance, omega = k_alpha * bearing."""

    type: Literal["go_to_goal"]
    k_rho: Annotated[PositiveFloat, Field(le=1e3)] = 1.0  # [1/s]
    k_alpha: Annotated[PositiveFloat, Field(le=1e3)] = 3.0  # [1/s]


class PursuitConfig(Section):
    """Pure-pursuit path following, shared by ``waypoints`` and ``navigate``."""

    lookahead: PositiveShort = 0.6  # [m] steering point ahead, full speed
    lookahead_time: PositiveShort = 0.4  # [s] lookahead = speed * this (0.2 m to ``lookahead``)
    corner_radius: Short = 0.5  # [m] corners are rounded with arcs up to this radius
    lateral_accel: Accel = 0.6  # [m/s^2] on bends: speed <= sqrt(lateral_accel * radius)
    decel: Accel = 1.0  # [m/s^2] planned braking before bends and the end
    rotate_threshold: Annotated[PositiveFloat, Field(le=3.1416)] = 1.2  # [rad] turn on the spot
    # Omni robots only: "path" turns to face along the path, "keep" holds the heading it had
    # when it started and slides (e.g. to keep facing a shelf).
    heading: Literal["path", "keep"] = "path"


class WaypointsControllerConfig(_DrivingConfig):
    """Follow a polyline of points with pure pursuit; ``loop`` patrols it forever.

    ``tolerance`` is the stop radius at the last point."""

    type: Literal["waypoints"]
    points: list[Vec2] = Field(min_length=1, max_length=MAX_WAYPOINTS)  # [m]
    loop: bool = False
    pursuit: PursuitConfig = PursuitConfig()
    give_up_after: Duration = 20.0  # [s] without progress along the points: fail


class DwaConfig(Section):
    """Dynamic Window Approach (Fox et al. 1997) tuning, shared by ``avoid`` and ``navigate``."""

    horizon: Annotated[PositiveShort, Field(le=10)] = 1.5  # [s] each arc is simulated this far
    time_samples: Annotated[PositiveInt, Field(le=100)] = 12  # collision checks along each arc
    v_samples: Annotated[PositiveInt, Field(ge=2, le=50)] = 7  # forward speeds tried per tick
    w_samples: Annotated[PositiveInt, Field(ge=2, le=100)] = 15  # turn rates tried per tick
    safety: Annotated[Short, Field(le=10)] = 0.1  # [m] clearance below this counts as a collision
    heading_weight: Gain = 0.4  # facing the target at the end of the arc
    progress_weight: Gain = 1.0  # getting closer to the target along the arc
    clearance_weight: Gain = 0.5  # closest approach on the arc (up to the cap)
    speed_weight: Gain = 0.2  # driving fast
    clearance_cap: PositiveShort = 0.4  # [m] more clearance scores no better
    allow_reverse: bool = False  # back away slowly when closer than ``safety`` to something


class AvoidControllerConfig(_GoalConfig):
    """Reactive obstacle avoidance from the LiDAR toward a goal (Dynamic Window Approach)."""

    type: Literal["avoid"]
    dwa: DwaConfig = DwaConfig()
    give_up_after: Duration = 30.0  # [s] without getting closer to the goal: fail


class HybridConfig(Section):
    """Hybrid A* settings, used when a car-like (ackermann) robot navigates."""

    step: Annotated[PositiveFloat, Field(ge=0.02, le=2.0)] = 0.2  # [m] arc length per expansion
    heading_bins: Annotated[PositiveInt, Field(ge=8, le=360)] = 72  # heading cells per turn
    reverse: bool = True  # may back up
    reverse_cost: Annotated[PositiveFloat, Field(ge=1.0)] = 1.5  # per metre, relative to forward
    switch_cost: NonNegativeFloat = 1.0  # [m] added at each change of direction
    max_expansions: Annotated[PositiveInt, Field(le=1_000_000)] = 40000  # then it gives up
    disc_spacing: Annotated[PositiveFloat, Field(ge=0.02)] = 0.15  # [m] between footprint discs


class NavigateControllerConfig(_GoalConfig):
    """Global A* on the scenario's map plus a local controller that follows the path."""

    type: Literal["navigate"]
    resolution: Annotated[Distance, Field(ge=0.01, le=10)] = 0.1  # [m] planning grid cell size
    margin: Short = 0.25  # [m] clearance beyond the radius that paths try to keep
    hard_margin: Short = 0.02  # [m] beyond the radius: closer cells are blocked
    clearance_cost: Gain = 4.0  # extra cost per metre next to an obstacle
    map_movable: bool = False  # plan around movable obstacles at their starting places
    lookahead: PositiveShort = 0.6  # [m] steering point ahead on the path
    stuck_time: Duration = 3.0  # [s] without progress along the path before a replan
    # [s] of failed replans (blocked by unmapped things), or without progress along any path
    give_up_after: Duration = 10.0
    # Final heading [rad] a car must arrive with (parking); None: any. Ackermann only.
    heading: Float | None = None
    heading_tolerance: Annotated[PositiveFloat, Field(le=3.1416)] = 0.2  # [rad]
    pursuit: PursuitConfig = PursuitConfig()
    dwa: DwaConfig = DwaConfig()
    hybrid: HybridConfig = HybridConfig()


class _CrowdConfig(_GoalConfig):
    """Keys the crowd-navigation baselines share (controllers/crowd_nav.py)."""

    resolution: Annotated[Distance, Field(ge=0.01, le=10)] = 0.1  # [m] planning grid cell size
    margin: Short = 0.1  # [m] beyond the radius: kept from obstacles (plan and avoidance)
    lookahead: PositiveShort = 1.0  # [m] steering point ahead on the path


class SocialForceControllerConfig(_CrowdConfig):
    """A social force robot (Helbing & Molnar 1995) following its global path."""

    type: Literal["social_force"]
    relaxation_time: PositiveShort = 0.5  # tau [s]: how fast it reaches its wished velocity
    # A and B of Helbing, Farkas & Vicsek 2000 (2000 N and 0.08 m for an 80 kg person)
    strength: Gain = 25.0  # A [m/s^2]: repulsion of an obstacle point at the margin
    range: PositiveShort = 0.08  # B [m]: how fast the repulsion decays with distance
    anticipation: Short = 1.0  # [s] a moving point repels from where it will be this soon


class OrcaControllerConfig(_CrowdConfig):
    """A LiDAR-based ORCA robot (van den Berg et al. 2011) following its global path; not
    CrowdNav's ORCA (that is ``crowdnav_orca``)."""

    type: Literal["orca"]
    time_horizon: PositiveShort = 3.0  # [s] moving points may not be met within this
    obstacle_time_horizon: PositiveShort = 1.0  # [s] static points may not be met within this


_CLASS_PATH = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_][\w.]*$")


def _importable(value: str, info: ValidationInfo) -> str:
    if not _CLASS_PATH.match(value):
        raise ValueError(f"must be 'package.module:ClassName' (got {value!r})")
    check_class_path(value, (info.context or {}).get("base_dir"))  # runs no user code
    return value


class PythonControllerConfig(Section):
    """A user's own controller class, imported from ``class_path`` ('package.module:Class')."""

    type: Literal["python"]
    class_path: Annotated[str, AfterValidator(_importable)]
    params: dict[str, Any] = {}  # keyword arguments for the class's constructor
    rate: Rate | None = None  # [Hz]; None = the class's own ``rate`` (default 10)
    goal: Vec2 | None = None  # [m]; None = the robot's goal
    # The scenario file's folder, where ``class_path`` is looked for first (not a YAML key).
    _base_dir: str | None = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _remember_base_dir(self, info: ValidationInfo) -> "PythonControllerConfig":
        self._base_dir = (info.context or {}).get("base_dir")
        return self

    @property
    def base_dir(self) -> str | None:
        """The scenario file's folder (None for data not read from a file)."""
        return self._base_dir


def _policy_file(value: str, info: ValidationInfo) -> str:
    """The policy file loads (relative paths from the scenario's folder); its size against
    the robot's LiDAR is checked when the controller is built."""
    from pymunk_bot.policy.files import PolicyFileError, load_policy

    try:
        load_policy(resolve_policy_path(value, (info.context or {}).get("base_dir")))
    except PolicyFileError as exc:
        raise ValueError(f"'{value}': {exc}") from None
    return value


def resolve_policy_path(path: str, base_dir: str | None) -> str:
    """``path`` as given if absolute, else relative to the scenario file's folder (the current
    folder for a scenario not read from a file)."""
    from pathlib import Path

    file = Path(path).expanduser()
    return str(file if file.is_absolute() or base_dir is None else Path(base_dir) / file)


class PolicyControllerConfig(Section):
    """A trained policy (``.npz`` MLP or ``.onnx``) seeing what ``pymunk_bot/Navigation-v0``
    shows it (pymunk_bot/policy/io.py) and driving as the env scales its action."""

    type: Literal["policy"]
    path: Annotated[str, AfterValidator(_policy_file)]
    rate: Rate = 10.0  # [Hz]; the env's control period is 1 / rate (0.1 s by default)
    goal: Vec2 | None = None  # [m]; None = the robot's goal
    tolerance: Distance | None = None  # [m] stop radius; None = the goal's tolerance
    give_up_after: Duration = 20.0  # [s] without getting closer to the goal: fail
    # None: as the policy file records; true: on (the file's settings, or the defaults);
    # false: off; a mapping: on with these settings (PlanGuidanceConfig)
    plan_guidance: PlanGuidanceConfig | bool | None = None
    # None: as the policy file records (an ONNX file: lidar); lidar; crowd_state (the nearest
    # humans' true states, pymunk_bot/policy/crowd_io.py: the robot needs crowd_state)
    observation: Literal["lidar", "crowd_state"] | None = None
    _base_dir: str | None = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _remember_base_dir(self, info: ValidationInfo) -> "PolicyControllerConfig":
        self._base_dir = (info.context or {}).get("base_dir")
        return self

    @property
    def resolved_path(self) -> str:
        """The policy file's path (relative paths from the scenario file's folder)."""
        return resolve_policy_path(self.path, self._base_dir)

    @field_serializer("path")
    def _dump_resolved(self, path: str) -> str:
        """Dumped as the resolved path, so the data parses back to the same file from any
        folder (as ``world.map`` is: config.scenario_data)."""
        return self.resolved_path

    def misfit(self, robot) -> str | None:
        """Why this policy cannot drive ``robot`` (a robot config), or None: it needs a LiDAR
        and a goal, takes the observation of the robot's beams and gives its action."""
        from pymunk_bot.policy.files import (
            PolicyFileError, check_runs_on, guidance_for, load_policy, observation_for,
        )
        from pymunk_bot.policy.io import action_size, observation_size

        if self.goal is None and robot.goal is None:
            return "policy needs a goal: set controller.goal or the robot's goal"
        holonomic = getattr(robot, "drive", "diff") == "omni"
        outputs = action_size(holonomic)
        try:
            policy = load_policy(self.resolved_path)
        except PolicyFileError as exc:
            return f"'{self.path}': {exc}"
        try:
            observation = observation_for(policy, self.observation)
        except PolicyFileError as exc:
            return f"'{self.path}' {exc}"
        if observation == "crowd_state":
            return self._crowd_misfit(policy, robot, holonomic, outputs)
        if robot.lidar is None:
            return "a policy sees the LiDAR: add a 'lidar' to the robot"
        inputs = observation_size(robot.lidar.beams, holonomic)
        if policy.inputs is not None and policy.inputs != inputs:
            return (f"'{self.path}' takes {policy.inputs} inputs, but a robot with "
                    f"{robot.lidar.beams} LiDAR beams gives {inputs} (beams + "
                    f"{inputs - robot.lidar.beams}): was it trained with another LiDAR?")
        if policy.outputs is not None and policy.outputs != outputs:
            return f"'{self.path}' gives {policy.outputs} outputs; a {robot.drive} drive takes {outputs}"
        try:
            check_runs_on(policy, inputs, outputs)
        except PolicyFileError as exc:
            return f"'{self.path}', for a robot with {robot.lidar.beams} LiDAR beams: {exc}"
        try:
            guidance_for(policy, self.plan_guidance)
        except PolicyFileError as exc:
            return f"'{self.path}' {exc}"
        return None

    def _crowd_misfit(self, policy, robot, holonomic: bool, outputs: int) -> str | None:
        """Why a policy on the crowd_state observation cannot drive ``robot``, or None."""
        from pymunk_bot.policy.crowd_io import crowd_observation_size, humans_of
        from pymunk_bot.policy.files import PolicyFileError, check_runs_on

        sensor = getattr(robot, "crowd_state", None)
        if sensor is None:
            return (f"'{self.path}' sees the crowd_state observation (the humans' true "
                    "states): add 'crowd_state: {}' to the robot")
        humans = policy.crowd_humans or humans_of(policy.inputs, holonomic)
        if humans is None:
            return (f"'{self.path}' takes {policy.inputs} inputs: no crowd_state observation "
                    f"of a {robot.drive} drive has that size")
        if sensor.max_humans < humans:
            return (f"'{self.path}' sees the {humans} nearest humans, but the robot's "
                    f"crowd_state.max_humans is {sensor.max_humans}")
        if self.plan_guidance:
            return f"'{self.path}' sees the crowd_state observation: plan_guidance does not apply"
        inputs = crowd_observation_size(humans, holonomic)
        if policy.inputs is not None and policy.inputs != inputs:
            return (f"'{self.path}' takes {policy.inputs} inputs, but the crowd_state "
                    f"observation of {humans} humans for a {robot.drive} drive has {inputs}")
        if policy.outputs is not None and policy.outputs != outputs:
            return f"'{self.path}' gives {policy.outputs} outputs; a {robot.drive} drive takes {outputs}"
        try:
            check_runs_on(policy, inputs, outputs)
        except PolicyFileError as exc:
            return f"'{self.path}': {exc}"
        return None

    def guidance(self) -> "PlanGuidanceConfig | None":
        """The plan guidance this policy runs with (the scenario's key, else
        what the file records); None for a file that cannot be read (:meth:`misfit` says)."""
        from pymunk_bot.policy.files import PolicyFileError, guidance_for, load_policy

        try:
            return guidance_for(load_policy(self.resolved_path), self.plan_guidance)
        except PolicyFileError:
            return None


class CrowdNavOrcaControllerConfig(Section):
    """CrowdNav's ORCA robot policy (Chen et al. 2019's baseline, crowd_sim/envs/policy/orca.py
    of vita-epfl/CrowdNav): reciprocal ORCA against the pedestrians' true states, read from the
    robot's ``crowd_state`` sensor. The defaults are CrowdNav's."""

    type: Literal["crowdnav_orca"]
    rate: Rate = 4.0  # [Hz]: CrowdNav's time step, 0.25 s
    max_speed: Speed | None = None  # [m/s]; None = the robot's (CrowdNav's v_pref, 1 m/s)
    time_horizon: PositiveShort = 5.0  # [s] no pedestrian may be met within this
    neighbor_distance: Annotated[PositiveFloat, Field(le=100.0)] = 10.0  # [m] who counts
    max_neighbors: Annotated[PositiveInt, Field(le=64)] = 10  # the nearest this many
    safety_space: Annotated[NonNegativeFloat, Field(le=1.0)] = 0.0  # [m] added to its radius
    radius_margin: Annotated[NonNegativeFloat, Field(le=1.0)] = 0.01  # [m] added to every radius
    share: Annotated[Float, Field(gt=0.0, le=1.0)] = 0.5  # of the avoidance it takes (0.5:
    # reciprocal, it assumes the pedestrians take the other half, as CrowdNav's does)
    goal: Vec2 | None = None  # [m]; None = the robot's goal
