"""``run --log run.mcap``: a simulation observer that writes an MCAP file atomically.

Messages go to a temporary file beside the target (chunked, zstd-compressed, with a summary
and message indexes so tools can seek); :meth:`McapLogger.save` closes it and renames it onto
the target. :meth:`McapLogger.abort` (or garbage collection, or the interpreter exiting)
removes the temporary file, so an error or Ctrl-C leaves nothing behind.
"""
from __future__ import annotations

import errno
import json
import os
import weakref
from pathlib import Path

import foxglove
from foxglove.mcap import MCAPCompression, MCAPWriteOptions

from pymunk_bot.outcomes.results import naming, temp_beside
from pymunk_bot.foxglove.frames import METADATA_NAME
from pymunk_bot.foxglove.publisher import Publisher, SimPublisher

PROFILE = ""  # Foxglove's own schemas: no ROS profile
CHUNK_SIZE = 4 * 1024 * 1024  # [bytes] uncompressed per chunk; big chunks compress better


def open_writer(path: str | Path, context: foxglove.Context):
    """An SDK MCAP writer on ``context`` writing to ``path`` (which may already exist)."""
    options = MCAPWriteOptions(compression=MCAPCompression.Zstd, chunk_size=CHUNK_SIZE,
                               profile=PROFILE, compression_threads=0)
    return foxglove.open_mcap(path, allow_overwrite=True, context=context,
                              writer_options=options)


class McapWriter:
    """An MCAP file being written through a Publisher; nothing appears at ``path`` until
    :meth:`commit`."""

    def __init__(self, path: str | Path, context: foxglove.Context | None = None) -> None:
        self.path = Path(path)
        self.context = context or foxglove.Context()
        self._tmp = temp_beside(self.path, suffix=".mcap.tmp")
        self._cleanup = weakref.finalize(self, _remove, self._tmp)
        self._writer = open_writer(self._tmp, self.context)
        self.publisher = Publisher(self.context)
        self.messages_written = 0

    def commit(self) -> None:
        """Write the run's metadata, close the file and move it onto ``path``."""
        geometry = self.publisher.geometry
        try:
            if geometry is not None:
                self._writer.write_metadata(METADATA_NAME, {"runlog": json.dumps(geometry.meta)})
            self._writer.close()
            os.replace(self._tmp, self.path)
        except OSError as exc:
            self.abort()
            raise naming(exc, self.path) from exc
        except RuntimeError as exc:  # the SDK's own error for a write that failed (a full disk)
            self.abort()
            raise OSError(errno.EIO, f"cannot finish the MCAP file ({exc})", str(self.path)) \
                from exc
        self._cleanup.detach()

    def abort(self) -> None:
        """Close and delete the unfinished file."""
        try:
            self._writer.close()
        except (OSError, RuntimeError):  # the tail of a file being deleted: nothing is lost
            pass
        finally:
            self._cleanup()


class McapLogger:
    """Records a simulation to MCAP after every step: :meth:`attach`, run, :meth:`save`.

    Survives ``sim.reset()`` (the file then holds the run since the reset, announced in /log).
    """

    def __init__(self, path: str | Path, context: foxglove.Context | None = None) -> None:
        self.path = Path(path)
        self._file = McapWriter(path, context)
        self.observer = SimPublisher(self._file.publisher)
        self.steps = 0

    @property
    def context(self) -> foxglove.Context:
        return self._file.context

    def attach(self, sim) -> "McapLogger":
        """Start recording ``sim`` from its present state."""
        self.observer.on_reset(sim)
        if self not in sim.observers:
            sim.observers.append(self)
        return self

    def on_reset(self, sim) -> None:
        self.steps = 0
        self.observer.on_reset(sim)

    def __call__(self, sim) -> None:
        self.steps += 1
        self.observer(sim)

    def save(self, path: str | Path | None = None) -> None:
        """Finish the file (``path`` must be the one given at construction, if given)."""
        if path is not None and Path(path) != self.path:
            raise ValueError(f"this logger writes {self.path}, not {path}")
        self._file.commit()

    def abort(self) -> None:
        """Drop the unfinished file."""
        self._file.abort()


def _remove(path: str) -> None:
    Path(path).unlink(missing_ok=True)
