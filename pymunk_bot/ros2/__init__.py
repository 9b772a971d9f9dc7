"""ROS 2 without ROS: rosbag2 MCAP files and a rosbridge server, in pure Python.

- :mod:`.names`: topics, frames and QoS, as ROS conventions (REP-103/105/117) name them;
- :mod:`.messages`: snapshots of a run (:mod:`pymunk_bot.foxglove.snapshot`) -> standard
  ROS 2 messages (``rosbags`` types, Humble definitions);
- :mod:`.bag`: ``run --log run.mcap --profile ros2`` and ``convert --profile ros2``;
- :mod:`.jsonmsg`: messages <-> the JSON that rosbridge speaks;
- :mod:`.commands`: ``/cmd_vel`` and ``/goal_pose`` -> the robot's public command API, with
  the watchdog that gives a robot back to its controller;
- :mod:`.bridge` and :mod:`.protocol`: ``run --rosbridge``, the rosbridge v2 protocol.

The optional packages (``rosbags``, ``mcap``, ``websockets``) are imported only when used:
:func:`require` turns a missing one into a one-line error naming the install command.
"""
from __future__ import annotations

from typing import Any

from pymunk_bot.config.extras import require as require_extra


def require(module: str, option: str) -> Any:
    """Import ``module``, or raise a ScenarioError naming the install command."""
    return require_extra(module, option, "ros2")
