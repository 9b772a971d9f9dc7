"""The extension points and what fills them: the built-ins, then third-party plugins.

Six registries: ``drives``, ``odometry`` (each drive kind's dead reckoning, under the drive's
name), ``obstacles``, ``sensors``, ``controllers``, ``localizers``. Each
entry is a factory (or a ``"module:attr"`` string, imported on first use, which keeps
``import pymunk_bot`` light) plus the pydantic model of its YAML section.

A third-party package adds entries through the entry-point group ``pymunk_bot.plugins``: each
entry point names a callable that is called once, with no arguments, and registers what it
brings, e.g. ``plugins.controllers.add("spiral", SpiralController, SpiralConfig)``.
"""
from __future__ import annotations

import importlib.metadata

from pymunk_bot.config.registry import Registry

ENTRY_POINT_GROUP = "pymunk_bot.plugins"

drives: Registry = Registry("drive")
# A drive kind's odometry: (drive group, one generator per robot) -> odometry group. Drives do
# not import sensors; the two meet here, by the drive's name.
odometry: Registry = Registry("odometry")
obstacles: Registry = Registry("obstacle type")
sensors: Registry = Registry("sensor")
controllers: Registry = Registry("controller")
localizers: Registry = Registry("localizer")

_loaded = False


def state() -> tuple[int, ...]:
    """Changes whenever any registry does (assembled schemas compare it)."""
    return tuple(r.version for r in (drives, odometry, obstacles, sensors, controllers, localizers))


def load() -> None:
    """Register the built-ins and every installed plugin (once per process)."""
    global _loaded
    if _loaded:
        return
    _loaded = True
    _register_builtins()
    load_entry_points()


def load_entry_points() -> list[str]:
    """Call every ``pymunk_bot.plugins`` entry point not loaded yet; returns their names.

    A plugin that fails to load is a bug in that plugin: the error says which one."""
    names = []
    for entry_point in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        if entry_point.name in _entry_points_loaded:
            continue
        _entry_points_loaded.add(entry_point.name)
        try:
            register = entry_point.load()
            register()
        except Exception as exc:
            raise RuntimeError(f"pymunk-bot plugin '{entry_point.name}' ({entry_point.value}) "
                               f"failed to load: {type(exc).__name__}: {exc}") from exc
        names.append(entry_point.name)
    return names


_entry_points_loaded: set[str] = set()


def _register_builtins() -> None:
    from pymunk_bot.config import controllers as c
    from pymunk_bot.config import drives as d
    from pymunk_bot.config import motion as m
    from pymunk_bot.config import localization as loc
    from pymunk_bot.config import schema as s

    drives.add("diff", "pymunk_bot.robots.drives.diff:DiffDriveGroup", s.DiffRobotConfig)
    drives.add("ackermann", "pymunk_bot.robots.drives.ackermann:AckermannDriveGroup",
               d.AckermannRobotConfig)
    drives.add("omni", "pymunk_bot.robots.drives.omni:OmniDriveGroup", d.OmniRobotConfig)
    odometry.add("diff", "pymunk_bot.sensors.odometry:of_diff_drive")
    odometry.add("ackermann", "pymunk_bot.sensors.odometry_ackermann:of_ackermann_drive")
    odometry.add("omni", "pymunk_bot.sensors.odometry_omni:of_omni_drive")
    obstacle_models: tuple[tuple[str, type], ...] = (("box", s.BoxObstacle), ("circle", s.CircleObstacle),
                        ("polygon", s.PolygonObstacle), ("wall", s.WallObstacle))
    for name, model in obstacle_models:
        obstacles.add(name, "pymunk_bot.physics.obstacles:build_obstacle", model)
    obstacles.add("pedestrian", "pymunk_bot.actors.pedestrians:build_pedestrian",
                  m.PedestrianObstacle)
    # Registration order fixes each sensor's random stream: keep new sensors after these.
    sensors.add("lidar", "pymunk_bot.sensors.attach:make_lidar", s.LidarConfig)
    sensors.add("imu", "pymunk_bot.sensors.attach:make_imu", s.ImuConfig)
    from pymunk_bot.config.crowd_state import CrowdStateConfig
    sensors.add("crowd_state", "pymunk_bot.sensors.attach:make_crowd_state", CrowdStateConfig)
    builtin_controllers: tuple[tuple[str, str, type], ...] = (
            ("wheels", "wheels:WheelsController", c.WheelsControllerConfig),
            ("velocity", "velocity:VelocityController", c.VelocityControllerConfig),
            ("go_to_goal", "go_to_goal:GoToGoalController", c.GoToGoalControllerConfig),
            ("waypoints", "waypoints:WaypointsController", c.WaypointsControllerConfig),
            ("avoid", "avoid:AvoidController", c.AvoidControllerConfig),
            ("navigate", "navigate_any:make_navigate", c.NavigateControllerConfig),
            ("social_force", "social_force:SocialForceController", c.SocialForceControllerConfig),
            ("orca", "orca:OrcaController", c.OrcaControllerConfig),
            ("crowdnav_orca", "crowdnav_orca:CrowdNavOrcaController",
             c.CrowdNavOrcaControllerConfig),
            ("python", "python:PythonController", c.PythonControllerConfig),
            ("policy", "policy:PolicyController", c.PolicyControllerConfig))
    for name, cls, model in builtin_controllers:
        controllers.add(name, f"pymunk_bot.controllers.{cls}", model)
    builtin_localizers: tuple[tuple[str, str, type], ...] = (
            ("ground_truth", "simple:GroundTruthLocalizer", loc.GroundTruthLocalizerConfig),
            ("odometry", "simple:OdometryLocalizer", loc.OdometryLocalizerConfig),
            ("mcl", "mcl:MclLocalizer", loc.MclConfig),
            ("ekf", "ekf:EkfLocalizer", loc.EkfConfig),
            ("slam", "slam:SlamLocalizer", loc.SlamConfig),
            ("python", "python:PythonLocalizer", loc.PythonLocalizerConfig))
    for name, cls, model in builtin_localizers:
        localizers.add(name, f"pymunk_bot.localization.{cls}", model)
