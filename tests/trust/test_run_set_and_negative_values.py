"""`run --set KEY=VALUE` changes one value for one run with sweep's checks; a value that starts
with a minus sign reaches its option's own check instead of argparse's "expected one argument"."""
from __future__ import annotations

import json

import pytest

from pymunk_bot.cli import main


def one_line_exit_2(capsys, argv: list[str], *fragments: str) -> None:
    code = None
    try:
        code = main(argv)
    except SystemExit as exit_:
        code = exit_.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("error: ") and "Traceback" not in err, err
    for fragment in fragments:
        assert fragment in err, err


def test_run_set_changes_the_value_for_this_run(tmp_path, capsys):
    out = tmp_path / "r.json"
    main(["run", "--headless", "--duration", "0.5", "--out", str(out),
          "--set", "robots[0].pose=[2.5, 2.0, 0.0]", "--set", "robots[0].max_wheel_speed=0.05"])
    x, y, _ = json.loads(out.read_text())["robots"]["r1"]["pose"]
    assert abs(x - 2.5) < 0.05 and abs(y - 2.0) < 0.05  # started there, barely moved


@pytest.mark.parametrize("setting, fragments", [
    ("robots[0].max_wheel_speed=0.5,1.0", ("--set", "one value per key")),
    ("robots[0].max_wheel_speed=-1", ("robots[0].max_wheel_speed", "with --set")),
    ("world.dtt=0.01", ("world.dtt", "did you mean 'dt'")),
    ("robots[7].radius=0.1", ("robots[7]", "no such item")),
    ("no equals sign", ("--set", "expected KEY.PATH=VALUE")),
])
def test_run_set_is_checked_as_sweep_set(capsys, setting, fragments):
    one_line_exit_2(capsys, ["run", "--headless", "--set", setting], *fragments)


def test_run_set_twice_is_refused(capsys):
    one_line_exit_2(capsys, ["run", "--headless", "--set", "world.dt=0.01",
                             "--set", "world.dt=0.02"], "set twice")


@pytest.mark.parametrize("argv, fragment", [
    (["sweep", "default", "--seeds", "-3:2", "--out", "x.csv"], "seeds '-3:2'"),
    (["run", "--headless", "--duration", "-3"], "--duration"),
    (["run", "--headless", "--seed", "-1"], "--seed"),
])
def test_a_negative_value_reaches_its_options_check(capsys, tmp_path, monkeypatch, argv,
                                                     fragment):
    monkeypatch.chdir(tmp_path)
    one_line_exit_2(capsys, argv, fragment)
    assert "expected one argument" not in capsys.readouterr().err


def test_run_set_echoes_each_effective_value_on_stderr(tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["run", "--headless", "--duration", "0.2", "--out", str(out),
                 "--set", "robots[0].max_wheel_speed=0.8", "--set", "world.dt=0.01",
                 "--set", "robots[0].lidar.beams=90"]) in (0, 1)
    captured = capsys.readouterr()
    echoed = [line for line in captured.err.splitlines() if line.startswith("set ")]
    assert echoed == ["set robots[0].max_wheel_speed = 0.8 (was 1.0)",
                      "set world.dt = 0.01 (was 0.016666666666666666)",
                      "set robots[0].lidar.beams = 90 (was 360)"], captured.err
    assert "set " not in captured.out  # stdout keeps only the run's own report
    assert json.loads(out.read_text())["robots"]["r1"]["pose"]  # --out is untouched JSON


def test_run_without_set_echoes_nothing(capsys):
    main(["run", "--headless", "--duration", "0.1"])
    assert "set " not in capsys.readouterr().err
