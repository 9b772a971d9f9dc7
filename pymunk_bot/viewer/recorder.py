"""Offscreen video recording (.mp4 through imageio-ffmpeg's ffmpeg, .gif through Pillow).

Frame k shows the state after round(k / fps / dt) physics steps, so a recording samples exactly
the trajectory a headless run computes; when it ends, a live simulation has been advanced by
exactly as many steps as ``Simulation.run(duration)`` would take.
"""
from __future__ import annotations

import contextlib
import math
import os
import subprocess
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pymunk_bot.outcomes.results import temp_beside, termination_deferred
from pymunk_bot.viewer._pygame import require_pygame

pygame = require_pygame()

from pymunk_bot.viewer.app import Viewer  # noqa: E402
from pymunk_bot.viewer.camera import FIT_MARGIN  # noqa: E402
from pymunk_bot.viewer.sources import LiveSource, ReplaySource  # noqa: E402

if TYPE_CHECKING:
    from pygame import Surface

FORMATS = (".mp4", ".gif")
DEFAULT_FPS = {".mp4": 30.0, ".gif": 10.0}  # [Hz]; GIF delays are whole 1/100 s: 10 fps is exact
GIF_COLOURS = 64  # one palette for a whole GIF: the scene's flat colours and their edges
LONG_SIDE = {".mp4": 1280, ".gif": 720}  # [px] default frame size along the arena's long side
MARGIN = FIT_MARGIN  # [px] around the arena


def default_size(arena: tuple[float, float], ext: str) -> tuple[int, int]:
    """A frame shaped like the arena, its sides multiples of 16 (what H.264 encoders like)."""
    width, height = arena
    long_side = LONG_SIDE[ext]
    scale = (long_side - 2 * MARGIN) / max(width, height)
    w = int(round((width * scale + 2 * MARGIN) / 16)) * 16
    h = int(round((height * scale + 2 * MARGIN) / 16)) * 16
    return max(w, 160), max(h, 160)


