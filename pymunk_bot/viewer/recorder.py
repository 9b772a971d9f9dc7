"""Offscreen video recording (.mp4 through imageio-ffmpeg's ffmpeg, .gif through Pillow).

Frame k shows the state after round(k / fps / dt) physics steps, so a recording samples exactly
the trajectory a headless run computes; when it ends, a live simulation has been advanced by
exactly as many steps as ``Simulation.run(duration)`` would take. A live run's video ends once
the run has settled (settling.py: every robot done and nothing moving for 1 s); the simulation
still runs to its end, headless.

The frames are encoded off the simulation's thread: a writer thread takes them from a short
queue and feeds the encoder (ffmpeg, a process of its own, or Pillow), so stepping and drawing
the next frame overlap with encoding this one, and memory stays bounded.
"""
from __future__ import annotations

import contextlib
import math
import os
import queue
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

from pymunk_bot.outcomes.results import temp_beside, termination_deferred
from pymunk_bot.viewer.display import require_pygame

pygame = require_pygame()

from pymunk_bot.viewer.app import Viewer  # noqa: E402
from pymunk_bot.viewer.camera import FIT_MARGIN  # noqa: E402
from pymunk_bot.viewer.settling import Settling  # noqa: E402
from pymunk_bot.viewer.sources import LiveSource, ReplaySource  # noqa: E402

if TYPE_CHECKING:
    from pygame import Surface

FORMATS = (".mp4", ".gif")
DEFAULT_FPS = {".mp4": 30.0, ".gif": 10.0}  # [Hz]; GIF delays are whole 1/100 s: 10 fps is exact
GIF_COLOURS = 64  # one palette for a whole GIF: the scene's flat colours and their edges
LONG_SIDE = {".mp4": 1280, ".gif": 720}  # [px] default frame size along the arena's long side
MARGIN = FIT_MARGIN  # [px] around the arena
QUEUE_FRAMES = 8  # frames waiting for the encoder at most (8 x 5 MB at 1280 x 1280)


def default_size(arena: tuple[float, float], ext: str) -> tuple[int, int]:
    """A frame shaped like the arena, its sides multiples of 16 (what H.264 encoders like)."""
    width, height = arena
    long_side = LONG_SIDE[ext]
    scale = (long_side - 2 * MARGIN) / max(width, height)
    w = int(round((width * scale + 2 * MARGIN) / 16)) * 16
    h = int(round((height * scale + 2 * MARGIN) / 16)) * 16
    return max(w, 160), max(h, 160)


def record(source, path: str | Path, duration: float | None = None, fps: float | None = None,
           size: tuple[int, int] | None = None, progress: bool = True,
           until_settled: bool = True) -> int:
    """Render a Simulation or RunLog to ``path`` (.mp4 or .gif), atomically; returns frames written.

    ``duration`` [s] defaults to the whole log for a RunLog and is required for a Simulation.
    ``until_settled``: a Simulation's video ends once the run has settled (every robot done,
    nothing moving for 1 s: settling.py), though the simulation still runs ``duration``; a
    RunLog's replay always shows the whole log.
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
    settling = Settling() if until_settled and isinstance(frames_source, LiveSource) else None
    written = 0
    tmp: str | None = None
    writer: _Background | None = None
    try:
        with termination_deferred():  # both or neither: a part file is never left unowned
            tmp = _temp_name(path)
            layout = _layout(surface)
            writer = _Background(_open_writer(tmp, ext, fps, size, layout))
        for k in _progress(range(n_frames), progress, path.name):
            _advance_to(frames_source, round(k / fps / dt))
            viewer.draw(surface)
            writer.append(_pixels(surface, layout))
            written += 1
            if settling is not None and settling.settled(frames_source.scene()):
                break  # nothing more would change on screen but the clock
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
    return written


def _advance_to(source: LiveSource | ReplaySource, steps: int) -> None:
    while source.steps < steps and not source.at_end:
        source.step()


def _layout(surface: Surface) -> str:
    """How a frame's bytes are laid out, in ffmpeg's names: ``bgr0`` when the surface's own
    memory is 32-bit pixels stored blue, green, red, unused without padding (pygame's usual
    surface on a little-endian machine), so a frame is one copy of it; else ``rgb24``."""
    if (surface.get_bitsize() == 32 and surface.get_masks()[:3] == (0xFF0000, 0xFF00, 0xFF)
            and sys.byteorder == "little" and surface.get_pitch() == 4 * surface.get_width()):
        return "bgr0"
    return "rgb24"


def _pixels(surface: Surface, layout: str) -> bytes:
    """A copy of the frame's pixels, laid out as ``layout`` says (``_layout``)."""
    if layout == "bgr0":
        return surface.get_buffer().raw  # a plain copy: a fifth of a conversion's time
    return pygame.image.tobytes(surface, "RGB")  # ten times faster than surfarray here


def _temp_name(path: Path) -> str:
    """A fresh file next to ``path`` with the same extension (the writers pick the format by it)."""
    return temp_beside(path, f".part{path.suffix.lower()}")


def _progress(frames, enabled: bool, name: str):
    if not enabled:
        return frames
    from tqdm import tqdm

    # disable=None: no bar when stderr is not a terminal (logs, CI).
    return tqdm(frames, desc=f"recording {name}", unit="frame", disable=None, leave=False)


