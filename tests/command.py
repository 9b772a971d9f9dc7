"""``pymunk-bot ARGS`` run in this process: the exit status, stdout and stderr that the
installed command gives, without a new interpreter's start-up (about 1 s of CPU each, a third
of the suite's CPU once). Tests of the start-up itself, of signals, of memory bounds, of hangs
and of separate processes keep real subprocesses."""
from __future__ import annotations

import contextlib
import io
import os
import subprocess
from pathlib import Path

from pymunk_bot.cli import main


def pymunk_bot(*args: object, cwd: str | Path | None = None) -> subprocess.CompletedProcess:
    """What ``pymunk-bot *args`` returns and prints, run from ``cwd`` (default: here)."""
    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.chdir(cwd or os.getcwd()), contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's usage errors
            code = exc.code if isinstance(exc.code, int) else 1
    return subprocess.CompletedProcess(["pymunk-bot", *argv], code, out.getvalue(), err.getvalue())