def record(source, path: str | Path, duration: float | None = None, fps: float | None = None,
           size: tuple[int, int] | None = None, progress: bool = True) -> int:
    """Render a Simulation or RunLog to ``path`` (.mp4 or .gif), atomically; returns frames written.

    ``duration`` [s] defaults to the whole log for a RunLog and is required for a Simulation.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in FORMATS:
        raise ValueError(f"cannot record to '{path.suffix}': use .mp4 or .gif")
    frames_source: LiveSource | ReplaySource
    if hasattr(source, "step"):
        frames_source = LiveSource(source)
        if duration is None:
            raise ValueError("duration is required to record a simulation")
    else:
        frames_source = ReplaySource(source)
        end = float(source.time[-1])
        duration = end if duration is None else min(duration, end)
    fps = float(fps or DEFAULT_FPS[ext])
    if not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be > 0 (got {fps})")
    if size is None:
        size = default_size(frames_source.size, ext)
    size = (int(size[0]) + int(size[0]) % 2, int(size[1]) + int(size[1]) % 2)  # H.264: even
    viewer = Viewer(frames_source, size)
    viewer.recording = True
    surface = pygame.Surface(size)
    dt = frames_source.dt
    n_frames = int(math.floor(duration * fps + 1e-9)) + 1  # frame 0 shows the start
    tmp: str | None = None
    writer: _GifWriter | _Mp4Writer | None = None
    try:
        with termination_deferred():  # both or neither: a part file is never left unowned
            tmp = _temp_name(path)
            writer = _open_writer(tmp, ext, fps, size)
        for k in _progress(range(n_frames), progress, path.name):
            _advance_to(frames_source, round(k / fps / dt))
            viewer.draw(surface)
            writer.append(_pixels(surface))
        writer.close()
        # End where a headless run of the same duration ends.
        _advance_to(frames_source, round(duration / dt))
        os.replace(tmp, path)
    except BaseException:
        if writer is not None:
            writer.abort()
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
        raise
    return n_frames


def _advance_to(source: LiveSource | ReplaySource, steps: int) -> None:
    while source.steps < steps and not source.at_end:
        source.step()


def _pixels(surface: Surface) -> np.ndarray:
    """(H, W, 3) uint8 RGB (tobytes is ten times faster than surfarray here)."""
    w, h = surface.get_size()
    return np.frombuffer(pygame.image.tobytes(surface, "RGB"), np.uint8).reshape(h, w, 3)


def _temp_name(path: Path) -> str:
    """A fresh file next to ``path`` with the same extension (the writers pick the format by it)."""
    return temp_beside(path, f".part{path.suffix.lower()}")


def _progress(frames, enabled: bool, name: str):
    if not enabled:
        return frames
    from tqdm import tqdm

    # disable=None: no bar when stderr is not a terminal (logs, CI).
    return tqdm(frames, desc=f"recording {name}", unit="frame", disable=None, leave=False)


class _GifWriter:
    """GIF through Pillow (imageio's own GIF backend), called directly to control quantisation.

    One palette for the whole clip, made from the first frame (the scene's colours do not
    change): successive frames then differ only where something moved, so Pillow stores just
    the changed rectangle of each, and LZW compresses the unchanged colours well. No dithering:
    line art stays crisp. Memory: one byte per pixel per frame until the file is written.
    """

    def __init__(self, path: str, fps: float) -> None:
        from PIL import Image

        self._image = Image
        self._path = path
        self._frames: list = []
        self._palette = None
        self._delay = int(round(1000.0 / fps))  # [ms]; GIF stores whole hundredths of a second

    def append(self, frame: np.ndarray) -> None:
        Image = self._image
        image = Image.fromarray(frame)
        if self._palette is None:
            self._palette = image.quantize(colors=GIF_COLOURS, method=Image.Quantize.FASTOCTREE,
                                           dither=Image.Dither.NONE)
            self._frames.append(self._palette)
            return
        self._frames.append(image.quantize(palette=self._palette, dither=Image.Dither.NONE))

    def close(self) -> None:
        if self._frames:
            first, rest = self._frames[0], self._frames[1:]
            first.save(self._path, format="GIF", save_all=True, append_images=rest,
                       duration=self._delay, loop=0, optimize=False, disposal=1)
        self._frames = []

    def abort(self) -> None:
        """Drop the frames (idempotent)."""
        self._frames = []


class _Mp4Writer:
    """H.264 in MP4: frames piped to the ffmpeg that imageio-ffmpeg ships, streamed (memory does
    not grow with length).

    The process is ours, so an interrupted recording stops it *before* its part file is removed:
    ffmpeg creates its output only when input (or the end of input) arrives, so an ffmpeg left
    running would create the removed file again.
    """

    def __init__(self, path: str, fps: float, size: tuple[int, int]) -> None:
        import imageio_ffmpeg

        width, height = size
        command = [imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-loglevel", "error",
                   "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{width}x{height}",
                   "-r", f"{fps:.12g}", "-i", "-", "-an", "-c:v", "libx264", "-pix_fmt", "yuv420p",
                   # crf 20 keeps thin lines sharp at a few hundred kB per simulated minute.
                   "-crf", "20", "-preset", "fast", path]
        self._errors = tempfile.TemporaryFile()  # a file, not a pipe: ffmpeg can never block on it
        # Its own session: a Ctrl-C in the terminal reaches only us, and we stop ffmpeg.
        self._process = subprocess.Popen(command, stdin=subprocess.PIPE,
                                         stdout=subprocess.DEVNULL, stderr=self._errors,
                                         start_new_session=True)

    def append(self, frame: np.ndarray) -> None:
        stdin = self._process.stdin
        assert stdin is not None
        try:
            stdin.write(frame.tobytes())
        except BrokenPipeError:  # ffmpeg stopped reading: it has said why
            self._process.wait()
            self._fail()

    def close(self) -> None:
        stdin = self._process.stdin
        assert stdin is not None
        try:
            stdin.close()
        except BrokenPipeError:
            pass
        if self._process.wait() != 0:
            self._fail()
        self._errors.close()

    def abort(self) -> None:
        """Stop ffmpeg and wait until it is gone (idempotent)."""
        self._process.kill()
        self._process.wait()
        if self._process.stdin is not None:
            with contextlib.suppress(OSError):
                self._process.stdin.close()
        self._errors.close()

    def _fail(self) -> None:
        self._errors.seek(0)
        message = self._errors.read().decode(errors="replace").strip().splitlines()
        raise RuntimeError(f"ffmpeg failed (exit {self._process.returncode}): "
                           f"{message[-1] if message else 'no message'}")


def _open_writer(path: str, ext: str, fps: float,
                 size: tuple[int, int]) -> _GifWriter | _Mp4Writer:
    return _GifWriter(path, fps) if ext == ".gif" else _Mp4Writer(path, fps, size)
