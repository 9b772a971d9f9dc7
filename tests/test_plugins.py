"""A third-party plugin, installed the way pip would (a module plus a ``*.dist-info`` folder with
an entry point), found through the ``pymunk_bot.plugins`` entry-point group and used."""
from __future__ import annotations

import math
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from pymunk_bot import plugins
from pymunk_bot.config import parse_scenario
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.engine.simulation import Simulation

# A spiral: forward speed v, yaw rate v / r(t) with a turn radius growing as r0 + growth * t,
# and a compass sensor reading the heading. Written as a third party would, on the public API.
SPIRAL_PLUGIN = '''
from typing import Literal

from pymunk_bot import plugins
from pymunk_bot.config.types import NonNegativeFloat, PositiveFloat, Section
from pymunk_bot.controllers.base import Command, Controller


class SpiralConfig(Section):
    type: Literal["spiral"]
    v: PositiveFloat = 0.3  # [m/s]
    r0: PositiveFloat = 0.5  # [m] turn radius at t = 0
    growth: NonNegativeFloat = 0.1  # [m/s] the turn radius grows this fast
    rate: PositiveFloat = 10.0  # [Hz]


class SpiralController(Controller):
    def __init__(self, config, robot):
        super().__init__(config, robot)

    def compute(self, obs):
        c = self.config
        return Command(c.v, c.v / (c.r0 + c.growth * obs.time))


class CompassConfig(Section):
    bias: float = 0.0  # [rad]


class Compass:
    name = "compass"

    def __init__(self, config, body):
        self.config, self.body, self.reading = config, body, None

    def update(self, time):
        self.reading = self.body.angle + self.config.bias


def make_compass(config, robot, world, rng):
    return Compass(config, robot.body)


def register():
    plugins.controllers.add("spiral", SpiralController, SpiralConfig)
    plugins.sensors.add("compass", make_compass, CompassConfig)
'''


def _install(folder: Path, module: str, source: str, entry_point: str) -> None:
    """What `pip install` leaves in site-packages: the module and its dist-info."""
    (folder / f"{module}.py").write_text(textwrap.dedent(source))
    info = folder / f"{module}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {module}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[pymunk_bot.plugins]\n{entry_point}\n")


@pytest.fixture
def installed(tmp_path, monkeypatch):
    """Put a folder on sys.path to install plugins into; forget what they registered after."""
    plugins.load()  # the built-ins first, as every real run has them
    monkeypatch.setattr(plugins, "_entry_points_loaded", set(plugins._entry_points_loaded))
    monkeypatch.syspath_prepend(str(tmp_path))
    modules = set(sys.modules)
    yield tmp_path
    for name in set(sys.modules) - modules:  # the plugin modules imported from tmp_path
        if str(tmp_path) in str(getattr(sys.modules[name], "__file__", "")):
            del sys.modules[name]
    for registry, name in ((plugins.controllers, "spiral"), (plugins.sensors, "compass")):
        if name in registry:
            registry.remove(name)


def _scenario(**controller) -> dict:
    return {"name": "spiral", "world": {"size": [12.0, 12.0]},
            # a brisk drive (30 m/s^2), so the path is the commanded one within a few cm
            "robots": [{"name": "r1", "pose": [6.0, 4.0, 0.0], "compass": {"bias": 0.0},
                        "max_accel": 30.0,
                        "controller": {"type": "spiral", **controller}}]}


def _expected_pose(v: float, r0: float, growth: float, seconds: float, rate: float = 10.0):
    """The plugin's commands integrated exactly (held for each control period)."""
    x, y, theta = 6.0, 4.0, 0.0
    for k in range(round(seconds * rate)):
        omega, h = v / (r0 + growth * k / rate), 1.0 / rate
        if abs(omega) > 1e-12:
            x += v / omega * (math.sin(theta + omega * h) - math.sin(theta))
            y -= v / omega * (math.cos(theta + omega * h) - math.cos(theta))
        theta += omega * h
    return np.array([x, y, theta])


