"""The crowd recipe (examples/train_crowd.py) runs end to end on CrowdNav's circle crossing:
a validated generation, a checkpoint and a saved .npz recording its crowd_state observation,
training layouts disjoint from the test cases; bad options are one line, exit 2."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

pytest.importorskip("gymnasium")

SCRIPT = Path(__file__).resolve().parents[2] / "examples" / "train_crowd.py"
sys.path.insert(0, str(SCRIPT.parent))
import train_crowd  # noqa: E402


def test_a_one_generation_run_validates_checkpoints_and_saves(tmp_path, capsys):
    pytest.importorskip("cma")
    out = tmp_path / "crowd.npz"
    train_crowd.main(["--generations", "1", "--popsize", "4", "--train-episodes", "1",
                      "--workers", "1", "--validation-episodes", "2", "--checkpoints",
                      "--out", str(out), "--plot", str(tmp_path / "curve.png")])
    from pymunk_bot.policy.files import load_policy

    policy = load_policy(out)
    assert policy.crowd_humans == 5 and policy.inputs == 3 + 3 + 8 * 5 and policy.outputs == 3
    assert load_policy(tmp_path / "crowd.g1.npz").weights[0].tolist() == \
        policy.weights[0].tolist()  # the checkpoint of the last generation is the result
    assert "generation 1" in capsys.readouterr().out
    assert (tmp_path / "curve.png").stat().st_size > 5_000


def test_training_and_validation_layouts_miss_the_test_cases():
    assert train_crowd.TRAIN_LAYOUTS[0] >= 500 and train_crowd.VALIDATION_LAYOUTS[0] >= 500
    assert train_crowd.TRAIN_LAYOUTS[1] <= train_crowd.VALIDATION_LAYOUTS[0]


@pytest.mark.parametrize("argv, message", [
    (["--generations", "0"], "error: --generations must be in [1, 100000] (got 0)"),
    (["--sigma", "nan"], "error: --sigma must be in (0, 100) (got nan)"),
    (["--validation-episodes", "0"], "error: --validation-episodes must be in [1, 10000]"),
])
def test_bad_options_are_one_line_and_exit_2(tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as exit_:
        train_crowd.main([*argv, "--out", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1 and err.startswith(message)
    assert not (tmp_path / "p.npz").exists()
