"""SE(2) helpers and the trajectory metrics (evo's ATE / RPE definitions)."""
import numpy as np
import pytest

from pymunk_bot.localization.metrics import align_rigid, ate, error_block, rpe
from pymunk_bot.localization.se2 import between, compose, wrap


def test_between_undoes_compose():
    rng = np.random.default_rng(1)
    a = rng.uniform(-5, 5, (50, 3))
    b = rng.uniform(-5, 5, (50, 3))
    np.testing.assert_allclose(between(a, compose(a, b)), np.column_stack([b[:, :2], wrap(b[:, 2])]),
                               atol=1e-12)


def _circle(n=400):
    t = np.linspace(0, 2 * np.pi, n)
    return np.column_stack([3 * np.cos(t), 3 * np.sin(t), wrap(t + np.pi / 2)])


def test_error_block_of_a_shifted_estimate():
    truth = _circle()
    est = truth + [0.03, 0.04, 0.01]
    block = error_block(truth, est)
    assert block["rmse"] == pytest.approx(0.05)
    assert block["max_error"] == pytest.approx(0.05)
    assert block["final_error"] == pytest.approx(0.05)
    assert block["heading_rmse"] == pytest.approx(0.01)


def test_ate_is_the_position_error_and_alignment_removes_a_rigid_offset():
    truth = _circle()
    moved = compose(np.array([0.5, -0.2, 0.1]), truth)  # the whole trajectory in another frame
    assert ate(truth, moved)["rmse"] > 0.3
    assert ate(truth, moved, align=True)["rmse"] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(align_rigid(truth, moved)[:, 2], truth[:, 2], atol=1e-9)


def test_rpe_ignores_a_constant_offset_but_sees_drift():
    truth = _circle()
    assert rpe(truth, compose(np.array([0.5, -0.2, 0.1]), truth))["trans"]["rmse"] < 1e-9
    drifting = truth.copy()
    drifting[:, :2] *= 1.01  # 1 % scale error: 1 cm per metre
    result = rpe(truth, drifting, delta=1.0, all_pairs=True)
    assert result["trans"]["rmse"] == pytest.approx(0.01, rel=0.1)
    assert result["pairs"] > 300
    consecutive = rpe(truth, drifting, delta=1.0)  # the path cut into 1 m pieces (evo's default)
    assert consecutive["trans"]["rmse"] == pytest.approx(0.01, rel=0.1)
    assert 10 < consecutive["pairs"] < 40


def test_metrics_refuse_mismatched_input():
    with pytest.raises(ValueError):
        ate(np.zeros((3, 3)), np.zeros((4, 3)))
