"""`pymunk-bot run SCENARIO --trajectory-out DIR`: TUM files evo reads, and our ATE / RPE are
evo's on those very files (evo is a dev dependency)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pymunk_bot.cli import main
from pymunk_bot.localization.metrics import ate, rpe
from pymunk_bot.localization.tum import read_tum

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
KINDS = ("truth", "odometry", "estimate")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("traj") / "run"  # made by the run (its parent exists)
    code = main(["run", str(SCENARIOS / "ekf_office.yaml"), "--headless", "--duration", "15",
                 "--trajectory-out", str(out)])
    assert code == 0
    return out


def test_the_run_writes_three_tum_files_per_robot_at_the_same_times(run_dir):
    assert sorted(p.name for p in run_dir.iterdir()) == [f"r1.{k}.tum" for k in sorted(KINDS)]
    loaded = {k: read_tum(run_dir / f"r1.{k}.tum") for k in KINDS}
    times = loaded["truth"][0]
    for kind in KINDS:
        np.testing.assert_array_equal(loaded[kind][0], times)
    assert times[0] == 0.0 and times[-1] == pytest.approx(15.0, abs=0.05)
    assert 40 <= (times.size - 1) / 15.0 <= 60  # ~50 Hz
    rows = [line.split() for line in (run_dir / "r1.truth.tum").read_text().splitlines()
            if not line.startswith("#")]
    assert {len(r) for r in rows} == {8}
    truth = loaded["truth"][1]
    np.testing.assert_allclose(truth[0], (1.0, 1.0, 0.0), atol=1e-6)  # the scenario's start
    assert np.hypot(*(truth[-1, :2] - truth[0, :2])) > 1.0  # it drove
    # the odometry drifts (an uncalibrated robot), the EKF stays close to the truth
    drift = np.hypot(*(loaded["odometry"][1][-1, :2] - truth[-1, :2]))
    error = np.hypot(*(loaded["estimate"][1][-1, :2] - truth[-1, :2]))
    assert error < 0.05 < drift


def _evo(run_dir, kind):
    pytest.importorskip("evo")
    from evo.core import metrics, sync
    from evo.tools import file_interface

    ref = file_interface.read_tum_trajectory_file(str(run_dir / "r1.truth.tum"))
    est = file_interface.read_tum_trajectory_file(str(run_dir / f"r1.{kind}.tum"))
    return (*sync.associate_trajectories(ref, est), metrics)


@pytest.mark.parametrize("kind", ["estimate", "odometry"])
def test_our_ate_is_evos_on_the_same_files(run_dir, kind):
    ref, est, metrics = _evo(run_dir, kind)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    theirs = ape.get_all_statistics()
    ours = ate(read_tum(run_dir / "r1.truth.tum")[1], read_tum(run_dir / f"r1.{kind}.tum")[1])
    for key in ("rmse", "mean", "median", "max", "std"):
        assert ours[key] == pytest.approx(theirs[key], rel=1e-6, abs=1e-9), key


@pytest.mark.parametrize("kind", ["estimate", "odometry"])
@pytest.mark.parametrize("delta, unit, all_pairs, from_truth", [
    (1.0, "m", False, False), (0.5, "m", True, False), (1.0, "m", False, True),
    (10, "frames", False, False), (25, "frames", True, False)])
def test_our_rpe_is_evos_on_the_same_files(run_dir, kind, delta, unit, all_pairs, from_truth):
    ref, est, metrics = _evo(run_dir, kind)
    truth = read_tum(run_dir / "r1.truth.tum")[1]
    estimate = read_tum(run_dir / f"r1.{kind}.tum")[1]
    ours = rpe(truth, estimate, delta, unit, all_pairs, "truth" if from_truth else "estimate")
    assert ours["pairs"] >= 5
    evo_unit = metrics.Unit.meters if unit == "m" else metrics.Unit.frames
    for part, relation in (("trans", metrics.PoseRelation.translation_part),
                           ("rot", metrics.PoseRelation.rotation_angle_rad)):
        metric = metrics.RPE(relation, delta, evo_unit, 0.1, all_pairs, from_truth)
        metric.process_data((ref, est))
        theirs = metric.get_all_statistics()
        assert len(metric.error) == ours["pairs"]
        for key in ("rmse", "mean", "median", "max", "std"):
            assert ours[part][key] == pytest.approx(theirs[key], rel=1e-6, abs=1e-9), (part, key)


@pytest.mark.parametrize("target, problem", [
    ("missing/deeper", "does not exist"),
    ("a_file", "exists and is not a directory"),
])
def test_a_bad_directory_is_one_line_and_exit_2_before_the_run(tmp_path, capsys, target, problem):
    (tmp_path / "a_file").write_text("x")
    code = main(["run", str(SCENARIOS / "ekf_office.yaml"), "--headless", "--duration", "60",
                 "--trajectory-out", str(tmp_path / target)])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.count("\n") == 0 and "--trajectory-out" in err and problem in err
    assert "Traceback" not in err
    assert not (tmp_path / "missing").exists()
