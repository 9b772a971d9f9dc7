"""Ctrl-C at any moment of `pymunk-bot`'s start-up (imports, building the parser, loading the
scenario) ends it with one line, never a KeyboardInterrupt traceback."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from bounds import HANG_GUARD

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("delay", [0.15, 0.2, 0.3, 0.45, 0.7])
def test_ctrl_c_during_start_up_is_one_line(delay):
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(REPO)}
    # The default Ctrl-C disposition, as in a terminal: a test runner's worker (pytest-xdist)
    # may ignore SIGINT, and a child inherits an ignored signal.
    # A long run, so the signal never comes after it has finished (a warm start takes 0.5 s).
    proc = subprocess.Popen([sys.executable, "-m", "pymunk_bot", "run", "maze", "--headless",
                             "--duration", "600"],
                            cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=lambda: signal.signal(signal.SIGINT,
                                                                        signal.SIG_DFL))
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=HANG_GUARD)
    if "Traceback" in err and not _frames_past_the_entry_point(err):
        # Python itself was still starting (importing site, runpy finding the module): no program
        # can handle a signal then. Seen on a loaded machine only.
        pytest.skip("the signal came before pymunk-bot's entry point ran")
    assert "Traceback" not in err, err
    assert len(err.strip().splitlines()) <= 1, err
    assert proc.returncode in (130, -signal.SIGINT), (proc.returncode, err)


def _frames_past_the_entry_point(err: str) -> list[str]:
    """The traceback's frames in pymunk-bot's own code, past the package files that lead to
    the command line (``pymunk_bot.cli.entry`` imports it inside a Ctrl-C handler)."""
    entry = ("pymunk_bot/__init__.py", "pymunk_bot/__main__.py", "pymunk_bot/cli/entry.py")
    frames = re.findall(r'File "([^"]+)"', err)
    return [f for f in frames if "pymunk_bot/" in f and not f.endswith(entry)]
