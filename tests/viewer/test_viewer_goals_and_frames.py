"""Both goals stay on screen and say what they mean; frames keep their HUD off the arena and
name the agent's robot; the run summary says what its real-time factor measured."""
from __future__ import annotations

import time

import numpy as np
import pygame
import pytest
from viewer_helpers import Harness, build, near

from pymunk_bot.viewer import palette as pal
from pymunk_bot.viewer.hud import goal_lines, robot_line

TASK, CLICK = (5.0, 1.5), (2.0, 2.4)


def clicked_and_arrived() -> Harness:
    sim = build([{"name": "r1", "pose": [1.0, 1.5, 0.0], "controller": {"type": "go_to_goal"},
                  "goal": {"position": list(TASK), "tolerance": 0.2}}], size=(6.0, 3.0))
    h = Harness(sim, size=(800, 450), duration=8.0)
    h.click(tuple(int(v) for v in h.viewer.camera.to_screen(*CLICK)))
    for _ in range(200):
        h.viewer.advance(0.05)
    assert h.viewer.ended and not sim.robots["r1"].goal_reached
    return h


def test_a_clicked_goal_leaves_the_task_goal_on_screen():
    h = clicked_and_arrived()
    (view,) = h.viewer.scene().robots
    assert view.goal == TASK and view.nav_goal == pytest.approx(CLICK, abs=0.02)
    h.draw()
    colour = pal.robot_colour(0)
    # the task goal's crosshair, 0.1 m right of its centre; the clicked goal's x, 0.08 m
    # diagonally from its centre (the robot, 0.2 m in radius, sits there)
    assert near(h.pixel((TASK[0] + 0.1, TASK[1])), colour, tol=40)
    assert not near(h.pixel((TASK[0] + 0.1, TASK[1] + 0.1)), colour, tol=40)  # a +, not an x


def test_the_hud_says_which_goal_is_which_and_that_the_task_is_not_done():
    h = clicked_and_arrived()
    (view,) = h.viewer.scene().robots
    (clicked, _), (task, warn) = goal_lines(view)
    assert clicked.startswith("drive-to goal (") and clicked.endswith(", dashed: arrived")
    assert task == "task goal (5.00, 1.50), solid: NOT reached, judges the run"
    assert warn == pal.HUD_WARN
    assert "arrived" not in robot_line(view)  # the status belongs to the clicked goal's line


def test_without_a_click_the_hud_is_as_before():
    sim = build([{"name": "r1", "pose": [1.0, 1.5, 0.0], "controller": {"type": "go_to_goal"},
                  "goal": {"position": [2.0, 1.5], "tolerance": 0.2}}], size=(6.0, 3.0))
    h = Harness(sim, size=(800, 450))
    for _ in range(100):
        h.viewer.advance(0.05)
    (view,) = h.viewer.scene().robots
    assert view.nav_goal is None and goal_lines(view) == []
    assert robot_line(view).endswith("goal reached, arrived")


@pytest.fixture
def frame_renderer():
    pytest.importorskip("gymnasium")
    from pymunk_bot.envs.render import FrameRenderer

    sim = build([{"name": "r1", "pose": [0.25, 2.75, 0.0]},  # in the arena's top-left corner
                 {"name": "r2", "pose": [3.0, 1.0, 0.0], "controller": {"type": "go_to_goal"},
                  "goal": {"position": [3.5, 1.0]}}], size=(4.0, 3.0))
    sim.robots["r1"].set_velocity(0.3, 0.0)  # as an env's agent drives it
    renderer = FrameRenderer(sim, agents=["r1"])
    yield renderer
    renderer.close()


def test_an_rgb_frame_keeps_its_hud_off_the_arena(frame_renderer):
    frame = frame_renderer.rgb()
    bare = pygame.Surface(frame_renderer.size)
    frame_renderer.viewer.draw(bare, hud=False)
    bare_rgb = pygame.surfarray.array3d(bare).transpose(1, 0, 2)
    camera = frame_renderer.viewer.camera
    (x0, y1), (x1, y0) = (camera.to_screen(0.0, 0.0), camera.to_screen(4.0, 3.0))
    inside = (slice(int(y0) + 1, int(y1) - 1), slice(int(x0) + 1, int(x1) - 1))
    assert np.array_equal(frame[inside], bare_rgb[inside])  # nothing drawn over the arena
    assert not np.array_equal(frame, bare_rgb)  # but a HUD there is, in the margins


def test_an_rgb_frame_names_the_agents_robot(frame_renderer):
    frame_renderer.sim.step()
    viewer = frame_renderer.viewer
    agent = next(r for r in viewer.scene().robots if r.name == "r1")
    line = robot_line(agent, viewer.agents)
    assert line.startswith("r1 (agent): ")
    assert "TELEOP" not in line and "no controller" not in line


def test_the_summary_says_what_its_real_time_factor_measured(tmp_path, monkeypatch, capsys):
    import importlib

    import pymunk_bot.viewer as viewer
    from pymunk_bot.cli import main as cli_main

    def watch_at_1x(sim, duration):  # stands in for the window: 0.3 s watched for 0.3 s
        sim.run(0.3)
        time.sleep(0.3)

    monkeypatch.setattr(importlib.import_module("pymunk_bot.cli.main"), "_display_available",
                        lambda: True)
    monkeypatch.setattr(viewer, "run_window", watch_at_1x)
    scenario = tmp_path / "still.yaml"
    scenario.write_text("name: still\nworld: {size: [2.0, 2.0]}\n"
                        "robots: [{name: r1, pose: [1.0, 1.0, 0.0]}]\n")
    status = cli_main(["run", str(scenario), "--duration", "0.3"])
    out = capsys.readouterr().out.splitlines()[0]
    assert status == 0
    watched = float(out.split("watched over ")[1].split(" s in the window")[0])
    assert "0.30 s simulated, watched over " in out and watched >= 0.3
    assert "x real time); computing the steps took " in out
    assert "of that (headless, it would run at " in out
    pace = float(out.split("in the window (")[1].split("x real time")[0])
    # What the user watched (at most the 1x the window slept), not the compute speed; a
    # loaded machine only lengthens the watch.
    assert pace == pytest.approx(0.3 / watched, rel=0.25) and pace <= 1.05
