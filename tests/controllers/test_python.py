"""python: a user's own controller class runs from YAML, at its own rate, with its params."""
import textwrap

import pytest

from pymunk_bot import ScenarioError, Simulation
from pymunk_bot.config.loader import parse_scenario

USER_MODULE = '''
from pymunk_bot.controllers import Controller, wheel_speeds

class Spinner(Controller):
    rate = 5.0

    def __init__(self, robot, speed=0.3, turn=0.0):
        super().__init__()
        self.speed, self.turn, self.robot, self.calls = speed, turn, robot, []

    def compute(self, obs):
        self.calls.append(obs.time)
        self.message = f"call {len(self.calls)}"
        return wheel_speeds(self.speed, self.turn, obs.robot.track_width)
'''


@pytest.fixture
def user_package(tmp_path, monkeypatch):
    package = tmp_path / "my_robots"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "spin.py").write_text(textwrap.dedent(USER_MODULE))
    monkeypatch.syspath_prepend(str(tmp_path))
    return "my_robots.spin:Spinner"


def config_with(controller):
    return parse_scenario({"name": "p", "world": {"size": [6.0, 6.0]}, "robots": [
        {"name": "r", "pose": [1.0, 3.0, 0.0], "controller": controller}]}, "p.yaml")


def test_user_class_runs_with_params_at_its_rate(user_package):
    sim = Simulation(config_with({"type": "python", "class_path": user_package,
                                  "params": {"speed": 0.5}}))
    sim.run(2.0)
    inner = sim.robots["r"].controller.inner
    assert len(inner.calls) == 10  # 5 Hz for 2 s
    assert sim.robots["r"].pose[0] == pytest.approx(1.0 + 0.5 * 2.0, abs=0.05)
    assert sim.result()["robots"]["r"]["controller_message"] == "call 10"


def test_rate_in_yaml_overrides_the_class(user_package):
    sim = Simulation(config_with({"type": "python", "class_path": user_package, "rate": 20.0}))
    sim.run(1.0)
    assert len(sim.robots["r"].controller.inner.calls) == 20


@pytest.mark.parametrize("class_path, problem", [
    ("no_such_pkg.mod:X", "cannot import module 'no_such_pkg.mod'"),
    ("my_robots.spin:Nope", "has no attribute 'Nope'"),
    ("my_robots.spin", "must be 'package.module:ClassName'"),
])
def test_bad_class_paths_are_one_line_errors(user_package, class_path, problem):
    with pytest.raises(ScenarioError) as err:
        config_with({"type": "python", "class_path": class_path})
    message = str(err.value)
    assert message.startswith("p.yaml: robots[0].controller.class_path: ") and problem in message
    assert "\n" not in message


def test_unknown_params_are_reported_at_the_controller(user_package):
    with pytest.raises(ScenarioError) as err:
        Simulation(config_with({"type": "python", "class_path": user_package,
                                "params": {"sped": 1.0}}), source="p.yaml")
    assert str(err.value).startswith("p.yaml: robots[0].controller: ") and "sped" in str(err.value)
