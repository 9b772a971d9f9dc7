"""Train a navigation policy with Stable-Baselines3 PPO on pymunk_bot/Navigation-v0.

    pip install 'pymunk-bot[rl,train]'              (Stable-Baselines3 brings PyTorch)
    python examples/train_ppo.py --steps 200000 --envs 8 --out ppo_navigation.zip
    python examples/train_ppo.py --evaluate ppo_navigation.zip

The policy sees a 90-beam LiDAR, the goal in its own frame and its speeds; the goal is drawn
anew each episode (``random_goal``) so it learns to navigate, not one path.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

ENV_ID = "pymunk_bot/Navigation-v0"
ENV_KWARGS = {"lidar": {"beams": 90}, "random_goal": True, "max_episode_time": 30.0}


def make_vec_env(n_envs: int, seed: int, **overrides):
    """``n_envs`` copies of Navigation-v0 in SB3's own vector env (SB3 has its own VecEnv
    interface; Gymnasium's native vector env serves other trainers)."""
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

    import pymunk_bot.envs  # noqa: F401  (registers the ids)

    return sb3_make_vec_env(ENV_ID, n_envs=n_envs, seed=seed,
                            env_kwargs={**ENV_KWARGS, **overrides})


def train(steps: int, n_envs: int = 8, seed: int = 0, out: Path | None = None,
          n_steps: int = 256, **env_overrides):
    """Train PPO for ``steps`` environment steps; returns the model (saved to ``out``)."""
    from stable_baselines3 import PPO

    env = make_vec_env(n_envs, seed, **env_overrides)
    model = PPO("MlpPolicy", env, n_steps=n_steps, batch_size=min(256, n_steps * n_envs),
                learning_rate=3e-4, gamma=0.99, seed=seed, verbose=0, device="cpu")
    model.learn(total_timesteps=steps)
    if out is not None:
        model.save(out)
    env.close()
    return model


def evaluate(model, episodes: int = 10, seed: int = 1000, **env_overrides) -> dict:
    """Success rate, mean return and collisions of the deterministic policy."""
    import gymnasium as gym

    import pymunk_bot.envs  # noqa: F401

    env = gym.make(ENV_ID, **{**ENV_KWARGS, **env_overrides})
    returns, successes, collisions = [], 0, 0
    for k in range(episodes):
        obs, _ = env.reset(seed=seed + k)
        total, done = 0.0, False
        while not done:
            action, _ = model.predict(obs, deterministic=True)
            obs, reward, terminated, truncated, info = env.step(action)
            total += reward
            done = terminated or truncated
        returns.append(total)
        successes += bool(info["goal_reached"])
        collisions += info["collisions"]
    return {"success_rate": successes / episodes, "mean_return": float(np.mean(returns)),
            "collisions_per_episode": collisions / episodes}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200_000, help="environment steps")
    parser.add_argument("--envs", type=int, default=8, help="worlds trained on at once")
    parser.add_argument("--episodes", type=int, default=10, help="evaluation episodes")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("ppo_navigation.zip"))
    parser.add_argument("--evaluate", type=Path, metavar="MODEL.zip",
                        help="only evaluate a saved model")
    args = parser.parse_args(argv)
    if args.evaluate is not None:
        from stable_baselines3 import PPO

        model = PPO.load(args.evaluate, device="cpu")
    else:
        model = train(args.steps, args.envs, args.seed, args.out)
        print(f"saved {args.out}")
    print(evaluate(model, args.episodes))


if __name__ == "__main__":
    main()
