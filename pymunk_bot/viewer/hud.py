"""The heads-up display: time, speed, the selected robot, a scale bar, messages and key help."""
from __future__ import annotations

from dataclasses import dataclass

import pygame

from pymunk_bot.viewer import palette as pal
from pymunk_bot.viewer.camera import Camera
from pymunk_bot.viewer.scene import RobotView, Scene

HELP_LIVE = (
    ("left click", "send the selected robot there (click a robot: select it)"),
    ("drag, wheel", "pan, zoom"),
    ("arrows / WASD", "drive the selected robot by hand (teleop)"),
    ("z / x", "slide left / right (omni robots)"),
    ("c", "give the robot back to its controller"),
    ("tab", "select the next robot"),
    ("space", "pause / resume"),
    (".", "one physics step while paused"),
    ("+ / -", "faster / slower (up to as fast as possible)"),
    ("r", "reset from the seed"),
    ("l  t  g  o  p", "toggle LiDAR rays, trails, grid, odometry ghost, paths"),
    ("m  k  v  e", "toggle built map, particles, covariance ellipse, estimate"),
    ("f", "fit the arena in the window"),
    ("h", "this help"),
    ("q / esc", "quit"),
)
HELP_REPLAY = (
    ("drag, wheel", "pan, zoom"),
    ("space", "pause / resume"),
    (".  /  ,", "one logged step forward / back while paused"),
    ("right / left", "jump 1 s forward / back"),
    ("+ / -", "faster / slower"),
    ("r", "restart the replay"),
    ("tab", "select the next robot"),
    ("l  t  g  o", "toggle LiDAR rays, trails, grid, odometry ghost"),
    ("m  k  v  e", "toggle built map, particles, covariance ellipse, estimate"),
    ("f", "fit the arena in the window"),
    ("h", "this help"),
    ("q / esc", "quit"),
)


@dataclass
class HudState:
    """What the HUD shows besides the scene."""

    speed_label: str  # the chosen speed, e.g. "1x" or "max"; "" shows none (recordings)
    achieved: float | None  # measured simulated seconds per real second
    paused: bool
    ended: str = ""  # why the run stopped, if it did
    message: str = ""  # a short-lived note (goal set, teleop on, ...)
    help: bool = False
    replay: bool = False
    hint: bool = True  # "h: keys" (not in recordings)
    agents: frozenset[str] = frozenset()  # robots driven by a program (a learning agent)
    band: int = 0  # [px] above and below the arena: frames put a one-line HUD and the scale
    # bar there, off the arena; 0: the window's panel, moved off the robots


