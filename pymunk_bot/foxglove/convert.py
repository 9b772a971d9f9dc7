"""``pymunk-bot convert IN OUT``: a run log from one format to the other (.npz <-> .mcap).

An .npz log becomes the same channels a live run writes (transforms, poses, scans, scene,
state, and the events that can be told from the log: contacts and goals reached). What an
.npz does not hold (planned paths, localizer estimates, controller status) is absent.
"""
from __future__ import annotations

from pathlib import Path

from pymunk_bot.outcomes.runlog import RunLog


def convert(source: str | Path, target: str | Path) -> RunLog:
    """Read ``source`` (.npz or .mcap) and write ``target`` (.mcap or .npz), atomically."""
    from pymunk_bot.foxglove.reader import load_any

    log = load_any(source)
    if Path(target).suffix.lower() == ".mcap":
        write_mcap(log, target)
    else:
        log.save(target)
    return log


def write_mcap(log: RunLog, path: str | Path) -> None:
    """Write ``log`` as MCAP with Foxglove schemas (see docs/foxglove.md), atomically."""
    from pymunk_bot.foxglove.mcap_log import McapWriter
    from pymunk_bot.foxglove.snapshot import geometry_of_log, snapshots_of_log

    writer = McapWriter(path)
    try:
        snapshots = snapshots_of_log(log)
        writer.publisher.start(geometry_of_log(log), next(snapshots))
        for snapshot in snapshots:
            writer.publisher.publish(snapshot)
        writer.commit()
    except BaseException:
        writer.abort()
        raise
