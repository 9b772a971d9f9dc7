"""Every shipped scenario holds its expectations; `pymunk-bot test` and the pytest plugin."""
from pathlib import Path

import pytest

from pymunk_bot.cli import main
from pymunk_bot.cli.scenario_tests import discover

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = sorted((ROOT / "scenarios").glob("*.yaml"))

BROKEN = "name: broken\nworld: {size: [4.0, -1.0]}\nrobots: [{name: r, pose: [1.0, 1.0, 0.0]}]\n" \
         "expect: {r: {max_collisions: 0}}\n"
FAILING = """name: failing
world: {size: [6.0, 4.0], duration: 3.0}
robots:
  - {name: r, pose: [1.0, 2.0, 0.0], controller: {type: wheels, left: 0.5, right: 0.5}}
expect:
  r: {max_path_length: 1.0}
"""


def test_discovery_finds_every_shipped_scenario_with_expectations():
    # Running them is tests/test_shipped_scenarios.py's job: each runs once in the suite.
    assert len(SHIPPED) >= 8
    assert {p.name for p in discover([ROOT / "scenarios"])} == {
        p.name for p in SHIPPED if "expect:" in p.read_text()}


@pytest.fixture
def suite(tmp_path):
    (tmp_path / "good.yaml").write_text((ROOT / "scenarios" / "unreachable.yaml").read_text())
    (tmp_path / "notes.yaml").write_text("just: data\n")  # no expect block: not a test
    return tmp_path


def test_command_exit_status_and_table(suite, capsys):
    assert main(["test", str(suite)]) == 0
    (suite / "failing.yaml").write_text(FAILING)
    assert main(["test", str(suite), "--jobs", "1"]) == 1
    out = capsys.readouterr().out
    assert "failing" in out and "FAILED" in out
    # 3 s at 0.5 m/s less the acceleration from standing: about 1.45 m
    assert "r.max_path_length: expected <= 1 m, got 1.45" in out and "(off by 0.45" in out
    (suite / "broken.yaml").write_text(BROKEN)
    assert main(["test", str(suite), "--jobs", "1"]) == 2
    assert "world.size[1]: must be >= 0.001" in capsys.readouterr().out


def test_pytest_plugin_collects_only_what_it_is_pointed_at(suite, pytester, monkeypatch):
    (suite / "failing.yaml").write_text(FAILING)
    (suite / "tests").mkdir()
    (suite / "tests" / "fixture.yaml").write_text(FAILING)
    (suite / "tests" / "test_nothing.py").write_text("def test_ok():\n    pass\n")
    monkeypatch.chdir(suite)

    def pytest_run(*args):  # in this process: the plugin loads from its entry point as there
        return pytester.runpytest_inprocess("-q", "-p", "no:cacheprovider", *args)

    explicit = pytest_run("good.yaml", "failing.yaml")
    assert "1 failed, 1 passed" in explicit.stdout.str()
    assert "expected <= 1 m" in explicit.stdout.str()
    # A bare `pytest` (testpaths from the ini) never runs YAML fixtures lying beside tests.
    (suite / "pytest.ini").write_text("[pytest]\ntestpaths = tests\n")
    plain = pytest_run()
    assert "1 passed" in plain.stdout.str() and "failed" not in plain.stdout.str()
    # ...unless the project asks for them with the ini glob.
    (suite / "pytest.ini").write_text("[pytest]\ntestpaths = tests\n"
                                      "pymunk_bot_scenarios = tests/*.yaml\n")
    assert "1 failed, 1 passed" in pytest_run().stdout.str()
