"""examples/quickstart.ipynb runs from top to bottom, headless, and shows what it says: a run
that reaches its goal, a plot, and a frame of the scene after steering toward the goal."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from bounds import HANG_GUARD

NOTEBOOK = Path(__file__).resolve().parents[2] / "examples" / "quickstart.ipynb"


def test_the_quickstart_notebook_runs_and_shows_a_plot_and_a_frame(tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")  # here, not at collection: 0.2 s to import
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")  # the kernel inherits the environment
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    assert all(not c.get("outputs") for c in notebook.cells if c.cell_type == "code"), \
        "commit the notebook without outputs"
    nbclient.NotebookClient(notebook, timeout=HANG_GUARD, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for c in notebook.cells if c.cell_type == "code" for o in c.outputs]
    text = "".join(o.get("text", "") for o in outputs)
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert "goal reached: True" in text and "0 collision(s)" in text
    assert "(492, 640, 3) uint8" in text  # the rgb_array frame
    assert len(images) == 2  # the path and speed plot, then the frame
    # The demo steers by the goal bearing it reads from the observation: 1.5 s at 0.5 of full
    # speed brings the robot clearly closer (a wrong feature index makes it spin on the spot).
    gym = pytest.importorskip("gymnasium")
    import pymunk_bot.envs  # noqa: F401  registers the env

    env = gym.make("pymunk_bot/Navigation-v0", scenario="doorway")
    start = env.reset(seed=0)[1]["distance_to_goal"]  # [m], the notebook's reset
    env.close()
    line = next(line for line in text.splitlines() if "distance to goal" in line)
    end = float(re.findall(r"(\d+\.\d+) m", line)[-1])  # [m], the last figure printed
    assert end < start - 0.3, f"the demo robot got no closer to the goal: {start} m -> {end} m"