class Hud:
    """Draws the HUD with its own fonts (pygame.font must be initialised)."""

    def __init__(self) -> None:
        self.font = pygame.font.Font(None, 22)
        self.small = pygame.font.Font(None, 18)

    def draw(self, surface: pygame.Surface, scene: Scene, camera: Camera, state: HudState,
             selected: RobotView | None) -> None:
        """Overlay the HUD on ``surface``."""
        if state.band:
            self._band(surface, scene, camera, state, selected)
            return
        lines: list[tuple[str, tuple[int, int, int]]] = []
        speed = f"   speed {state.speed_label}" if state.speed_label else ""
        if state.speed_label and state.achieved is not None:
            speed += f" (running at {state.achieved:.2f}x real time)"
        status = "  PAUSED" if state.paused else ""
        lines.append((f"t = {scene.time:7.2f} s{speed}{status}",
                      pal.HUD_WARN if state.paused else pal.HUD_TEXT))
        if selected is not None:
            lines.append((robot_line(selected, state.agents), pal.HUD_TEXT))
            lines.extend(goal_lines(selected))
        total = sum(r.collisions for r in scene.robots)
        if len(scene.robots) > 1:
            lines.append((f"{len(scene.robots)} robots, {total} collision(s) in all", pal.HUD_DIM))
        if state.ended:
            lines.append((state.ended, pal.HUD_WARN))
        if state.hint:
            lines.append(("h: keys", pal.HUD_DIM))
        panel = self._render_panel(lines, self.font)
        surface.blit(panel, self._free_corner(surface, panel.get_size(), scene, camera))
        self._scale_bar(surface, camera)
        if state.message:
            text = self.font.render(state.message, True, pal.HUD_TEXT)
            w, h = surface.get_size()
            self._panel(surface, [(state.message, pal.HUD_TEXT)],
                        ((w - text.get_width()) // 2 - 8, h - 40), self.font)
        if state.help:
            self._help(surface, HELP_REPLAY if state.replay else HELP_LIVE)

    def _band(self, surface: pygame.Surface, scene: Scene, camera: Camera, state: HudState,
              selected: RobotView | None) -> None:
        """One line in the strip above the arena (a frame or video: nothing is covered)."""
        if selected is not None:
            about = robot_line(selected, state.agents)
        else:
            total = sum(r.collisions for r in scene.robots)
            about = f"{len(scene.robots)} robots, {total} collision(s) in all"
        text = self.small.render(f"t = {scene.time:.2f} s    {about}", True, pal.HUD_TEXT)
        surface.blit(text, (8, max(1, (state.band - text.get_height()) // 2)))
        self._scale_bar(surface, camera, band=state.band)

    def _panel(self, surface: pygame.Surface, lines, pos: tuple[int, int], font) -> None:
        surface.blit(self._render_panel(lines, font), pos)

    @staticmethod
    def _free_corner(surface: pygame.Surface, size: tuple[int, int], scene: Scene,
                     camera: Camera) -> tuple[int, int]:
        """Top left, unless a robot is under it there: then the top corner (or, failing that,
        the bottom right) with the fewest robots under it. The HUD never hides a robot that
        could be shown."""
        w, h = surface.get_size()
        pw, ph = size
        corners = [(8, 8), (w - pw - 8, 8), (w - pw - 8, h - ph - 48)]

        def covered(corner: tuple[int, int]) -> int:
            rect = pygame.Rect(corner, size)
            count = 0
            for robot in scene.robots:
                sx, sy = camera.to_screen(float(robot.pose[0]), float(robot.pose[1]))
                r = robot.radius * camera.scale + 4
                if rect.inflate(2 * r, 2 * r).collidepoint(sx, sy):
                    count += 1
            return count

        return min(corners, key=lambda c: (covered(c), corners.index(c)))

    def _render_panel(self, lines, font) -> pygame.Surface:
        rendered = [font.render(text, True, colour) for text, colour in lines]
        width = max(t.get_width() for t in rendered) + 16
        height = sum(t.get_height() + 2 for t in rendered) + 10
        panel = pygame.Surface((width, height), pygame.SRCALPHA)
        panel.fill(pal.HUD_BACK)
        y = 6
        for t in rendered:
            panel.blit(t, (8, y))
            y += t.get_height() + 2
        return panel

    def _scale_bar(self, surface: pygame.Surface, camera: Camera, band: int = 0) -> None:
        """A bar of a round length near 100 px, bottom left: on a panel over the scene, or bare
        in the ``band`` [px] below the arena."""
        target = 100.0 / camera.scale  # [m]
        length = next((m * 10.0 ** e for e in range(-3, 4) for m in (1, 2, 5)
                       if m * 10.0 ** e >= target * 0.6), 1000.0)
        px = int(round(length * camera.scale))
        _, h = surface.get_size()
        label = f"{length:g} m" if length >= 1 else f"{length * 100:g} cm"
        text = self.small.render(label, True, pal.HUD_TEXT)
        height = 26 if not band else band
        panel = pygame.Surface((px + 20 + text.get_width() + 8, height), pygame.SRCALPHA)
        if not band:
            panel.fill(pal.HUD_BACK)
        y = height // 2 + 4 if not band else height // 2
        pygame.draw.line(panel, pal.HUD_TEXT, (8, y), (8 + px, y), 3)
        pygame.draw.line(panel, pal.HUD_TEXT, (8, y - 6), (8, y + 5), 2)
        pygame.draw.line(panel, pal.HUD_TEXT, (8 + px, y - 6), (8 + px, y + 5), 2)
        panel.blit(text, (16 + px, 6 if not band else y - text.get_height() // 2))
        surface.blit(panel, (8, h - 34) if not band else (0, h - band))

    def _help(self, surface: pygame.Surface, rows) -> None:
        keys = [self.font.render(k, True, pal.HUD_WARN) for k, _ in rows]
        what = [self.font.render(d, True, pal.HUD_TEXT) for _, d in rows]
        key_w = max(k.get_width() for k in keys) + 24
        width = key_w + max(d.get_width() for d in what) + 32
        row_h = keys[0].get_height() + 6
        height = row_h * len(rows) + 24
        panel = pygame.Surface((width, height), pygame.SRCALPHA)
        panel.fill((20, 22, 26, 230))
        for i, (k, d) in enumerate(zip(keys, what)):
            panel.blit(k, (16, 12 + i * row_h))
            panel.blit(d, (16 + key_w, 12 + i * row_h))
        w, h = surface.get_size()
        surface.blit(panel, ((w - width) // 2, max(8, (h - height) // 2)))


def robot_line(r: RobotView, agents: frozenset[str] = frozenset()) -> str:
    """The robot's speed, collisions and who drives it. A robot driven by a program (the agent
    of a Gymnasium env) is labelled so, not as a robot without a controller under teleop."""
    v, omega = r.velocity
    turn = f"{omega:+.2f}" if abs(omega) >= 0.005 else "0.00"
    line = f"{r.name}{' (agent)' if r.name in agents else ''}: {abs(v):.2f} m/s, {turn} rad/s, " \
           f"{r.collisions} collision(s)"
    if r.nav_goal is None and r.goal_reached:
        line += ", goal reached"
    if r.name in agents:
        return line
    if r.nav_goal is None and r.status not in ("", "running"):
        line += f", {r.status}"  # with a drive-to goal, its own line says
    return line + ("  TELEOP" if r.teleop else "")


def goal_lines(r: RobotView) -> list[tuple[str, tuple[int, int, int]]]:
    """With a drive-to goal (a click, or the controller block's own goal), one line for it and
    one for the task goal, saying what each means: the robot drives to the first; the run is
    judged on the second."""
    if r.nav_goal is None:
        return []
    status = "driving" if r.status in ("", "running") else r.status
    lines = [(f"drive-to goal ({r.nav_goal[0]:.2f}, {r.nav_goal[1]:.2f}), dashed: {status}",
              pal.HUD_TEXT)]
    if r.goal is not None:
        reached = "reached" if r.goal_reached else "NOT reached"
        lines.append((f"task goal ({r.goal[0]:.2f}, {r.goal[1]:.2f}), solid: {reached}, "
                      "judges the run", pal.HUD_TEXT if r.goal_reached else pal.HUD_WARN))
    return lines
