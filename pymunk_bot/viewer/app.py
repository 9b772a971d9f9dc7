"""The viewer's state and actions, independent of a real window.

A :class:`Viewer` is fed events (see :mod:`.input`) and frame times (:meth:`Viewer.advance`)
and draws itself onto any surface, so tests drive it with synthetic events and an offscreen
surface. Physics always advances in whole steps of the simulation's fixed dt: the frame rate
decides only how many steps run between two frames, never what a step computes.
"""
from __future__ import annotations

import math
import time as wallclock
from collections import deque
from typing import Callable

import numpy as np
import pygame

from pymunk_bot.viewer.camera import Camera
from pymunk_bot.viewer.draw import Layers, StaticLayer, draw_scene
from pymunk_bot.viewer.hud import Hud, HudState
from pymunk_bot.viewer.scene import Scene

SPEEDS = (0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, math.inf)  # simulated s per real s
DEFAULT_SPEED = 3  # index of 1x
FRAME_BUDGET = 0.05  # [s] of real time spent stepping per frame at most, so the window stays live
MESSAGE_TIME = 2.5  # [s] a message stays on screen
TELEOP_FORWARD = 0.7  # fraction of the max wheel speed when driving by hand
TELEOP_TURN = 0.35  # wheel speed difference (fraction of max) when turning while driving
TELEOP_SPIN = 0.4  # wheel speed (fraction of max) when turning on the spot
CLICK_SLOP = 5  # [px] a press that moves further than this is a drag, not a click


