"""The API reference (docs/build_api.py, pdoc) covers the public names and fails on a broken
docstring: a name in ``__all__`` that does not exist, or a docstring example that fails."""
from __future__ import annotations

import importlib.util
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("pdoc")
REPO = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("build_api", REPO / "docs" / "build_api.py")
build_api = importlib.util.module_from_spec(spec)
spec.loader.exec_module(build_api)


def test_the_reference_documents_the_public_api(tmp_path):
    assert build_api.main(["--out", str(tmp_path)]) == 0
    assert (tmp_path / "index.html").is_file()
    pages = {name: (tmp_path / (name.replace(".", "/") + ".html")).read_text(encoding="utf-8")
             for name in build_api.PUBLIC_MODULES}
    # the names of the contract, each with its own docstring on its page
    for module, names in {"pymunk_bot.engine.simulation": ["Simulation.from_file", "Simulation.from_dict",
                                             "Simulation.reset", "Simulation.run"],
                          "pymunk_bot.robots.robot": ["Robot.set_velocity", "Robot.teleport"],
                          "pymunk_bot.engine.replicas": ["Replicas"],
                          "pymunk_bot.outcomes.runlog": ["load_log"],
                          "pymunk_bot.envs": ["MultiRobotEnv", "NavigationEnv"],
                          "pymunk_bot.plugins": ["controllers", "localizers"]}.items():
        for name in names:
            assert f'id="{name}"' in pages[module], f"{module}.{name} is not in the reference"
    assert "Ground truth" in pages["pymunk_bot.robots.robot"] or "ground truth" in pages["pymunk_bot.robots.robot"]


def test_a_broken_docstring_fails_the_build(tmp_path, monkeypatch, capsys):
    package = tmp_path / "src" / "broken_pkg"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text(textwrap.dedent('''\
        """A package whose docs went stale.

        >>> 1 + 1
        3
        """
        __all__ = ["renamed_away"]
        '''))
    monkeypatch.syspath_prepend(str(tmp_path / "src"))
    problems = build_api.build(tmp_path / "out", ["broken_pkg"])
    capsys.readouterr()
    assert any("renamed_away" in p for p in problems), problems
    assert any("broken_pkg: 1 of 1 docstring examples fail" in p for p in problems), problems
    sys.modules.pop("broken_pkg", None)
