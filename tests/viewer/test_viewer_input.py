"""Synthetic pygame events drive the viewer: clicks, keys, wheel, drag, teleop, time control."""
from __future__ import annotations

import numpy as np
import pygame
import pytest

from pymunk_bot.outcomes.runlog import RunLogger
from pymunk_bot.viewer.app import SPEEDS
from viewer_helpers import Harness, build, wheels
from bounds import HANG_GUARD

DT = 1.0 / 60.0


def two_robots():
    return build([{"name": "a", "pose": [1.0, 1.0, 0.0], "controller": {"type": "go_to_goal"},
                   "goal": {"position": [3.0, 1.0]}},
                  {"name": "b", "pose": [3.0, 2.0, 0.0], "controller": wheels(0.0, 0.0)}])


def test_left_click_sets_the_selected_robots_goal():
    sim = two_robots()
    task_goal = sim.robots["a"].goal
    h = Harness(sim)
    target = h.viewer.camera.to_screen(2.5, 2.5)
    h.click((round(target[0]), round(target[1])))
    goal = sim.robots["a"].nav_goal
    tolerance = 1.0 / h.viewer.camera.scale  # one pixel [m]
    assert goal == pytest.approx((2.5, 2.5), abs=tolerance)
    # Where it drives changes; what the scenario's expectations judge does not.
    assert sim.robots["a"].goal == task_goal
    assert sim.robots["b"].nav_goal is None
    # The controller drives there.
    for _ in range(360):
        h.source.step()
    assert np.hypot(*(sim.robots["a"].pose[:2] - np.array(goal))) < 0.2


def test_clicking_a_robot_selects_it_and_tab_cycles():
    sim = two_robots()
    h = Harness(sim)
    assert h.viewer.selected == "a"
    px, py = h.viewer.camera.to_screen(3.0, 2.0)
    h.click((round(px), round(py)))
    assert h.viewer.selected == "b"
    assert sim.robots["a"].goal == (3.0, 1.0)  # a click on a robot sets no goal
    h.key(pygame.K_TAB)
    assert h.viewer.selected == "a"
    h.key(pygame.K_TAB)
    assert h.viewer.selected == "b"


def test_drag_pans_without_setting_a_goal_and_wheel_zooms_about_the_pointer():
    sim = two_robots()
    h = Harness(sim)
    cam = h.viewer.camera
    before = cam.to_screen(2.0, 1.5)
    h.drag((200, 150), (260, 120))
    assert cam.to_screen(2.0, 1.5) == pytest.approx((before[0] + 60, before[1] - 30))
    assert sim.robots["a"].goal == (3.0, 1.0)
    pointer = (100, 200)
    h.input.handle(pygame.event.Event(pygame.MOUSEMOTION, pos=pointer, rel=(0, 0),
                                      buttons=(0, 0, 0)))
    under = cam.to_world(*pointer)
    scale = cam.scale
    h.input.handle(pygame.event.Event(pygame.MOUSEWHEEL, x=0, y=2, flipped=False))
    assert cam.scale == pytest.approx(scale * 1.15 ** 2)
    assert cam.to_world(*pointer) == pytest.approx(under)
    h.key(pygame.K_f)  # fit brings the whole arena back
    assert cam.scale == pytest.approx(scale)


def test_space_pauses_and_dot_steps_exactly_one_dt():
    sim = two_robots()
    h = Harness(sim)
    assert h.viewer.advance(0.5) == 30
    h.key(pygame.K_SPACE, " ")
    assert h.viewer.paused
    assert h.viewer.advance(1.0) == 0
    steps, time = sim.steps, sim.time
    h.key(pygame.K_PERIOD, ".")
    assert sim.steps == steps + 1
    assert sim.time == pytest.approx(time + DT, abs=1e-12)
    h.key(pygame.K_SPACE, " ")
    assert not h.viewer.paused
    h.key(pygame.K_PERIOD, ".")  # not paused: '.' does nothing
    assert sim.steps == steps + 1


def test_speed_keys_change_how_many_steps_a_frame_takes():
    sim = two_robots()
    h = Harness(sim)
    h.key(pygame.K_EQUALS, "+")
    h.key(pygame.K_PLUS, "+")
    assert h.viewer.speed == 4.0
    assert h.viewer.advance(0.1) == 24  # 0.4 simulated s of 1/60 s steps
    for _ in range(10):
        h.key(pygame.K_MINUS, "-")
    assert h.viewer.speed == SPEEDS[0]
    taken = sum(h.viewer.advance(0.1) for _ in range(10))  # 1 real s at 0.1x
    assert taken == 6
    for _ in range(10):
        h.key(pygame.K_KP_PLUS)
    assert h.viewer.speed_label == "max"
    assert h.viewer.advance(0.001) > 1  # as fast as possible: not tied to real time


