"""How a fresh interpreter reaches pymunk_bot/Navigation-v0 under Gymnasium 1.x, which loads no
plugin entry points (docs/learning.md): the start-up hook a regular install puts in
site-packages, the id with its module, or the import first."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("gymnasium")
ROOT = Path(__file__).resolve().parents[2]
HOOK = ROOT / "pymunk_bot-gymnasium.pth"  # setup.py installs it at the top of site-packages


def test_the_bare_id_works_where_the_start_up_hook_is_installed(tmp_path):
    site_packages = tmp_path / "site-packages"
    site_packages.mkdir()
    shutil.copy(HOOK, site_packages)
    # site.addsitedir reads the .pth files of a folder as Python does for site-packages at
    # start-up; then the user's code: import Gymnasium (pymunk_bot is still not imported) and
    # make the env by its bare id.
    out = fresh_python(
        "import site, sys\n"
        f"site.addsitedir({str(site_packages)!r})\n"
        "import gymnasium as gym\n"
        "assert 'pymunk_bot' not in sys.modules, 'the hook imported pymunk_bot'\n"
        "env = gym.make('pymunk_bot/Navigation-v0')\n"
        "print(env.spec.id, env.reset(seed=1)[0].shape)")
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("pymunk_bot/Navigation-v0 (") and out.stderr == ""


def fresh_python(code: str) -> subprocess.CompletedProcess:
    """``code`` in a new interpreter (nothing of pymunk_bot imported before it runs)."""
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)})


@pytest.mark.parametrize("code", [
    # The id with its module: Gymnasium imports pymunk_bot.envs, which registers the id.
    'import sys, gymnasium as gym\n'
    'assert "pymunk_bot" not in sys.modules\n'
    'env = gym.make("pymunk_bot.envs:pymunk_bot/Navigation-v0")\n'
    'print(env.spec.id, env.reset(seed=1)[0].shape)',
    # gym.register_envs(module): Gymnasium's documented form of "import first".
    'import gymnasium as gym, pymunk_bot.envs\n'
    'gym.register_envs(pymunk_bot.envs)\n'
    'env = gym.make("pymunk_bot/Navigation-v0")\n'
    'print(env.spec.id, env.reset(seed=1)[0].shape)',
])
def test_a_fresh_interpreter_makes_navigation_v0(code):
    out = fresh_python(code)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "pymunk_bot/Navigation-v0 (368,)"  # 360 beams + 8
