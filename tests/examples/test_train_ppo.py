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
    out, onnx = tmp_path / "ppo.zip", tmp_path / "ppo.onnx"
    args = ["--steps", "2048", "--envs", "2", "--out", str(out), "--episodes", "2"]
    if _has("onnxruntime") and _has("onnx"):
        args += ["--onnx", str(onnx)]
    train_ppo.main(args)
    assert out.stat().st_size > 10_000  # a saved policy
    printed = capsys.readouterr().out
    assert "contact-free success" in printed and "time to goal" in printed
    if onnx.exists():  # the exported actor acts as the model does
        from stable_baselines3 import PPO

        from pymunk_bot.policy_file import load_policy

        model, policy = PPO.load(out, device="cpu"), load_policy(onnx)
        obs = np.random.default_rng(0).uniform(0, 1, (3, policy.inputs)).astype(np.float32)
        expected = np.clip(model.predict(obs, deterministic=True)[0], -1, 1)
        np.testing.assert_allclose(policy.act(obs), expected, atol=1e-5)


def _has(module: str) -> bool:
    try:
        __import__(module)
    except ImportError:
        return False
    return True