def test_teleop_takes_over_and_gives_back():
    sim = build([{"name": "r", "pose": [1.0, 1.5, 0.0], "max_wheel_speed": 1.0,
                  "controller": wheels(0.0, 0.0)}])
    h = Harness(sim)
    robot = sim.robots["r"]
    h.key(pygame.K_UP)
    assert robot.overridden
    assert robot.drive.target == pytest.approx((0.7, 0.7))
    h.key(pygame.K_a)  # up + left: an arc to the left
    left, right = robot.drive.target
    assert right > left > 0
    h.key(pygame.K_a, up=True)
    for _ in range(60):
        h.source.step()
    assert robot.pose[0] > 1.4  # it drove forward
    h.key(pygame.K_UP, up=True)
    assert robot.overridden and robot.drive.target == (0.0, 0.0)  # held: stopped, still by hand
    h.key(pygame.K_c, "c")
    assert not robot.overridden  # the controller has it again
    h.key(pygame.K_d)  # alone, a turn key spins on the spot
    left, right = robot.drive.target
    assert left == pytest.approx(-right) and left > 0


def test_click_gives_a_teleoperated_robot_back_to_its_controller():
    sim = two_robots()
    h = Harness(sim)
    h.key(pygame.K_w)
    assert sim.robots["a"].overridden
    px, py = h.viewer.camera.to_screen(2.0, 2.5)
    h.click((round(px), round(py)))
    assert not sim.robots["a"].overridden


def test_reset_rebuilds_from_the_seed_and_keeps_the_logger():
    sim = two_robots()
    logger = RunLogger().attach(sim)
    h = Harness(sim)
    h.viewer.advance(1.0)
    assert sim.steps == 60
    h.key(pygame.K_r, "r")
    assert sim.steps == 0 and sim.time == 0.0
    assert np.array_equal(sim.robots["a"].pose, [1.0, 1.0, 0.0])
    assert logger in sim.observers
    h.viewer.advance(0.5)
    assert len(logger.log().time) == 31  # the start of the new run, then 30 steps


def test_the_run_pauses_at_its_duration_and_space_runs_on():
    sim = two_robots()
    h = Harness(sim, duration=0.5)
    taken = h.viewer.advance(2.0)
    assert taken == 30 and sim.steps == 30
    assert h.viewer.ended
    assert h.viewer.advance(1.0) == 0
    h.key(pygame.K_SPACE, " ")
    assert not h.viewer.ended
    assert h.viewer.advance(0.5) == 30


def test_toggles_help_and_quit():
    h = Harness(two_robots())
    for key, layer in ((pygame.K_l, "rays"), (pygame.K_t, "trails"), (pygame.K_g, "grid"),
                       (pygame.K_o, "ghost"), (pygame.K_p, "paths")):
        assert getattr(h.viewer.layers, layer)
        h.key(key)
        assert not getattr(h.viewer.layers, layer)
    h.key(pygame.K_h, "h")
    assert h.viewer.help
    h.draw(hud=True)  # the help overlay renders
    h.key(pygame.K_ESCAPE)
    assert not h.viewer.running
    h2 = Harness(two_robots())
    h2.input.handle(pygame.event.Event(pygame.QUIT))
    assert not h2.viewer.running


def test_window_frames_give_the_headless_result():
    """Whatever the frame times, the window's physics is the headless run's, step for step."""
    headless = two_robots()
    headless.run(3.0)
    windowed = two_robots()
    h = Harness(windowed, duration=3.0)
    frames = np.random.default_rng(5).uniform(0.0, 0.05, size=2000)
    for real_dt in frames:
        h.viewer.advance(float(real_dt))
        if h.viewer.ended:
            break
    assert windowed.steps == headless.steps == 180
    for name in headless.robots:
        assert np.array_equal(windowed.robots[name].pose, headless.robots[name].pose)
    assert windowed.result()["robots"] == headless.result()["robots"]


def test_run_window_opens_handles_events_and_returns():
    from pymunk_bot.viewer import run_window

    sim = two_robots()
    pygame.display.init()
    pygame.display.set_mode((320, 240))
    for event in (pygame.event.Event(pygame.KEYDOWN, key=pygame.K_SPACE, mod=0, unicode=" "),
                  pygame.event.Event(pygame.KEYDOWN, key=pygame.K_PERIOD, mod=0, unicode="."),
                  pygame.event.Event(pygame.QUIT)):
        pygame.event.post(event)
    run_window(sim, 5.0)
    assert sim.steps == 1  # paused at once, one step, then quit
    assert not pygame.display.get_init()


def test_an_unreachable_display_falls_back_to_headless_instead_of_an_invisible_window(tmp_path):
    """SDL silently picks its offscreen driver when no display answers; the CLI must not."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("SDL_VIDEODRIVER", "WAYLAND_DISPLAY")}
    env.update(DISPLAY=":97", XDG_RUNTIME_DIR=str(tmp_path))  # no X server there
    done = subprocess.run([sys.executable, "-m", "pymunk_bot", "run", "--duration", "0.2"],
                          env=env, capture_output=True, text=True, timeout=HANG_GUARD)
    assert done.returncode in (0, 1), done.stderr
    assert "running headless" in done.stdout
    assert "0.20 s simulated" in done.stdout
