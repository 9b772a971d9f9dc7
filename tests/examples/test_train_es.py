"""The ES recipe runs end to end: CMA-ES generations, a saved .npz the policy controller loads,
a learning-curve plot (the measured 10-minute run is in docs/learning.md)."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import train_es  # noqa: E402


def test_a_short_run_learns_saves_and_plots(tmp_path):
    pytest.importorskip("cma")  # here, not at collection: importing cma costs 0.4 s
    theta, shapes, history = train_es.train(minutes=0.03, seed=0, popsize=4, episodes=1,
                                            workers=1, progress=False)
    assert history and {"mean_return", "best_return", "success"} <= history[0].keys()
    policy = train_es.to_policy(theta, shapes)
    assert policy.inputs == 32 + 8 and policy.outputs == 2
    policy.save(tmp_path / "p.npz")
    from pymunk_bot.policy.files import load_policy

    np.testing.assert_array_equal(load_policy(tmp_path / "p.npz").weights[0], policy.weights[0])
    train_es.plot(history, tmp_path / "curve.png", "test")
    assert (tmp_path / "curve.png").stat().st_size > 5_000


def test_a_guided_run_records_its_guidance(tmp_path):
    pytest.importorskip("cma")
    theta, shapes, history = train_es.train(minutes=0.03, seed=0, popsize=4, episodes=1,
                                            workers=1, progress=False, guided=True,
                                            kind="office")
    assert history
    train_es.to_policy(theta, shapes, guided=True).save(tmp_path / "p.npz")
    from pymunk_bot.policy.files import load_policy

    assert load_policy(tmp_path / "p.npz").plan_guidance is not None  # evaluate turns it on
