"""Gymnasium and PettingZoo environments (needs the `rl` extra).

    import gymnasium as gym
    import pymunk_bot.envs                       # registers pymunk_bot/Navigation-v0
    env = gym.make("pymunk_bot/Navigation-v0")   # the built-in default scenario
    # the same with nothing imported (Gymnasium 1.x loads no plugin entry points; a regular
    # install's start-up hook registers the id, see docs/learning.md), in every install:
    env = gym.make("pymunk_bot.envs:pymunk_bot/Navigation-v0")
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

from _pymunk_bot_gymnasium import NAVIGATION_ID, register

from pymunk_bot.envs.navigation import NavigationEnv
from pymunk_bot.envs.task import RewardWeights
from pymunk_bot.envs.vector import NavigationVectorEnv


def register_envs() -> None:
    """Register the environment ids with Gymnasium (idempotent; importing this module does, and
    so does importing Gymnasium where pymunk-bot was installed with its start-up hook)."""
    register(gymnasium)


register_envs()


def __getattr__(name: str):
    if name == "MultiRobotEnv":  # PettingZoo is imported only when asked for
        from pymunk_bot.envs.multi import MultiRobotEnv

        return MultiRobotEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["MultiRobotEnv", "NAVIGATION_ID", "NavigationEnv", "NavigationVectorEnv",
           "RewardWeights", "register_envs"]
