"""Writing result files atomically: readers never see a half-written file."""
from __future__ import annotations

import contextlib
import json
import os
import signal
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path


def temp_beside(path: str | Path, suffix: str = ".tmp") -> str:
    """A new empty file in ``path``'s directory (so a rename onto ``path`` is atomic), with the
    permissions a plain ``open()`` would give it (mkstemp makes files private, 0600)."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=suffix, dir=directory)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    return tmp


@contextlib.contextmanager
def termination_deferred() -> Iterator[None]:
    """A SIGTERM that arrives inside the block is delivered when it ends: for steps that must not
    be cut in two (a part file created but not yet known to its cleanup; a child process forked
    but not yet owned). Outside the main thread, signals cannot be handled: the block just runs."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
        if caught:
            signal.raise_signal(signal.SIGTERM)  # now to the handler that was there before


def writable_problem(path: str | Path) -> str | None:
    """Why ``path`` cannot be written atomically (None if it can): checked before a run, by
    creating and removing a temporary file beside it (``os.access`` is fooled by /proc and
    read-only mounts when running as root)."""
    path = Path(path)
    if path.is_dir():
        return f"{path} is a directory"
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        return f"{path}: directory {parent} does not exist"
    if path.exists() and not path.is_file():
        return f"{path} exists and is not a regular file"
    try:
        Path(temp_beside(path)).unlink()
    except OSError as exc:
        return f"{path}: cannot write in {parent} ({exc.strerror or exc})"
    return None


def write_atomic(path: str | Path, data: bytes) -> None:
    """Write to a temporary file beside ``path``, fsync, then rename over ``path``."""
    tmp = temp_beside(path)
    try:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_json(path: str | Path, result: dict) -> None:
    write_atomic(path, (json.dumps(result, indent=2) + "\n").encode("utf-8"))
