"""The ROS 2 options of `pymunk-bot run`: bad values are one line and exit 2; --rosbridge serves
a real run and stops when it ends."""
from __future__ import annotations

import pytest

from pymunk_bot.cli import main

pytest.importorskip("websockets")


@pytest.mark.parametrize("args, message", [
    (["--rosbridge", "--cmd-timeout", "0"], "--cmd-timeout: must be > 0"),
    (["--cmd-timeout", "1"], "--cmd-timeout: only applies with --rosbridge or --foxglove"),
    (["--rosbridge", "--port", "70000"], "--port: must be 0..65535"),
    (["--rosbridge", "--speed", "0"], "--speed: must be > 0"),
    (["--rosbridge", "--foxglove", "--port", "9999"], "--port: ambiguous"),
    (["--profile", "ros2"], "--profile: only applies with --log RUN.mcap"),
])
def test_bad_ros2_options_are_one_line(args, message, capsys):
    assert main(["run", "--headless", "--duration", "0.2", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err


def test_rosbridge_serves_a_run_and_stops(capsys):
    import time

    started = time.perf_counter()
    status = main(["run", "open_goal", "--headless", "--rosbridge", "--port", "0",
                   "--duration", "1", "--speed", "4"])
    wall = time.perf_counter() - started
    out = capsys.readouterr().out
    assert status in (0, 1) and "rosbridge: serving the run at ws://127.0.0.1:" in out
    # Paced at 4x real time, not as fast as it can (a loaded machine only makes it slower:
    # the upper bound is a hang guard).
    assert 0.25 <= wall < 120.0
