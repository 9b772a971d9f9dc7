"""The PPO example trains and evaluates end to end (only where torch and SB3 are installed)."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

pytest.importorskip("gymnasium")
pytest.importorskip("torch")
pytest.importorskip("stable_baselines3")

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import train_ppo  # noqa: E402


def test_ppo_trains_a_few_thousand_steps_and_evaluates(tmp_path, capsys):
    out = tmp_path / "ppo.zip"
    train_ppo.main(["--steps", "4096", "--envs", "2", "--out", str(out), "--episodes", "2"])
    assert out.stat().st_size > 10_000  # a saved policy
    printed = capsys.readouterr().out
    assert "success_rate" in printed and "mean_return" in printed
