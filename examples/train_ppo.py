"""Train a navigation policy with Stable-Baselines3 PPO on pymunk_bot/Navigation-v0.

    pip install torch --index-url https://download.pytorch.org/whl/cpu   # PyTorch's CPU build
    pip install 'pymunk-bot[rl,train,onnx]'    # SB3, onnxscript (ONNX export), onnxruntime
    python examples/train_ppo.py --steps 480000 --envs 8 --seed 0 --out ppo_navigation.zip \\
        --npz ppo_navigation.npz --onnx ppo_navigation.onnx --checkpoints 8 --plot ppo_curve.png
    python examples/train_ppo.py --evaluate ppo_navigation.zip --episodes 200
    pymunk-bot evaluate ppo_navigation.onnx SCENARIO --episodes 200     # the exported policy

Install PyTorch first: a plain ``pip install torch`` brings the CUDA build (several GB). On
this project's machines the CPU wheel is on disk: ``pip install torch==2.13.0``. Measured
(docs/learning.md): 94 % contact-free success on the held-out episodes after 2.5 minutes of
training in one process on a shared 2-core machine, 98-100 % from 300,000 steps (about 7 minutes).

The task is the ES recipe's (examples/train_es.py): every episode a new generated cluttered
world, a random free start and a random goal; the 32-beam observation of
:mod:`pymunk_bot.policy.io`. The actor is SB3's default MLP (two layers of 64 tanh units, a
linear output): exactly the ``.npz`` MLP of :mod:`pymunk_bot.policy.files`, so ``--npz`` saves
it for ``controller: {type: policy, path: ppo_navigation.npz}`` without onnxruntime, and
``--onnx`` exports the same actor as ONNX. ``--checkpoints N`` saves N models during training
with their wall time; ``--plot`` then evaluates each on held-out episodes (the learning curve).
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from train_es import HELD_OUT_WORLDS, TRAIN_WORLDS, env_kwargs

ENV_ID = "pymunk_bot/Navigation-v0"
# Held-out episodes: the ES recipe's (its seeds 10,000 .. 10,000 + episodes - 1).
EVALUATION_SEED = 10_000


def make_vec_env(n_envs: int, seed: int):
    """``n_envs`` copies of Navigation-v0 in SB3's own vector env (SB3 has its own VecEnv
    interface; Gymnasium's native vector env serves other trainers). Worlds drawn per episode
    cannot share a pymunk Space, so SB3's in-process vector of single envs loses nothing."""
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

    import pymunk_bot.envs  # noqa: F401  (registers the ids)

    kwargs = env_kwargs(TRAIN_WORLDS, training=True)
    return sb3_make_vec_env(ENV_ID, n_envs=n_envs, seed=seed, env_kwargs=kwargs)


