"""Sweeps: the grid, rows, resume after a crash, the CLI, and identical rows on every backend."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from pymunk_bot.cli import main as cli_main
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.sweep import backends, parse_assignment, parse_seeds, run_sweep, summarize
from pymunk_bot.sweep.output import journal_path
from dask_cluster import loopback_dask_cluster

ROOT = Path(__file__).resolve().parents[2]
SPEEDS = {"robots[0].max_wheel_speed": [0.5, 1.0]}


def sprint() -> dict:
    """A 4 s sprint to a goal 1.2 m away (2.5 s at 1 m/s, 3 s at 0.5 m/s); noisy sensors."""
    return {"name": "sprint", "world": {"size": [4.0, 2.0], "duration": 4.0},
            "robots": [{"name": "r1", "pose": [0.5, 1.0, 0.0],
                        "lidar": {"beams": 16, "noise_std": 0.02},
                        "odometry": {"wheel_noise_std": 0.02}, "localization": "ground_truth",
                        "controller": {"type": "go_to_goal"},
                        "goal": {"position": [1.7, 1.0], "tolerance": 0.1}}],
            "expect": {"r1": {"goal_reached": True, "within": 2.75}}}


def comparable(rows):
    return sorted((json.dumps(r, sort_keys=True) for r in rows))


# ---------------------------------------------------------------------------- grid


def test_assignments_and_seeds_parse_as_documented():
    assert parse_assignment("robots[0].max_wheel_speed=0.5,1.0") == (
        "robots[0].max_wheel_speed", [0.5, 1.0])
    assert parse_assignment("world.size=[10, 4],[12,5]") == ("world.size", [[10, 4], [12, 5]])
    assert parse_assignment("robots[0].lidar=null,{beams: 8}")[1] == [None, {"beams": 8}]
    assert parse_seeds("0:20") == list(range(20)) and parse_seeds("3,5") == [3, 5]
    for bad in ("5:2", "-1", "a", "1,1"):
        with pytest.raises(ValueError):
            parse_seeds(bad)
    for bad in ("novalue", "=1", "a..b=1", "x=1,,2"):
        with pytest.raises(ValueError):
            parse_assignment(bad)


def test_rows_carry_values_seed_passed_and_flattened_robot_fields():
    rows = run_sweep(sprint(), SPEEDS, seeds=range(3))
    assert len(rows) == 6 and [r["run"] for r in rows] == list(range(6))
    first = rows[0]
    assert list(first)[:4] == ["run", "robots[0].max_wheel_speed", "seed", "passed"]
    assert {"r1.goal_reached", "r1.time_to_goal", "r1.collisions", "r1.pose[0]"} <= set(first)
    assert "wall_time" not in first and "real_time_factor" not in first
    slow = [r["r1.time_to_goal"] or 99 for r in rows if r["robots[0].max_wheel_speed"] == 0.5]
    fast = [r["r1.time_to_goal"] for r in rows if r["robots[0].max_wheel_speed"] == 1.0]
    assert min(slow) > max(fast)  # what the swept value does, as a user sees it
    assert len({r["r1.odometry_error"] for r in rows}) == 6  # every seed its own noise
    groups = summarize(rows, list(SPEEDS))
    assert [g.value for g in groups] == [0.5, 1.0] and groups[1].pass_rate == 1.0
    assert groups[1].metrics["r1.time_to_goal"].n == 3


def test_a_grid_over_two_keys_is_their_product():
    rows = run_sweep(sprint(), {**SPEEDS, "robots[0].lidar.beams": [8, 32]}, seeds=[4],
                     duration=0.2)
    assert [(r["robots[0].max_wheel_speed"], r["robots[0].lidar.beams"]) for r in rows] == [
        (0.5, 8), (0.5, 32), (1.0, 8), (1.0, 32)]
    assert all(r["sim_time"] == pytest.approx(0.2) for r in rows)


@pytest.mark.parametrize("grid, path", [
    ({"robots[0].max_wheel_sped": [1.0]}, "robots[0].max_wheel_sped"),
    ({"robots[2].radius": [0.2]}, "robots[2]"),
    ({"robots[0].lidar.beams": [8, -5]}, "robots[0].lidar.beams"),
    ({"world.dt": ["fast"]}, "world.dt"),
    ({"robots[0].pose": [[-3.0, 1.0, 0.0]]}, "robots[0].pose"),
])
def test_every_combination_is_checked_before_anything_runs(grid, path, tmp_path, monkeypatch):
    ran = []
    monkeypatch.setattr(backends, "run_chunk", lambda *a: ran.append(a) or [])
    out = tmp_path / "rows.csv"
    with pytest.raises(ScenarioError) as exc:
        run_sweep(sprint(), grid, seeds=range(2), out=out)
    assert exc.value.path == path and "--set" in exc.value.problem
    assert not ran and not out.exists() and not journal_path(out).exists()


# ---------------------------------------------------------------------------- files, resume


def test_rows_are_journalled_as_they_arrive_and_resume_finishes_the_rest(tmp_path, monkeypatch):
    out = tmp_path / "rows.csv"
    reference = run_sweep(sprint(), SPEEDS, seeds=range(4), duration=0.5)
    real, calls = backends.run_chunk, []

    def dies_on_third_chunk(base, source, chunk, duration, base_dir=None):
        calls.append([r.index for r in chunk])
        if len(calls) == 3:
            raise RuntimeError("worker died")
        return real(base, source, chunk, duration, base_dir)

    monkeypatch.setattr(backends, "run_chunk", dies_on_third_chunk)
    with pytest.raises(RuntimeError):
        run_sweep(sprint(), SPEEDS, seeds=range(4), duration=0.5, out=out, chunk_size=2)
    saved = journal_path(out).read_text().splitlines()
    assert len(saved) == 4 and not out.exists()  # two finished chunks kept, no table yet
    with open(journal_path(out), "a") as f:
        f.write('{"run": 7, "cut sho')  # a line the crash cut short is ignored
    with pytest.raises(ScenarioError, match="--resume"):  # no silent overwrite
        run_sweep(sprint(), SPEEDS, seeds=range(4), duration=0.5, out=out)
    calls.clear()
    rows = run_sweep(sprint(), SPEEDS, seeds=range(4), duration=0.5, out=out, resume=True,
                     chunk_size=2)
    assert sorted(i for c in calls for i in c) == [4, 5, 6, 7]  # only the unfinished runs
    assert comparable(rows) == comparable(reference)
    assert not journal_path(out).exists()
    from pymunk_bot.sweep.output import read_table

    assert comparable(read_table(out)) == comparable(reference)  # the CSV round-trips
    calls.clear()
    again = run_sweep(sprint(), SPEEDS, seeds=range(4), duration=0.5, out=out, resume=True)
    assert calls == [] and comparable(again) == comparable(reference)
    with pytest.raises(ScenarioError, match="different sweep"):
        run_sweep(sprint(), {"robots[0].max_wheel_speed": [0.7]}, seeds=range(4), out=out,
                  resume=True)


def test_cli_prints_the_summary_writes_csv_and_plot(tmp_path, capsys):
    scenario = tmp_path / "sprint.yaml"
    scenario.write_text(json.dumps(sprint()))
    out = tmp_path / "rows.csv"
    status = cli_main(["sweep", str(scenario), "--seeds", "0:2", "--set",
                       "robots[0].max_wheel_speed=0.5,1.0", "--out", str(out), "--plot",
                       "--backend", "serial", "--no-progress"])  # processes: tested below
    printed = capsys.readouterr().out
    assert status == 1  # the 0.5 m/s runs miss the 2.75 s expectation
    assert "robots[0].max_wheel_speed" in printed and "100%" in printed and "2/4 runs passed" \
        in printed
    assert out.read_text().count("\n") == 5 and (tmp_path / "rows.png").stat().st_size > 1000


def test_cli_bad_set_is_one_line_and_exit_2(tmp_path, capsys):
    scenario = tmp_path / "sprint.yaml"
    scenario.write_text(json.dumps(sprint()))
    status = cli_main(["sweep", str(scenario), "--set", "robots[0].lidar.beams=8,0",
                       "--out", str(tmp_path / "rows.csv")])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1
    assert err.startswith(f"error: {scenario}: robots[0].lidar.beams: must be > 0")


# ---------------------------------------------------------------------------- backends


def test_process_backend_gives_the_serial_rows():
    serial = run_sweep(sprint(), SPEEDS, seeds=range(3), duration=1.0)
    process = run_sweep(sprint(), SPEEDS, seeds=range(3), duration=1.0, backend="process",
                        workers=2)
    assert comparable(process) == comparable(serial)


@pytest.fixture(scope="module")
def dask_cluster(tmp_path_factory):
    """A real scheduler and two worker processes on 127.0.0.1, stopped afterwards."""
    with loopback_dask_cluster(tmp_path_factory.mktemp("dask"), cwd=ROOT,
                               pythonpath=ROOT) as address:
        yield address


def test_dask_cluster_gives_the_serial_rows(dask_cluster, tmp_path):
    scenario = _write(tmp_path, sprint())
    serial = run_sweep(scenario, SPEEDS, seeds=range(3), duration=1.0)
    out = tmp_path / "rows.csv"
    status = cli_main(["sweep", str(scenario), "--seeds", "0:3", "--set",
                       "robots[0].max_wheel_speed=0.5,1.0", "--duration", "1.0",
                       "--backend", "dask", "--address", dask_cluster, "--out", str(out),
                       "--no-progress"])
    assert status in (0, 1)
    from pymunk_bot.sweep.output import read_table

    assert comparable(read_table(out)) == comparable(serial)


def test_unreachable_dask_scheduler_is_one_line(tmp_path, capsys, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(backends, "CONNECT_TIMEOUT", 1.0)
    status = cli_main(["sweep", str(_write(tmp_path, sprint())), "--backend", "dask",
                       "--address", "tcp://127.0.0.1:9", "--out", str(tmp_path / "r.csv"),
                       "--no-progress"])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and "Dask scheduler" in err
    assert not journal_path(tmp_path / "r.csv").exists()  # nothing ran: nothing to resume


@pytest.mark.slow
def test_dask_local_cluster_on_loopback_gives_the_serial_rows():
    serial = run_sweep(sprint(), SPEEDS, seeds=range(2), duration=0.5)
    local = run_sweep(sprint(), SPEEDS, seeds=range(2), duration=0.5, backend="dask", workers=1)
    assert comparable(local) == comparable(serial)


@pytest.mark.skipif(os.environ.get("PYMUNK_BOT_TEST_RAY") != "1",
                    reason="Ray's servers listen on every interface (measured with Ray 2.60 and "
                           "_node_ip_address=127.0.0.1), so it runs only when asked for: "
                           "PYMUNK_BOT_TEST_RAY=1")
def test_ray_backend_gives_the_serial_rows():
    pytest.importorskip("ray")
    serial = run_sweep(sprint(), SPEEDS, seeds=range(2), duration=0.5)
    ray_rows = run_sweep(sprint(), SPEEDS, seeds=range(2), duration=0.5, backend="ray",
                         workers=2)
    assert comparable(ray_rows) == comparable(serial)


def _write(tmp_path: Path, data: dict) -> Path:
    path = tmp_path / "sprint.yaml"
    path.write_text(json.dumps(data))
    return path


def test_a_dead_worker_loses_no_finished_rows(tmp_path, capsys):
    scenario = sprint()
    scenario["robots"][0]["controller"] = {"type": "python",
                                           "class_path": "crashing_controller:DiesWhenTold"}
    path = _write(tmp_path, scenario)
    out = tmp_path / "rows.csv"
    argv = ["sweep", str(path), "--seeds", "0:3", "--set",
            "robots[0].controller.params={die: false},{die: true}", "--duration", "0.5",
            "--backend", "process", "--workers", "1", "--chunk-size", "1", "--out", str(out),
            "--no-progress"]
    status = cli_main(argv)
    err = capsys.readouterr().err
    assert status == 3 and err.count("\n") == 1 and "--resume" in err
    kept = [json.loads(line) for line in journal_path(out).read_text().splitlines()]
    assert sorted(r["run"] for r in kept) == [0, 1, 2]  # every run before the crash
    assert not out.exists()
    assert cli_main(argv + ["--resume"]) == 3  # the same runs die again; nothing is lost
    assert len(journal_path(out).read_text().splitlines()) == 3


def test_bad_input_found_inside_a_worker_is_still_one_line_exit_2(tmp_path, capsys):
    scenario = sprint()
    scenario["robots"][0]["controller"] = {"type": "python", "class_path": "no_such_module:X"}
    status = cli_main(["sweep", str(_write(tmp_path, scenario)), "--backend", "process",
                       "--workers", "1", "--out", str(tmp_path / "rows.csv"), "--no-progress"])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1
    assert "robots[0].controller" in err and "no_such_module" in err


def test_parquet_output_round_trips(tmp_path):
    pytest.importorskip("pyarrow")
    from pymunk_bot.sweep.output import read_table

    out = tmp_path / "rows.parquet"
    rows = run_sweep(sprint(), SPEEDS, seeds=range(2), duration=0.5, out=out)
    assert comparable(read_table(out)) == comparable(rows)
    again = run_sweep(sprint(), SPEEDS, seeds=range(2), duration=0.5, out=out, resume=True)
    assert comparable(again) == comparable(rows)


def test_a_ros_map_scenario_sweeps_from_any_folder(tmp_path, monkeypatch):
    """A scenario whose arena is a ROS map (no `size`) re-parses in every run, its map path
    resolved against the scenario file, wherever the sweep runs from."""
    monkeypatch.chdir(tmp_path)
    rows = run_sweep("floor_plan", {"robots[0].max_wheel_speed": [0.5, 1.0]}, [0],
                     duration=1.0)
    assert [row["robots[0].max_wheel_speed"] for row in rows] == [0.5, 1.0]
    assert rows[1]["r1.distance"] > rows[0]["r1.distance"] > 0.1


def test_the_plot_says_what_was_swept_and_in_which_units(tmp_path, monkeypatch):
    import matplotlib.figure

    from pymunk_bot.sweep import plot_summary, summarize

    saved = []
    original = matplotlib.figure.Figure.savefig
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig",
                        lambda fig, *a, **k: (saved.append(fig), original(fig, *a, **k))[1])
    rows = run_sweep(sprint(), SPEEDS, seeds=range(2))
    plot_summary(summarize(rows, list(SPEEDS)), tmp_path / "plot.png", scenario="sprint.yaml")
    (fig,) = saved
    assert fig.get_suptitle() == "Sweep of robots[0].max_wheel_speed on sprint.yaml: 4 runs"
    axes = {ax.get_title(): ax for ax in fig.axes}
    assert axes["r1.time_to_goal"].get_ylabel() == "time [s]"
    assert axes["pass rate"].get_ylabel() == "% of runs"
    assert all(ax.get_xlabel() == "robots[0].max_wheel_speed [m/s]" for ax in fig.axes)


@pytest.mark.parametrize("backend", ["serial", "process"])
def test_a_python_controller_beside_the_scenario_is_found_from_any_folder(
        tmp_path, monkeypatch, capsys, backend):
    """As `run` does: the module is looked for beside the scenario file, not only in the
    current folder (here the sweep runs from another folder)."""
    folder = tmp_path / "project"
    folder.mkdir()
    (folder / "beside_sweep_ctrl.py").write_text(
        "from pymunk_bot.controllers import Command, Controller\n\n\n"
        "class Forward(Controller):\n"
        "    def compute(self, obs):\n"
        "        return Command(v=0.5)\n")
    data = sprint()
    data["robots"][0]["controller"] = {"type": "python",
                                       "class_path": "beside_sweep_ctrl:Forward"}
    data["expect"] = {"r1": {"goal_reached": True}}
    scenario = folder / "forward.yaml"
    scenario.write_text(json.dumps(data))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    status = cli_main(["sweep", str(scenario), "--seeds", "0:2", "--backend", backend,
                       "--workers", "1", "--out", str(tmp_path / "rows.csv"), "--no-progress"])
    out, err = capsys.readouterr()
    assert status == 0, err
    assert "2/2 runs passed" in out
