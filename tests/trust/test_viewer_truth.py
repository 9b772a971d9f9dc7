"""The window tells the truth: the HUD never hides a robot, a click after the end sets nothing,
step counts do not depend on the machine's load."""
from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "viewer"))

from viewer_helpers import FakeClock, Harness, build, near, wheels  # noqa: E402

from pymunk_bot.viewer import palette as pal  # noqa: E402
from pymunk_bot.viewer.app import Viewer  # noqa: E402
from pymunk_bot.viewer.sources import LiveSource  # noqa: E402


def test_the_hud_moves_off_a_robot_in_its_corner():
    # A robot at the top-left corner of the arena, where the HUD panel sits by default.
    sim = build([{"name": "r", "pose": [0.3, 2.7, 0.0]}], size=(4.0, 3.0))
    h = Harness(sim, size=(400, 300))
    bare = h.draw(hud=False).copy()
    with_hud = h.draw(hud=True)
    px, py = (int(v) for v in h.viewer.camera.to_screen(0.3, 2.7))
    assert with_hud.get_at((px, py))[:3] == bare.get_at((px, py))[:3]


def test_the_hud_stays_top_left_when_nothing_is_there():
    sim = build([{"name": "r", "pose": [3.5, 0.5, 0.0]}], size=(4.0, 3.0))
    h = Harness(sim, size=(400, 300))
    h.draw(hud=True)
    assert not near(h.surface.get_at((20, 20))[:3], pal.FLOOR, tol=4)


def test_a_click_after_the_end_of_the_run_sets_no_goal():
    sim = build([{"name": "r", "pose": [1.0, 1.5, 0.0],
                  "controller": {"type": "go_to_goal", "goal": [3.0, 1.5]}}])
    h = Harness(sim, duration=0.5)
    h.viewer.advance(1.0)
    assert h.viewer.ended
    goal_before = sim.robots["r"].goal
    nav_before = sim.robots["r"].nav_goal
    px, py = h.viewer.camera.to_screen(2.0, 2.5)
    h.click((int(px), int(py)))
    assert sim.robots["r"].goal == goal_before and sim.robots["r"].nav_goal == nav_before
    assert "run has ended" in h.viewer.message


def test_step_counts_follow_the_injected_clock_not_the_machine():
    sim = build([{"name": "r", "pose": [1.0, 1.5, 0.0], "controller": wheels(0.2, 0.2)}])
    ticks = iter([0.0, 0.0, 0.01, 0.02, 0.03, 0.2] + [1.0] * 100)  # 5th step blows the budget
    viewer = Viewer(LiveSource(sim), (200, 150), clock=lambda: next(ticks))
    viewer.speed_index = len(__import__("pymunk_bot.viewer.app", fromlist=["SPEEDS"]).SPEEDS) - 1
    assert viewer.advance(0.001) == 5
    fast = Viewer(LiveSource(build([{"name": "r", "pose": [1.0, 1.5, 0.0]}])), (200, 150),
                  clock=FakeClock())
    assert fast.advance(1.0) == 60  # 1x real time: exactly 60 steps of 1/60 s