def _checkpoint_callback(every: int, out: Path, history: list[dict]):
    """An SB3 callback saving the model every ``every`` steps as ``OUT.STEPS.zip``, with the
    training wall time it took so far (in ``history``)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Checkpoints(BaseCallback):
        def _on_training_start(self) -> None:
            self.started = time.perf_counter()
            self.next = every

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next:
                elapsed = time.perf_counter() - self.started  # [s] (a save takes milliseconds)
                path = out.with_name(f"{out.stem}.{self.num_timesteps}.zip")
                self.model.save(path)
                history.append({"steps": self.num_timesteps, "time": elapsed, "path": path})
                self.next += every
            return True

    return Checkpoints()


def train(steps: int, n_envs: int = 8, seed: int = 0, out: Path | None = None,
          n_steps: int = 256, checkpoints: int = 0, progress: bool = True,
          threads: int = 1) -> tuple[Any, list[dict]]:
    """Train PPO for ``steps`` environment steps: (the model, saved to ``out``; the
    checkpoints' steps, training wall time [s] and paths, ``checkpoints`` of them evenly
    spaced, the last at the end). ``threads``: PyTorch's (the nets are small; the envs step
    in this process too)."""
    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(threads)
    env = make_vec_env(n_envs, seed)
    model = PPO("MlpPolicy", env, n_steps=n_steps, batch_size=min(256, n_steps * n_envs),
                learning_rate=3e-4, gamma=0.99, seed=seed, verbose=0, device="cpu")
    history: list[dict] = []
    callback = None
    if checkpoints > 0:
        if out is None:
            raise ValueError("checkpoints need an output path")
        callback = _checkpoint_callback(max(1, steps // checkpoints), out, history)
    model.learn(total_timesteps=steps, progress_bar=progress and _has_rich(), callback=callback)
    if out is not None:
        model.save(out)
    env.close()
    return model, history


def _has_rich() -> bool:
    try:
        import rich  # noqa: F401  (SB3's progress bar needs rich and tqdm)
    except ImportError:
        return False
    return True


def to_mlp_policy(model):
    """The model's deterministic actor (its mean action) as a :class:`MlpPolicy`: SB3's
    default actor is linear layers with tanh between them and a linear output, which is what
    the ``.npz`` MLP computes. Other activations or feature extractors are refused."""
    import torch
    from stable_baselines3.common.torch_layers import FlattenExtractor

    from pymunk_bot.policy.files import MlpPolicy

    policy = model.policy
    hidden = list(policy.mlp_extractor.policy_net)  # Linear, Tanh, Linear, Tanh, ...
    tanh_mlp = len(hidden) % 2 == 0 and all(
        isinstance(m, torch.nn.Tanh if i % 2 else torch.nn.Linear) for i, m in enumerate(hidden))
    if not (tanh_mlp and isinstance(policy.pi_features_extractor, FlattenExtractor)):
        raise ValueError("only SB3's MlpPolicy with tanh activations is an .npz MLP "
                         "(export with --onnx instead)")
    linear = hidden[0::2] + [policy.action_net]
    return MlpPolicy([m.weight.detach().numpy().T for m in linear],
                     [m.bias.detach().numpy() for m in linear])


def export_onnx(model, path: Path) -> None:
    """The deterministic actor as ONNX: input ``obs`` (batch x observation, float32), output
    ``action`` (batch x 2), before clipping (the policy controller clips). PyTorch's exporter
    needs ``onnxscript`` (the ``train`` extra)."""
    import torch

    class Actor(torch.nn.Module):
        def __init__(self, policy) -> None:
            super().__init__()
            self.policy = policy

        def forward(self, obs):
            features = self.policy.extract_features(obs, self.policy.pi_features_extractor)
            return self.policy.action_net(self.policy.mlp_extractor.forward_actor(features))

    size = model.observation_space.shape[0]
    torch.onnx.export(Actor(model.policy).eval(), (torch.zeros(1, size),), str(path),
                      input_names=["obs"], output_names=["action"],
                      dynamic_shapes=({0: torch.export.Dim("batch")},),
                      external_data=False, verbose=False)  # one self-contained file


def evaluate(policy, episodes: int = 10, seed: int = EVALUATION_SEED, workers: int = 1) -> dict:
    """Held-out episodes (unseen worlds, not ended at a contact): contact-free success and
    more, with 95 % intervals."""
    from pymunk_bot.envs.evaluation import evaluate_policy, summarize

    outcomes = evaluate_policy(policy, env_kwargs(HELD_OUT_WORLDS, False), episodes,
                               seed=seed, workers=workers)
    return summarize(outcomes)


def learning_curve(history: list[dict], episodes: int, workers: int) -> list[dict]:
    """Each checkpoint's held-out summary beside its steps and training wall time."""
    from stable_baselines3 import PPO

    return [dict(entry, summary=evaluate(to_mlp_policy(PPO.load(entry["path"], device="cpu")),
                                         episodes, workers=workers)) for entry in history]


