"""pytest plugin: scenario files with an ``expect`` block become test items.

Registered through the ``pytest11`` entry point, so ``pytest scenarios/`` in a user's own
repository runs their scenarios (with their own ``python`` controllers) as tests. To keep it
from picking up YAML fixtures by accident, a file is collected only when

* it lies under a path given explicitly on the pytest command line, or
* it matches one of the globs of the ``pymunk_bot_scenarios`` ini option (relative to the
  rootdir, e.g. ``pymunk_bot_scenarios = scenarios/*.yaml``),

and its top level has a non-empty ``expect`` block. A file that fails validation is a failed
item showing the one-line error. Disable the plugin with ``-p no:pymunk_bot``.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from pymunk_bot.cli.scenario_tests import YAML_SUFFIXES, has_expect_block, run_scenario


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addini("pymunk_bot_scenarios", type="linelist", default=[],
                  help="globs (relative to the rootdir) of scenario files to collect as tests")
    parser.addoption("--scenario-seed", type=int, default=None,
                     help="run every collected scenario with this seed instead of its own")


def _explicit_paths(config: pytest.Config) -> list[Path]:
    """Paths named on the command line (not testpaths defaults), resolved."""
    paths = []
    for arg in config.invocation_params.args:
        arg = str(arg)
        if arg.startswith("-"):
            continue
        candidate = Path(config.invocation_params.dir, arg.split("::")[0])
        if candidate.exists():
            paths.append(candidate.resolve())
    return paths


def _wanted(file_path: Path, config: pytest.Config) -> bool:
    resolved = file_path.resolve()
    for base in _explicit_paths(config):
        if resolved == base or base in resolved.parents:
            return True
    root = Path(config.rootpath)
    for pattern in config.getini("pymunk_bot_scenarios"):
        try:
            relative = resolved.relative_to(root.resolve())
        except ValueError:
            continue
        if relative.match(pattern) or resolved.match(pattern):
            return True
    return False


def pytest_collect_file(file_path: Path, parent: pytest.Collector):
    if file_path.suffix not in YAML_SUFFIXES:
        return None
    if not _wanted(file_path, parent.config) or not has_expect_block(file_path):
        return None
    return ScenarioFile.from_parent(parent, path=file_path)


class ScenarioFile(pytest.File):
    """One scenario file: one test item."""

    def collect(self):
        yield ScenarioItem.from_parent(self, name=self.path.stem)


class ScenarioFailure(Exception):
    """A scenario's expectations did not hold, or the file is invalid."""


class ScenarioItem(pytest.Item):
    """Runs a scenario for its duration and checks its ``expect`` block."""

    def runtest(self) -> None:
        outcome = run_scenario(self.path, seed=self.config.getoption("scenario_seed"))
        if outcome.status == "error":
            raise ScenarioFailure(f"invalid scenario: {outcome.error}")
        if outcome.failures:
            raise ScenarioFailure("\n".join(["expectations failed:"] + outcome.failures))

    def repr_failure(self, excinfo, style=None):
        if isinstance(excinfo.value, ScenarioFailure):
            return str(excinfo.value)
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self):
        return self.path, None, f"scenario {self.path.name}"
