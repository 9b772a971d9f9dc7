"""The interactive window: a pygame display around a :class:`~.app.Viewer`."""
from __future__ import annotations

from pymunk_bot.viewer.display import open_display, require_pygame

pygame = require_pygame()  # before the modules below import it: a clear error if missing

from pymunk_bot.viewer.app import Viewer  # noqa: E402
from pymunk_bot.viewer.input import InputHandler  # noqa: E402
from pymunk_bot.viewer.sources import LiveSource, ReplaySource  # noqa: E402

FPS = 60  # [Hz] frames drawn per second at most
MAX_FRAME_GAP = 0.25  # [s]; a longer stall (window dragged, machine busy) is not caught up
PREFERRED_SIZE = (1200, 800)  # [px] largest initial window
MIN_SIZE = (480, 320)  # [px]


def run_window(sim, duration: float | None = None) -> None:
    """Show a live simulation until the user quits (see :func:`pymunk_bot.viewer.run_window`)."""
    _loop(LiveSource(sim), duration, f"pymunk-bot: {sim.config.name}")


def replay_window(log) -> None:
    """Play a run log until the user quits."""
    _loop(ReplaySource(log), None, f"pymunk-bot replay: {log.meta['scenario']}")


def initial_size(arena: tuple[float, float], desktop: tuple[int, int] | None) -> tuple[int, int]:
    """A window shaped like the arena, as large as PREFERRED_SIZE and 85% of the desktop allow."""
    limit_w, limit_h = PREFERRED_SIZE
    if desktop is not None and desktop[0] > 0 and desktop[1] > 0:
        limit_w = min(limit_w, int(0.85 * desktop[0]))
        limit_h = min(limit_h, int(0.85 * desktop[1]))
    width, height = arena
    scale = min(limit_w / width, limit_h / height)
    return (max(MIN_SIZE[0], int(width * scale) + 48), max(MIN_SIZE[1], int(height * scale) + 48))


def _desktop() -> tuple[int, int] | None:
    try:
        sizes = pygame.display.get_desktop_sizes()
    except (pygame.error, AttributeError):
        return None
    return tuple(sizes[0]) if sizes else None


def _loop(source, duration: float | None, title: str) -> None:
    open_display()
    size = initial_size(source.size, _desktop())
    screen = pygame.display.set_mode(size, pygame.RESIZABLE)
    pygame.display.set_caption(title)
    viewer = Viewer(source, screen.get_size(), duration)
    handler = InputHandler(viewer)
    clock = pygame.time.Clock()
    try:
        while viewer.running:
            real_dt = min(clock.tick(FPS) / 1000.0, MAX_FRAME_GAP)
            for event in pygame.event.get():
                handler.handle(event)
            if not viewer.running:
                break
            viewer.advance(real_dt)
            screen = pygame.display.get_surface()
            if screen.get_size() != (viewer.camera.width, viewer.camera.height):
                viewer.resize(screen.get_size())
            viewer.draw(screen)
            pygame.display.flip()
    finally:
        pygame.display.quit()