class Viewer:
    """State of one window (live run or replay) and everything a key or click can do."""

    def __init__(self, source, viewport: tuple[int, int], duration: float | None = None,
                 clock: Callable[[], float] = wallclock.perf_counter) -> None:
        """``clock`` [s] measures the real time spent stepping in a frame (FRAME_BUDGET); tests
        inject a fake one so that step counts do not depend on the machine's load."""
        pygame.font.init()
        self._wallclock = clock
        self.source = source
        self.camera = Camera(viewport)
        self.layers = Layers()
        self.static = StaticLayer()  # the frame's fixed part, redrawn only when the view moves
        self.hud = Hud()
        self.label_font = pygame.font.Font(None, 18)
        self.duration = duration
        self.stop_step = self._stop_step()
        self.paused = False
        self.ended = ""
        self.speed_index = DEFAULT_SPEED
        self.help = False
        self.running = True
        self.recording = False  # a video frame: no speed, no key hint, the HUD off the arena
        self.agents: frozenset[str] = frozenset()  # robots a program drives (an env's agent)
        names = source.robot_names
        self.selected: str | None = names[0] if names else None
        self.held: set[str] = set()  # teleop directions held down
        self._debt = 0.0  # simulated time owed to the real-time clock [s]
        self._clock = 0.0  # real time seen by advance() [s]
        self._samples: deque[tuple[float, float]] = deque()
        self._message = ("", 0.0)
        self.fit()

    # ------------------------------------------------------------------ view
    def fit(self) -> None:
        """Show the whole arena."""
        width, height = self.source.size
        x0, y0 = getattr(self.source, "origin", (0.0, 0.0))
        self.camera.fit(x0, y0, x0 + width, y0 + height)

    def resize(self, viewport: tuple[int, int]) -> None:
        """The window changed size: keep the user's view, or refit if they have not chosen one."""
        self.camera.resize(viewport)
        if not self.camera.user_moved:
            self.fit()

    def say(self, text: str) -> None:
        """Show a short message at the bottom of the window."""
        self._message = (text, self._clock + MESSAGE_TIME)

    @property
    def message(self) -> str:
        text, until = self._message
        return text if self._clock < until else ""

    # ------------------------------------------------------------------ time
    def _stop_step(self) -> int | None:
        if self.duration is None or not self.source.interactive:
            return None
        return round(self.duration / self.source.dt)  # as Simulation.run rounds it

    @property
    def speed(self) -> float:
        return SPEEDS[self.speed_index]

    @property
    def speed_label(self) -> str:
        return "max" if math.isinf(self.speed) else f"{self.speed:g}x"

    def advance(self, real_dt: float) -> int:
        """Let ``real_dt`` seconds of real time pass; returns the number of steps taken."""
        self._clock += real_dt
        taken = 0
        if not (self.paused or self.ended):
            if math.isinf(self.speed):
                taken = self._step_for(FRAME_BUDGET, None)
            else:
                self._debt += real_dt * self.speed
                wanted = int(self._debt / self.source.dt + 1e-9)
                taken = self._step_for(FRAME_BUDGET, wanted)
                # What could not be done in time is dropped: the run slows down, it never jumps.
                self._debt = 0.0 if taken < wanted else self._debt - taken * self.source.dt
        self._sample()
        return taken

    def _step_for(self, budget: float, steps: int | None) -> int:
        started = self._wallclock()
        taken = 0
        while steps is None or taken < steps:
            if self._at_stop():
                break
            self.source.step()
            taken += 1
            if self._wallclock() - started > budget:
                break
        self._at_stop()
        return taken

    def _at_stop(self) -> bool:
        if self.stop_step is not None and self.source.steps >= self.stop_step:
            self.ended = (f"end of run ({self.duration:g} s): space runs on, "
                          "q quits and prints the result")
            return True
        if self.source.at_end:
            self.ended = "end of the log: r plays it again, q quits"
            return True
        return False

    def _sample(self) -> None:
        samples = self._samples
        samples.append((self._clock, self.source.time))
        while len(samples) > 2 and self._clock - samples[0][0] > 1.0:
            samples.popleft()

    @property
    def achieved(self) -> float | None:
        """Simulated seconds per real second over the last second (None until measurable)."""
        if len(self._samples) < 2:
            return None
        (c0, t0), (c1, t1) = self._samples[0], self._samples[-1]
        return (t1 - t0) / (c1 - c0) if c1 - c0 >= 0.25 else None

    # ------------------------------------------------------------------ actions
    def toggle_pause(self) -> None:
        if self.ended and self.stop_step is not None and self.source.steps >= self.stop_step:
            self.stop_step, self.ended, self.paused = None, "", False  # run on past the duration
            self.say("running on past the scenario's duration")
            return
        if self.ended:
            return
        self.paused = not self.paused
        self._debt = 0.0

    def step_once(self, direction: int = 1) -> None:
        """One step (a logged step back, in a replay) while paused."""
        if not self.paused and not self.ended:
            self.say("pause first (space), then . steps")
            return
        if direction < 0:
            if hasattr(self.source, "seek"):
                self.source.seek(-1)
                self.ended = ""
            return
        if self.source.at_end:
            return
        self.source.step()

    def change_speed(self, delta: int) -> None:
        self.speed_index = int(np.clip(self.speed_index + delta, 0, len(SPEEDS) - 1))
        self._debt = 0.0
        self.say(f"speed {self.speed_label}")

    def seek(self, seconds: float) -> None:
        """Jump within a replay."""
        if hasattr(self.source, "seek"):
            self.source.seek(round(seconds / self.source.dt))
            self.ended = ""

    def reset(self) -> None:
        """Start over: rebuild the simulation from its seed (or rewind the replay)."""
        self.release_teleop(quiet=True)
        self.source.reset()
        self.stop_step = self._stop_step()
        self.ended = ""
        self._debt = 0.0
        self._samples.clear()
        if self.selected not in self.source.robot_names:
            self.selected = self.source.robot_names[0]
        self.say("reset from the seed" if self.source.interactive else "replay from the start")

    def select_next(self) -> None:
        names = self.source.robot_names
        if not names:
            return
        self._stop_teleop_keys()
        i = names.index(self.selected) if self.selected in names else -1
        self.selected = names[(i + 1) % len(names)]
        self.say(f"selected {self.selected}")

    def toggle(self, layer: str) -> None:
        value = not getattr(self.layers, layer)
        setattr(self.layers, layer, value)
        self.say(f"{layer} {'on' if value else 'off'}")

    def quit(self) -> None:
        self.running = False

    # ------------------------------------------------------------------ mouse
    def robot_at(self, px: float, py: float) -> str | None:
        """The robot under a pixel, if any."""
        x, y = self.camera.to_world(px, py)
        slack = 4.0 / self.camera.scale  # [m]; small robots are still easy to hit
        for r in self.scene().robots:
            if math.hypot(r.pose[0] - x, r.pose[1] - y) <= r.radius + slack:
                return r.name
        return None

    def click(self, px: float, py: float) -> None:
        """A left click: select the robot under it, else send the selected robot there."""
        hit = self.robot_at(px, py)
        if hit is not None:
            if hit != self.selected:
                self._stop_teleop_keys()
                self.selected = hit
                self.say(f"selected {hit}")
            return
        if not self.source.interactive:
            self.say("a replay cannot take new goals")
            return
        if self.selected is None:
            return
        if self.ended:
            # Nothing steps any more: a goal set now would never be driven to.
            self.say("the run has ended: space runs on past its duration, then click a goal")
            return
        x, y = self.camera.to_world(px, py)
        width, height = self.source.size
        x0, y0 = getattr(self.source, "origin", (0.0, 0.0))
        if not (x0 <= x <= x0 + width and y0 <= y <= y0 + height):
            self.say("that is outside the arena")
            return
        robot = self.source.robot(self.selected)
        robot.set_nav_goal((x, y))  # where it drives; the scenario's goal still judges the run
        if robot.overridden:
            robot.clear_wheel_speeds()
            self.held.clear()
        note = "" if robot.controller is not None else " (it has no controller to drive there)"
        task = "; the task goal still judges the run" if robot.goal is not None else ""
        self.say(f"{self.selected}: drive-to goal ({x:.2f}, {y:.2f}) m{note}{task}")

    # ------------------------------------------------------------------ teleop
    def teleop_key(self, direction: str, down: bool) -> None:
        """An arrow/WASD key went down or up: drive the selected robot by hand."""
        if not self.source.interactive:
            return
        if down:
            self.held.add(direction)
        else:
            self.held.discard(direction)
        if self.selected is None:
            return
        robot = self.source.robot(self.selected)
        if not down and not robot.overridden:
            return
        if down and not robot.overridden:
            self.say(f"teleop {self.selected}: c gives it back to its controller")
        forward = ("up" in self.held) - ("down" in self.held)
        turn = ("left" in self.held) - ("right" in self.held)
        if robot.config.drive != "diff":
            robot.set_velocity(*teleop_velocity(robot.spec, forward, turn,
                                                ("slide_left" in self.held)
                                                - ("slide_right" in self.held)))
            return
        vmax = robot.config.max_wheel_speed
        if forward:
            left = vmax * (TELEOP_FORWARD * forward - TELEOP_TURN * turn)
            right = vmax * (TELEOP_FORWARD * forward + TELEOP_TURN * turn)
        else:
            left, right = -TELEOP_SPIN * vmax * turn, TELEOP_SPIN * vmax * turn
        robot.set_wheel_speeds(left, right)

    def _stop_teleop_keys(self) -> None:
        """Keys held for one robot must not keep driving it once another is selected."""
        if self.held and self.selected is not None and self.source.interactive:
            robot = self.source.robot(self.selected)
            if robot.overridden:
                robot.set_velocity(0.0, 0.0)
        self.held.clear()

    def release_teleop(self, quiet: bool = False) -> None:
        """Give the selected robot back to its controller."""
        self.held.clear()
        if not self.source.interactive or self.selected is None:
            return
        robot = self.source.robot(self.selected)
        if robot.overridden:
            robot.clear_wheel_speeds()
            if not quiet:
                self.say(f"{self.selected} is back under its controller")

    # ------------------------------------------------------------------ drawing
    def scene(self) -> Scene:
        return self.source.scene()

    def draw(self, surface: pygame.Surface, hud: bool = True) -> None:
        """Render the present state (with the HUD); changes nothing but ``surface``."""
        scene = self.scene()
        draw_scene(surface, scene, self.camera, self.layers, self.selected, self.label_font,
                   halo=not self.recording, static=self.static)
        if not hud:
            return
        selected = next((r for r in scene.robots if r.name == self.selected), None)
        if self.recording and len(scene.robots) > 1:
            selected = None  # a video has no selection: the HUD sums over the robots
        running = not (self.paused or self.ended)
        # A frame (video, rgb_array) puts its HUD in the margins, off the arena.
        band = self._margin(surface.get_height()) if self.recording else 0
        state = HudState(speed_label="" if self.recording else self.speed_label,
                         achieved=self.achieved if running else None, paused=self.paused,
                         ended=self.ended, message=self.message, help=self.help,
                         replay=not self.source.interactive, hint=not self.recording,
                         agents=self.agents, band=band)
        self.hud.draw(surface, scene, self.camera, state, selected)

    def _margin(self, surface_height: int) -> int:
        """[px] free both above and below the arena in the present view."""
        height = self.source.size[1]
        y0 = getattr(self.source, "origin", (0.0, 0.0))[1]
        top = self.camera.to_screen(0.0, y0 + height)[1]
        bottom = surface_height - self.camera.to_screen(0.0, y0)[1]
        return max(0, int(min(top, bottom)))


def teleop_velocity(spec, forward: int, turn: int, slide: int) -> tuple[float, float, float]:
    """(v, omega, vy) for held keys on a drive other than diff: a car steers to full lock
    (it cannot turn on the spot: standing, it only turns its wheels); an omni robot also
    slides sideways."""
    v = TELEOP_FORWARD * spec.max_speed * forward
    if spec.min_turn_radius > 0:
        omega = (abs(v) / spec.min_turn_radius * turn * (1 if v >= 0 else -1) if v
                 else float(turn))
        return v, omega, 0.0
    vy = TELEOP_FORWARD * spec.max_speed * slide if spec.holonomic else 0.0
    return v, TELEOP_SPIN * spec.max_omega * turn, vy
