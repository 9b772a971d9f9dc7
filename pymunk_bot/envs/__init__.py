"""Gymnasium and PettingZoo environments (needs the `rl` extra).

    import gymnasium as gym
    import pymunk_bot.envs                       # registers pymunk_bot/Navigation-v0
    env = gym.make("pymunk_bot/Navigation-v0")   # the built-in default scenario
    envs = gym.make_vec("pymunk_bot/Navigation-v0", num_envs=16,
                        vectorization_mode="vector_entry_point")
    from pymunk_bot.envs import MultiRobotEnv     # PettingZoo ParallelEnv

See docs/learning.md for spaces, reward, termination and seeding.
"""
from __future__ import annotations

try:
    import gymnasium
except ImportError:  # pragma: no cover - depends on the install
    raise ImportError("pymunk_bot.envs needs gymnasium: pip install 'pymunk-bot[rl]'") from None

from pymunk_bot.envs.navigation import NavigationEnv
from pymunk_bot.envs.task import RewardWeights
from pymunk_bot.envs.vector import NavigationVectorEnv

NAVIGATION_ID = "pymunk_bot/Navigation-v0"


def register_envs() -> None:
    """Register the environment ids with Gymnasium (idempotent; also the entry point)."""
    if NAVIGATION_ID not in gymnasium.registry:
        gymnasium.register(id=NAVIGATION_ID, entry_point="pymunk_bot.envs.navigation:NavigationEnv",
                           vector_entry_point="pymunk_bot.envs.vector:NavigationVectorEnv",
                           disable_env_checker=False)


register_envs()


def __getattr__(name: str):
    if name == "MultiRobotEnv":  # PettingZoo is imported only when asked for
        from pymunk_bot.envs.multi import MultiRobotEnv

        return MultiRobotEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["MultiRobotEnv", "NAVIGATION_ID", "NavigationEnv", "NavigationVectorEnv",
           "RewardWeights", "register_envs"]