class _Background:
    """A GIF or MP4 writer fed from a thread of its own through a queue of QUEUE_FRAMES frames:
    ``append`` returns at once unless the encoder is that far behind. An error in the writer
    comes out of the next ``append`` or ``close``.

    ``abort`` does not rely on the queue: it runs after an interrupt (Ctrl-C, SIGTERM), which
    may have struck inside the queue's own locking and left it unable to wake the thread (seen
    once: the thread waited for ever on a ``get`` that the end mark never woke). The thread polls
    a stop flag instead, and an abort waits for it at most ABORT_WAIT (it is a daemon).
    """

    _END = None
    POLL = 0.05  # [s] how often the idle thread looks at the stop flag
    ABORT_WAIT = 2.0  # [s] at most, for the thread to stop after an abort
    PUT_POLL = 0.002  # [s] how often a full queue is tried again (a frame takes milliseconds)

    def __init__(self, writer: _GifWriter | _Mp4Writer) -> None:
        self._writer = writer
        self._frames: queue.Queue = queue.Queue(maxsize=QUEUE_FRAMES)
        self._error: BaseException | None = None
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._work, name="video writer", daemon=True)
        self._thread.start()

    def _work(self) -> None:
        while True:
            try:
                frame = self._frames.get(timeout=self.POLL)
            except queue.Empty:
                if self._stopping.is_set():
                    return
                continue
            if frame is self._END or self._stopping.is_set():
                return
            if self._error is None:  # after an error, drain so that no put blocks
                try:
                    self._writer.append(frame)
                except BaseException as exc:  # handed to the recording's thread
                    self._error = exc

    def _raise(self) -> None:
        if self._error is not None:
            raise self._error

    def _put(self, item: bytes | None) -> None:
        """Queue ``item`` once there is room, polling: waiting inside the queue, an interrupt
        (SIGTERM's SystemExit) that struck inside ``Condition.wait``, between its release and
        re-acquire of the queue's lock, surfaced as "release unlocked lock" instead."""
        while self._thread.is_alive():
            try:
                self._frames.put_nowait(item)
                return
            except queue.Full:
                self._raise()
                time.sleep(self.PUT_POLL)

    def append(self, frame: bytes) -> None:
        """Queue ``frame``, one frame's pixels (``_pixels``)."""
        self._raise()
        self._put(frame)

    def close(self) -> None:
        """Write what is queued and finish the file."""
        self._put(self._END)
        self._thread.join()
        self._raise()
        self._writer.close()

    def abort(self) -> None:
        """Stop the encoder and the thread (idempotent; at most ABORT_WAIT)."""
        self._stopping.set()
        self._writer.abort()  # a write blocked on ffmpeg's pipe fails at once
        self._thread.join(timeout=self.ABORT_WAIT)


class _GifWriter:
    """GIF through Pillow (imageio's own GIF backend), called directly to control quantisation.

    One palette for the whole clip, made from the first frame (the scene's colours do not
    change): successive frames then differ only where something moved, so Pillow stores just
    the changed rectangle of each, and LZW compresses the unchanged colours well. No dithering:
    line art stays crisp. Memory: one byte per pixel per frame until the file is written.
    """

    def __init__(self, path: str, fps: float, size: tuple[int, int], layout: str) -> None:
        from PIL import Image

        self._image = Image
        self._size = size
        self._raw_mode = "BGRX" if layout == "bgr0" else "RGB"  # Pillow's name for the layout
        self._path = path
        self._frames: list = []
        self._palette = None
        self._delay = int(round(1000.0 / fps))  # [ms]; GIF stores whole hundredths of a second

    def append(self, frame: bytes) -> None:
        Image = self._image
        image = Image.frombuffer("RGB", self._size, frame, "raw", self._raw_mode, 0, 1)
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

    def __init__(self, path: str, fps: float, size: tuple[int, int], layout: str) -> None:
        import imageio_ffmpeg

        width, height = size
        command = [imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-loglevel", "error",
                   "-f", "rawvideo", "-pix_fmt", layout, "-s", f"{width}x{height}",
                   "-r", f"{fps:.12g}", "-i", "-", "-an", "-c:v", "libx264", "-pix_fmt", "yuv420p",
                   # crf 20 keeps thin lines sharp at a few hundred kB per simulated minute.
                   # veryfast: half the CPU of fast for this flat line art, files about as large.
                   "-crf", "20", "-preset", "veryfast", path]
        self._errors = tempfile.TemporaryFile()  # a file, not a pipe: ffmpeg can never block on it
        # Its own session: a Ctrl-C in the terminal reaches only us, and we stop ffmpeg.
        self._process = subprocess.Popen(command, stdin=subprocess.PIPE,
                                         stdout=subprocess.DEVNULL, stderr=self._errors,
                                         start_new_session=True)

    def append(self, frame: bytes) -> None:
        stdin = self._process.stdin
        assert stdin is not None
        try:
            stdin.write(frame)
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


def _open_writer(path: str, ext: str, fps: float, size: tuple[int, int],
                 layout: str) -> _GifWriter | _Mp4Writer:
    if ext == ".gif":
        return _GifWriter(path, fps, size, layout)
    return _Mp4Writer(path, fps, size, layout)