def test_installed_plugin_drives_a_spiral_and_reads_its_compass(installed):
    _install(installed, "spiral_plugin", SPIRAL_PLUGIN, "spiral = spiral_plugin:register")
    assert "spiral" in plugins.load_entry_points()
    assert "spiral" in plugins.controllers and "compass" in plugins.sensors

    sim = Simulation.from_dict(_scenario(v=0.3, r0=0.5, growth=0.1))
    robot = sim.robots["r1"]
    sim.run(2.0)
    early = robot.velocity[1]  # yaw rate [rad/s] at t = 2 s: turn radius 0.7 m
    sim.run(6.0)
    late = robot.velocity[1]  # at t = 8 s: 1.3 m
    assert early == pytest.approx(0.3 / 0.7, rel=0.05)
    assert late == pytest.approx(0.3 / 1.3, rel=0.05)
    # It drove the spiral the plugin commands.
    expected = _expected_pose(0.3, 0.5, 0.1, 8.0)
    assert np.hypot(*(robot.pose[:2] - expected[:2])) < 0.05
    assert robot.pose[2] == pytest.approx(expected[2], abs=0.05)
    # The plugin's sensor is attached from its YAML key and reads what it says.
    assert robot.readings()["compass"] == pytest.approx(robot.pose[2], abs=1e-9)


def test_misspelt_plugin_keys_get_the_usual_one_line_error(installed):
    _install(installed, "spiral_plugin", SPIRAL_PLUGIN, "spiral = spiral_plugin:register")
    plugins.load_entry_points()
    with pytest.raises(ScenarioError) as key_error:
        parse_scenario(_scenario(grwth=0.2), "spiral.yaml")
    message = str(key_error.value)
    assert "robots[0].controller" in message and "grwth" in message
    assert "did you mean" in message and "growth" in message
    assert "\n" not in message
    with pytest.raises(ScenarioError) as bad_value:
        parse_scenario(_scenario(v=-1.0), "spiral.yaml")
    assert "robots[0].controller.v" in str(bad_value.value)
    spelt = _scenario()
    spelt["robots"][0]["controller"]["type"] = "spirl"
    with pytest.raises(ScenarioError) as type_error:
        parse_scenario(spelt, "spiral.yaml")
    assert "spiral" in str(type_error.value)  # the valid names include the plugin's


def test_removed_plugin_is_an_unknown_controller_again(installed):
    _install(installed, "spiral_plugin", SPIRAL_PLUGIN, "spiral = spiral_plugin:register")
    plugins.load_entry_points()
    parse_scenario(_scenario(), "spiral.yaml")
    plugins.controllers.remove("spiral")
    with pytest.raises(ScenarioError, match="robots\\[0\\].controller"):
        parse_scenario(_scenario(), "spiral.yaml")


@pytest.mark.parametrize("module, source, problem", [
    ("raising_plugin", "def register():\n    raise ValueError('no licence key')\n",
     "ValueError: no licence key"),
    ("missing_dependency_plugin", "import not_a_real_module_xyz\n\ndef register():\n    pass\n",
     "ModuleNotFoundError"),
])
def test_plugin_that_fails_to_load_is_named(installed, module, source, problem):
    _install(installed, module, source, f"broken = {module}:register")
    with pytest.raises(RuntimeError) as error:
        plugins.load_entry_points()
    message = str(error.value)
    assert "'broken'" in message and f"{module}:register" in message and problem in message


POST_PLUGIN = '''
from typing import Literal

import numpy as np
import pymunk

from pymunk_bot import plugins
from pymunk_bot.config.types import Friction, PositiveFloat, Section, Vec2
from pymunk_bot.physics.obstacles import Obstacle


class PostConfig(Section):
    type: Literal["post"]
    center: Vec2
    radius: PositiveFloat = 0.05  # [m]
    friction: Friction = 0.5

    def outline(self):  # what start checks, substeps and planning maps see of it
        a = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
        return np.stack((self.center[0] + self.radius * np.cos(a),
                         self.center[1] + self.radius * np.sin(a)), axis=1)


def make_post(space, config):
    shape = pymunk.Circle(space.static_body, config.radius, tuple(config.center))
    space.add(shape)
    return Obstacle(config, space.static_body, [shape])


def register():
    plugins.obstacles.add("post", make_post, PostConfig)
'''


def test_plugin_obstacle_kind_is_seen_by_the_lidar(installed):
    _install(installed, "post_plugin", POST_PLUGIN, "post = post_plugin:register")
    plugins.load_entry_points()
    try:
        sim = Simulation.from_dict({
            "name": "post", "world": {"size": [5.0, 2.0]},
            "obstacles": [{"type": "post", "center": [3.0, 1.0], "radius": 0.1}],
            "robots": [{"name": "r1", "pose": [1.0, 1.0, 0.0],
                        "lidar": {"beams": 4, "max_range": 5.0}}]})
        ahead = sim.robots["r1"].lidar.scan()[2]  # beam beams // 2 looks straight ahead
        assert ahead == pytest.approx(3.0 - 1.0 - 0.1, abs=1e-6)
    finally:
        plugins.obstacles.remove("post")
