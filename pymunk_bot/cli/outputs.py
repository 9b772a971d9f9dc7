"""The command-line side of the views: `run --record/--log`, `plot` and `replay`.

main.py defines the options; the work is here so that main.py stays a thin dispatcher. Output
paths are checked before anything runs, so a typo costs no simulation time. Nothing here
imports pygame or matplotlib at module level.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.cli.arguments import check_output

if TYPE_CHECKING:
    from pymunk_bot.cli.foxglove import FoxgloveOutputs
    from pymunk_bot.cli.map_output import MapOutput
    from pymunk_bot.cli.trajectory import TrajectoryOutput
    from pymunk_bot.cli.ros2 import Ros2Outputs
    from pymunk_bot.outcomes.runlog import RunLogger

VIDEO_FORMATS = (".mp4", ".gif")
LOG_FORMATS = (".npz", ".mcap")
PLOT_FORMATS = (".png", ".pdf", ".svg")
MAX_FPS = 240.0  # [Hz]


def parse_size(text: str) -> tuple[int, int]:
    """'WxH' in pixels (argparse type: raises ValueError with a readable message)."""
    parts = text.lower().split("x")
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise ValueError(f"expected WIDTHxHEIGHT in pixels, e.g. 1280x720 (got '{text}')") from None
    if not (16 <= w <= 7680 and 16 <= h <= 4320):
        raise ValueError(f"frame size must be 16..7680 x 16..4320 pixels (got {w}x{h})")
    return w, h


def _check_fps(fps: float | None) -> None:
    if fps is not None and not (math.isfinite(fps) and 0 < fps <= MAX_FPS):
        raise ScenarioError("--fps", "", f"must be > 0 and <= {MAX_FPS:g} (got {fps:g})")


def _check_video_options(args) -> Path | None:
    record = getattr(args, "record", None)
    if record is None:
        for option, value in (("--fps", args.fps), ("--size", args.size)):
            if value is not None:
                raise ScenarioError(option, "", "only applies with --record")
        return None
    _check_fps(args.fps)
    return check_output("--record", Path(record), VIDEO_FORMATS)


# ---------------------------------------------------------------------------- run


@dataclass
class RunOutputs:
    """What `run` writes besides its JSON result: a video and/or a run log."""

    record: Path | None = None
    fps: float | None = None
    size: tuple[int, int] | None = None
    log_path: Path | None = None
    logger: RunLogger | None = None
    foxglove: FoxgloveOutputs | None = None  # an MCAP log and/or a live server
    ros2: Ros2Outputs | None = None  # a ROS 2 bag and/or a rosbridge server
    map_out: MapOutput | None = None  # the map a robot built (--map-out)
    trajectory: TrajectoryOutput | None = None  # TUM trajectories (--trajectory-out)

    def run_headless(self, sim, duration: float) -> None:
        """Run ``sim`` for ``duration`` (paced at real time while serving Foxglove live)."""
        if self.ros2 is not None and (self.ros2.live or self.foxglove is None):
            self.ros2.run_headless(sim, duration)  # paced while serving rosbridge
        elif self.foxglove is not None:
            self.foxglove.run_headless(sim, duration)
        else:
            sim.run(duration)

    def close(self) -> None:
        """After an error or Ctrl-C: drop unfinished files, stop servers."""
        if self.foxglove is not None:
            self.foxglove.close()
        if self.ros2 is not None:
            self.ros2.close()

    def record_run(self, sim, duration: float) -> None:
        """Run ``sim`` for ``duration`` while rendering the video (offscreen)."""
        from pymunk_bot.viewer import ViewerUnavailable, record_video

        if self.record is None:
            raise RuntimeError("record_run needs the video path (--record)")
        started = time.perf_counter()
        try:
            frames = record_video(sim, self.record, duration, fps=self.fps, size=self.size,
                                  progress=True)
        except ViewerUnavailable as exc:
            raise ScenarioError("--record", "", str(exc)) from None
        spent = max(time.perf_counter() - started, 1e-9)  # [s] of wall time, drawing included
        print(f"wrote {self.record} ({frames} frames in {spent:.1f} s: {frames / spent:.0f} "
              f"frames/s, {duration / spent:.2f}x real time)")

    def finish(self, sim=None) -> list[OSError]:
        """Write the run log, the built map (--map-out) and the trajectories, if asked for.
        Each is tried, whatever happened to the others: returns the writes that failed (a
        full disk: an OSError naming the file), after keeping what was complete."""
        failed: list[OSError] = []
        steps: list = []
        if self.map_out is not None and sim is not None:
            steps.append(lambda: self.map_out.save(sim))
        if self.trajectory is not None and sim is not None:
            steps.append(lambda: self.trajectory.save(sim))
        if self.logger is not None:
            steps.append(self._save_log)
        if self.foxglove is not None:
            steps.append(self.foxglove.finish)
        if self.ros2 is not None:
            steps.append(self.ros2.finish)
        for step in steps:
            try:
                step()
            except OSError as exc:
                failed.append(exc)
        return failed

    def _save_log(self) -> None:
        if self.logger is None or self.log_path is None:
            raise RuntimeError("a run logger needs its log path (--log)")
        self.logger.save(self.log_path)
        steps = len(self.logger.log().time) - 1
        print(f"wrote {self.log_path} ({steps} steps)")


def prepare_outputs(args, sim) -> RunOutputs:
    """Check --record/--fps/--size/--log before the run and start the logger."""
    from pymunk_bot.cli.map_output import prepare_map_output
    from pymunk_bot.cli.trajectory import prepare_trajectory_output

    outputs = RunOutputs(record=_check_video_options(args), fps=args.fps, size=args.size,
                         map_out=prepare_map_output(args, sim),
                         trajectory=prepare_trajectory_output(args, sim))
    if args.log is not None:
        from pymunk_bot.outcomes.runlog import RunLogger

        outputs.log_path = check_output("--log", Path(args.log), LOG_FORMATS)
        if outputs.log_path.suffix.lower() == ".npz":
            outputs.logger = RunLogger().attach(sim)
    from pymunk_bot.cli.foxglove import prepare_foxglove

    from pymunk_bot.cli.ros2 import prepare_ros2, wants_ros2_bag

    outputs.ros2 = prepare_ros2(args, sim, outputs.log_path)  # --profile ros2, --rosbridge
    foxglove_log = None if wants_ros2_bag(args) else outputs.log_path
    try:
        outputs.foxglove = prepare_foxglove(args, sim, foxglove_log)  # .mcap, --foxglove
    except BaseException:
        outputs.close()  # a rosbridge server already started
        raise
    return outputs


# ---------------------------------------------------------------------------- plot, replay


def cmd_plot(args) -> int:
    """`pymunk-bot plot LOG [-o OUT] [--kind K] [--robot NAME]`."""
    from pymunk_bot.foxglove.reader import load_any as load_log  # .npz or .mcap
    from pymunk_bot.viewer.plots import save_plot

    log_path = Path(args.log)
    if args.output is not None:
        out = Path(args.output)
    else:
        suffix = "" if args.kind == "all" else f"_{args.kind}"
        out = log_path.with_name(f"{log_path.stem}{suffix}.png")
    check_output("--output", out, PLOT_FORMATS)
    log = load_log(log_path)
    save_plot(log, out, args.kind, args.robot)
    print(f"wrote {out}")
    return 0


def cmd_replay(args, display_available: bool) -> int:
    """`pymunk-bot replay LOG [--record VIDEO]`: play a run log in the window or to a video."""
    from pymunk_bot.foxglove.reader import load_any as load_log  # .npz or .mcap
    from pymunk_bot.viewer import ViewerUnavailable

    record = _check_video_options(args)
    log = load_log(args.log)
    if record is not None:
        from pymunk_bot.viewer import record_video

        frames = record_video(log, record, None, fps=args.fps, size=args.size, progress=True)
        print(f"wrote {record} ({frames} frames)")
        return 0
    if not display_available:
        raise ScenarioError("replay", "", "no display available for the window; render the "
                                          "log to a video instead (--record run.mp4)")
    try:
        from pymunk_bot.viewer import replay_window

        replay_window(log)
    except ViewerUnavailable as exc:
        raise ScenarioError("replay", "", f"{exc}; render the log to a video instead "
                                          "(--record run.mp4)") from None
    return 0
