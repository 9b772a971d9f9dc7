"""Train a navigation policy with Stable-Baselines3 PPO on pymunk_bot/Navigation-v0.

    pip install 'pymunk-bot[rl,train,onnx]'          (Stable-Baselines3 brings PyTorch)
    python examples/train_ppo.py --steps 1000000 --envs 8 --out ppo_navigation.zip \\
        --onnx ppo_navigation.onnx
    python examples/train_ppo.py --evaluate ppo_navigation.zip --episodes 200
    pymunk-bot evaluate ppo_navigation.onnx SCENARIO --episodes 200     # the exported policy

The task is the ES recipe's (examples/train_es.py): every episode a new generated cluttered
world, a random free start and a random goal; the 32-beam observation of
:mod:`pymunk_bot.policy_io`. ``--onnx`` exports the deterministic actor (observation in, action
out) for ``controller: {type: policy, path: ppo_navigation.onnx}``.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from train_es import HELD_OUT_WORLDS, TRAIN_WORLDS, env_kwargs

ENV_ID = "pymunk_bot/Navigation-v0"


def make_vec_env(n_envs: int, seed: int):
    """``n_envs`` copies of Navigation-v0 in SB3's own vector env (SB3 has its own VecEnv
    interface; Gymnasium's native vector env serves other trainers)."""
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

    import pymunk_bot.envs  # noqa: F401  (registers the ids)

    kwargs = env_kwargs(TRAIN_WORLDS, training=True)
    return sb3_make_vec_env(ENV_ID, n_envs=n_envs, seed=seed, env_kwargs=kwargs)


def train(steps: int, n_envs: int = 8, seed: int = 0, out: Path | None = None,
          n_steps: int = 256):
    """Train PPO for ``steps`` environment steps; returns the model (saved to ``out``)."""
    from stable_baselines3 import PPO

    env = make_vec_env(n_envs, seed)
    model = PPO("MlpPolicy", env, n_steps=n_steps, batch_size=min(256, n_steps * n_envs),
                learning_rate=3e-4, gamma=0.99, seed=seed, verbose=0, device="cpu")
    model.learn(total_timesteps=steps, progress_bar=_has_rich())
    if out is not None:
        model.save(out)
    env.close()
    return model


def _has_rich() -> bool:
    try:
        import rich  # noqa: F401  (SB3's progress bar needs rich and tqdm)
    except ImportError:
        return False
    return True


class DeterministicActor:
    """An SB3 model as a policy for :mod:`pymunk_bot.envs.evaluation` (its mean action)."""

    inputs = outputs = None

    def __init__(self, model) -> None:
        self.model = model

    def act(self, obs: np.ndarray) -> np.ndarray:
        action, _ = self.model.predict(obs, deterministic=True)
        return np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)


def export_onnx(model, path: Path) -> None:
    """The deterministic actor as ONNX: input ``obs`` (batch x observation, float32), output
    ``action`` (batch x 2), before clipping (the policy controller clips)."""
    import torch

    class Actor(torch.nn.Module):
        def __init__(self, policy) -> None:
            super().__init__()
            self.policy = policy

        def forward(self, obs):
            features = self.policy.extract_features(obs, self.policy.pi_features_extractor)
            return self.policy.action_net(self.policy.mlp_extractor.forward_actor(features))

    size = model.observation_space.shape[0]
    torch.onnx.export(Actor(model.policy).eval(), torch.zeros(1, size), str(path),
                      input_names=["obs"], output_names=["action"],
                      dynamic_axes={"obs": {0: "batch"}, "action": {0: "batch"}})


def evaluate(model, episodes: int = 10, seed: int = 10_000) -> dict:
    """Held-out episodes (unseen worlds): contact-free success and more, with 95 % intervals."""
    from pymunk_bot.envs.evaluation import evaluate_policy, summarize

    outcomes = evaluate_policy(DeterministicActor(model), env_kwargs(HELD_OUT_WORLDS, False),
                               episodes, seed=seed)
    return summarize(outcomes)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000, help="environment steps")
    parser.add_argument("--envs", type=int, default=8, help="worlds trained on at once")
    parser.add_argument("--episodes", type=int, default=10, help="evaluation episodes")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("ppo_navigation.zip"))
    parser.add_argument("--onnx", type=Path, default=None, help="also export the actor here")
    parser.add_argument("--evaluate", type=Path, metavar="MODEL.zip",
                        help="only evaluate a saved model")
    args = parser.parse_args(argv)
    from pymunk_bot.envs.evaluation import format_summary

    if args.evaluate is not None:
        from stable_baselines3 import PPO

        model = PPO.load(args.evaluate, device="cpu")
    else:
        model = train(args.steps, args.envs, args.seed, args.out)
        print(f"saved {args.out}")
    if args.onnx is not None:
        export_onnx(model, args.onnx)
        print(f"exported {args.onnx}")
    print(format_summary(evaluate(model, args.episodes)))


if __name__ == "__main__":
    main()