def plot(curve: list[dict], out: Path, title: str) -> None:
    """Held-out contact-free success (95 % interval) against training wall time and steps."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    minutes = [c["time"] / 60 for c in curve]
    rate = [c["summary"]["success"]["rate"] for c in curve]
    low = [c["summary"]["success"]["low"] for c in curve]
    high = [c["summary"]["success"]["high"] for c in curve]
    fig, axis = plt.subplots(figsize=(6, 3.5))
    axis.fill_between(minutes, low, high, color="C2", alpha=0.25, label="95 % interval")
    axis.plot(minutes, rate, "o-", color="C2", label="contact-free success (held out)")
    for m, r, c in zip(minutes, rate, curve):
        axis.annotate(f"{c['steps'] // 1000}k", (m, r), textcoords="offset points",
                      xytext=(0, -13), ha="center", fontsize=7)
    axis.set_ylim(0, 1)
    axis.set_xlim(left=0)
    axis.set_xlabel("training wall time [min] (labels: env steps)")
    axis.set_ylabel("contact-free success rate")
    axis.legend(loc="lower right", fontsize=8)
    axis.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--steps", type=int, default=300_000, help="environment steps")
    parser.add_argument("--envs", type=int, default=8, help="worlds trained on at once")
    parser.add_argument("--episodes", type=int, default=200, help="held-out evaluation episodes")
    parser.add_argument("--workers", type=int, default=2, help="evaluation processes")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("ppo_navigation.zip"))
    parser.add_argument("--npz", type=Path, default=None, help="also save the actor as .npz")
    parser.add_argument("--onnx", type=Path, default=None, help="also export the actor here")
    parser.add_argument("--checkpoints", type=int, default=0,
                        help="save this many models during training (OUT.STEPS.zip)")
    parser.add_argument("--plot", type=Path, default=None,
                        help="evaluate the checkpoints and plot the learning curve here")
    parser.add_argument("--evaluate", type=Path, metavar="MODEL.zip",
                        help="only evaluate a saved model")
    args = parser.parse_args(argv)
    for name, low, high in (("steps", 1, 10**9), ("envs", 1, 256), ("episodes", 1, 100_000),
                            ("workers", 1, 64), ("checkpoints", 0, 100)):
        if not low <= getattr(args, name) <= high:
            parser.error(f"--{name} must be in [{low}, {high}] (got {getattr(args, name)})")
    if args.plot is not None and args.checkpoints < 1:
        parser.error("--plot needs --checkpoints N (the models it evaluates)")
    if args.evaluate is not None and not args.evaluate.is_file():
        parser.error(f"--evaluate {args.evaluate}: no such file")
    from stable_baselines3 import PPO

    from pymunk_bot.envs.evaluation import format_summary

    if args.evaluate is not None:
        model = PPO.load(args.evaluate, device="cpu")
    else:
        started = time.perf_counter()
        model, history = train(args.steps, args.envs, args.seed, args.out,
                               checkpoints=args.checkpoints)
        print(f"{args.steps} steps in {(time.perf_counter() - started) / 60:.1f} min; "
              f"saved {args.out}")
        if args.plot is not None:
            curve = learning_curve(history, args.episodes, args.workers)
            print("steps     minutes  contact-free success (95 % CI, held out)")
            for c in curve:
                s = c["summary"]["success"]
                print(f"{c['steps']:<9d} {c['time'] / 60:7.1f}  {s['rate']:6.1%} "
                      f"({s['low']:.1%} - {s['high']:.1%})")
            plot(curve, args.plot, f"SB3 PPO, {args.envs} envs, seed {args.seed}, "
                 f"{args.episodes} held-out episodes per point")
    policy = to_mlp_policy(model)
    if args.npz is not None:
        policy.save(args.npz)
        print(f"saved {args.npz}")
    if args.onnx is not None:
        export_onnx(model, args.onnx)
        print(f"exported {args.onnx}")
    print("held-out episodes in unseen generated worlds:")
    print(format_summary(evaluate(policy, args.episodes, workers=args.workers)))


if __name__ == "__main__":
    main()
