"""The PPO example trains, evaluates and exports ONNX end to end (only where torch and SB3 are
installed: skipped cleanly otherwise)."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")
pytest.importorskip("torch")
pytest.importorskip("stable_baselines3")

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import train_ppo  # noqa: E402


def test_ppo_trains_a_few_thousand_steps_evaluates_and_exports(tmp_path, capsys):
    out, npz, onnx = tmp_path / "ppo.zip", tmp_path / "ppo.npz", tmp_path / "ppo.onnx"
    args = ["--steps", "2048", "--envs", "2", "--out", str(out), "--npz", str(npz),
            "--episodes", "2", "--workers", "1", "--checkpoints", "2"]
    if _has("onnxruntime") and _has("onnxscript"):
        args += ["--onnx", str(onnx)]
    train_ppo.main(args)
    assert out.stat().st_size > 10_000  # a saved policy
    assert out.with_name("ppo.1024.zip").exists() and out.with_name("ppo.2048.zip").exists()
    printed = capsys.readouterr().out
    assert "contact-free success" in printed and "time to goal" in printed
    # The exported actors act as the model does (its mean action, clipped).
    from stable_baselines3 import PPO

    from pymunk_bot.policy.files import load_policy

    model = PPO.load(out, device="cpu")
    obs = np.random.default_rng(0).uniform(-1, 1, (5, model.observation_space.shape[0]))
    expected = np.clip(model.predict(obs.astype(np.float32), deterministic=True)[0], -1, 1)
    assert np.abs(expected).max() > 0.01  # the check below is not trivially true
    for path in (npz, onnx) if onnx.exists() else (npz,):
        policy = load_policy(path)
        assert policy.inputs == obs.shape[1] and policy.outputs == 2
        np.testing.assert_allclose(policy.act(obs.astype(np.float32)), expected, atol=1e-5)


def _has(module: str) -> bool:
    try:
        __import__(module)
    except ImportError:
        return False
    return True
