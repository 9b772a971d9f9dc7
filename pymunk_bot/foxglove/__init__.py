"""Foxglove and MCAP: every run viewable in the robotics tools people already use.

- :mod:`.snapshot`: what one step looks like (from a live simulation or an .npz run log);
- :mod:`.publisher`: the channel layer, snapshots -> Foxglove messages (shared by file and live);
- :mod:`.mcap_log`: ``run --log run.mcap``, an observer writing MCAP atomically;
- :mod:`.live`: ``run --foxglove``, the SDK's WebSocket server, paced at real time;
- :mod:`.teleop`: client publishing on that server (Foxglove's Teleop panel on ``/cmd_vel``);
- :mod:`.reader`: MCAP back to a :class:`~pymunk_bot.outcomes.runlog.RunLog` (``replay``, ``plot``);
- :mod:`.convert`: ``pymunk-bot convert run.npz run.mcap``.

Topic and frame names are in :mod:`.frames` and docs/foxglove.md. The optional packages
(``foxglove-sdk``, ``mcap``, ``mcap-protobuf-support``) are imported only when used:
:func:`require` turns a missing one into a one-line error naming the install command.
"""
from __future__ import annotations

from typing import Any

from pymunk_bot.config.extras import require as require_extra


def require(module: str, option: str) -> Any:
    """Import ``module`` (e.g. "foxglove"), or raise a ScenarioError naming the install command."""
    return require_extra(module, option, "foxglove")
