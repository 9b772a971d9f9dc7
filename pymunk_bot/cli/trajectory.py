"""`pymunk-bot run ... --trajectory-out DIR`: every robot's trajectories as TUM files.

DIR/<robot>.truth.tum, <robot>.odometry.tum and <robot>.estimate.tum (the localizer's pose;
the odometry's when the robot names no localizer), sampled at the same times, so evo scores a
run as it is: ``evo_ape tum DIR/r1.truth.tum DIR/r1.estimate.tum``. DIR is checked (and made,
if its parent exists) before the run; each file is written atomically after it.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.localization.tum import KINDS, TrajectoryRecorder
from pymunk_bot.outcomes.results import writable_problem

OPTION = "--trajectory-out"


def add_run_options(run: argparse.ArgumentParser) -> None:
    """Add --trajectory-out to the `run` subcommand."""
    run.add_argument(OPTION, dest="trajectory_out", type=Path, metavar="DIR",
                     help="write each robot's true, odometry and estimated poses as TUM files "
                          "(DIR/<robot>.truth.tum, .odometry.tum, .estimate.tum) for evo")


@dataclass
class TrajectoryOutput:
    """Where the recorded trajectories go once the run is over."""

    directory: Path
    recorder: TrajectoryRecorder

    def save(self, sim) -> list[Path]:
        """Write every robot's three TUM files; returns their paths."""
        written = self.recorder.write(self.directory, sim.config.name)
        print(f"wrote {len(written)} trajectories ({len(self.recorder.times)} poses each) "
              f"to {self.directory}")
        return written


def _check_directory(directory: Path, robots) -> Path:
    if directory.exists() and not directory.is_dir():
        raise ScenarioError(OPTION, "", f"{directory} exists and is not a directory")
    if not directory.exists():
        parent = directory.parent if str(directory.parent) else Path(".")
        if not parent.is_dir():
            raise ScenarioError(OPTION, "", f"{directory}: directory {parent} does not exist")
        try:
            directory.mkdir()
        except OSError as exc:
            raise ScenarioError(OPTION, "", f"{directory}: cannot create it "
                                            f"({exc.strerror or exc})") from None
    for name in robots:
        for kind in KINDS:
            problem = writable_problem(directory / f"{name}.{kind}.tum")
            if problem is not None:
                raise ScenarioError(OPTION, "", problem)
    return directory


def prepare_trajectory_output(args: argparse.Namespace, sim) -> TrajectoryOutput | None:
    """Check --trajectory-out before the run and start recording (ScenarioError: exit 2)."""
    directory = getattr(args, "trajectory_out", None)
    if directory is None:
        return None
    directory = _check_directory(Path(directory), sim.robots)
    return TrajectoryOutput(directory, TrajectoryRecorder().attach(sim))
