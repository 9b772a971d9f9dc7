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


TEACHER = SCRIPT.parent / "crowd_teacher.yaml"


@pytest.mark.slow  # about 8 s: two runs, each recording, fitting and validating
def test_imitation_runs_end_to_end_and_is_deterministic(tmp_path, capsys):
    """--imitate records the teacher, runs a DAgger round, fits and validates; the same seed
    gives the same policy file, bit for bit."""
    from pymunk_bot.policy.files import load_policy

    argv = ["--imitate", str(TEACHER), "--demos", "2", "--dagger-rounds", "1",
            "--dagger-episodes", "1", "--epochs", "3", "--hidden", "16", "--workers", "1",
            "--validation-episodes", "2"]
    for name in ("a.npz", "b.npz"):
        train_crowd.main([*argv, "--out", str(tmp_path / name)])
    out = capsys.readouterr().out
    assert "teacher" in out and "DAgger round 1" in out and "validation success" in out
    policy = load_policy(tmp_path / "a.npz")
    assert policy.crowd_humans == 5 and policy.inputs == 3 + 3 + 8 * 5 and policy.outputs == 3
    assert policy.weights[0].shape == (46, 16)
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()


def test_the_recorded_actions_are_the_teachers_commands_on_the_action_scale():
    """A teacher episode: every recorded action within [-1, 1], the observation the policy
    sees (46 numbers, the previous action the one recorded a step before), and the
    teacher (social force) starting from rest toward the goal: v rises over the first steps."""
    import crowd_imitation

    block = {"type": "social_force", "rate": 4.0, "anticipation": 2.0, "range": 0.12}
    observations, actions, _ = crowd_imitation.record_episode(block, 100_000, 5)
    assert observations.shape[1] == 46 and len(observations) == len(actions) > 10
    assert abs(actions).max() <= 1.0
    assert observations[1:, 3:6].tolist() == actions[:-1].astype("float32").tolist()
    assert 0.0 < actions[0, 0] < actions[1, 0] < actions[3, 0]


def test_the_fit_learns_a_smooth_map():
    """The numpy Adam fit brings a small network's error on a known smooth map far below
    the error of predicting the mean (a fit that did not train would not)."""
    import numpy as np

    import crowd_imitation

    rng = np.random.default_rng(1)
    x = rng.uniform(-1, 1, (2000, 4))
    y = np.stack([np.tanh(x[:, 0] - x[:, 1]), 0.5 * np.sin(2 * x[:, 2]), x[:, 3] * x[:, 0]], 1)
    weights, biases = crowd_imitation.fit(x, y, [32], seed=0, epochs=200, learning_rate=3e-3)
    baseline = float(np.mean((y - y.mean(0)) ** 2))
    assert crowd_imitation.mse(weights, biases, x, y) < 0.02 * baseline


@pytest.mark.parametrize("argv, message", [
    (["--imitate", "no_such_controller"], "error: --imitate: 'no_such_controller' is neither"),
    (["--imitate", "social_force", "--demos", "0"], "error: --demos must be in [1, 100000]"),
])
def test_bad_imitation_options_are_one_line_and_exit_2(tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as exit_:
        train_crowd.main([*argv, "--out", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1 and err.startswith(message)
    assert not (tmp_path / "p.npz").exists()
