"""Writing result files atomically: readers never see a half-written file.

A file (or folder) being written is a hidden temporary beside its target, named
``.<target stem>.<pid>.<random><suffix>`` after the process writing it. An error or an
interrupt removes it; a process killed outright (SIGKILL, a power cut) cannot, so the next
temporary made beside the same target removes those whose process is gone.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import sys
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any


def _directory_of(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")


def _process_alive(pid: int) -> bool:
    """Whether process ``pid`` runs on this machine (True when it cannot be told)."""
    if sys.platform == "win32":  # os.kill there terminates: never guess
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process (EPERM): alive
        return True
    return True


def remove_stale_temps(path: str | Path, suffix: str) -> list[Path]:
    """Remove the temporaries beside ``path`` (files or folders named as :func:`temp_beside`
    names them, with ``suffix``) whose writing process has ended; returns what was removed."""
    path = Path(path)
    pattern = re.compile(rf"\.{re.escape(path.stem)}\.(\d+)\.[a-z0-9_]+{re.escape(suffix)}")
    removed: list[Path] = []
    try:
        entries = list(os.scandir(_directory_of(path)))
    except OSError:
        return removed
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None or _process_alive(int(match.group(1))):
            continue
        try:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
        except OSError:
            continue  # another run took it first, or it cannot be removed: not ours to insist
        removed.append(Path(entry.path))
    return removed


def _temp_prefix(path: Path) -> str:
    return f".{path.stem}.{os.getpid()}."


def temp_beside(path: str | Path, suffix: str = ".tmp") -> str:
    """A new empty file in ``path``'s directory (so a rename onto ``path`` is atomic), with the
    permissions a plain ``open()`` would give it (mkstemp makes files private, 0600). Those a
    killed process left beside ``path`` are removed first."""
    path = Path(path)
    remove_stale_temps(path, suffix)
    fd, tmp = tempfile.mkstemp(prefix=_temp_prefix(path), suffix=suffix, dir=_directory_of(path))
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    return tmp


def save_figure(fig: Any, path: str | Path, **options: Any) -> None:
    """Write the matplotlib figure ``fig`` to ``path`` atomically (a file beside it, renamed
    onto it), in the format its suffix names (.png without one); ``options`` go to
    ``savefig``. The figure stays open: the caller closes it."""
    path = Path(path)
    tmp = temp_beside(path, suffix=path.suffix or ".png")
    try:
        fig.savefig(tmp, **options)
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


def temp_folder_beside(path: str | Path, suffix: str = ".tmp") -> str:
    """A new empty folder beside ``path`` (renamed onto ``path`` when complete), named and
    cleaned up as :func:`temp_beside`'s files, with the permissions ``mkdir`` would give it."""
    path = Path(path)
    remove_stale_temps(path, suffix)
    folder = tempfile.mkdtemp(prefix=_temp_prefix(path), suffix=suffix, dir=_directory_of(path))
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(folder, 0o777 & ~umask)
    return folder


def naming(exc: OSError, path: str | Path) -> OSError:
    """``exc`` (a failed write) as the same error naming ``path``, the file the user asked
    for (not its temporary): the CLI prints ``error: PATH: No space left on device``."""
    return OSError(exc.errno, exc.strerror or str(exc), str(path))


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
    parent = _directory_of(path)
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
    """Write to a temporary file beside ``path``, fsync, then rename over ``path``. A failed
    write (a full disk) leaves ``path`` as it was and raises OSError naming ``path``."""
    try:
        tmp = temp_beside(path)
    except OSError as exc:
        raise naming(exc, path) from exc
    try:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise naming(exc, path) from exc
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_json(path: str | Path, result: dict) -> None:
    write_atomic(path, (json.dumps(result, indent=2) + "\n").encode("utf-8"))
