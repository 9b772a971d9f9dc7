"""`pymunk-bot run ... --trajectory-out DIR`: every robot's trajectories as TUM files.

DIR/<robot>.truth.tum, <robot>.odometry.tum and <robot>.estimate.tum (the localizer's pose;
the odometry's when the robot names no localizer), sampled at the same times, so evo scores a
run as it is: ``evo_ape tum DIR/r1.truth.tum DIR/r1.estimate.tum``. DIR is checked before
the run and made only after it, with its files: they are written in a hidden folder beside DIR
that is renamed onto it, so an interrupted run leaves no folder. Into a DIR that exists, each
file is written atomically. A full disk keeps the files that were complete.
"""
from __future__ import annotations

import argparse
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.outcomes.results import temp_folder_beside, writable_problem

if TYPE_CHECKING:  # the localization package loads only when a run records trajectories
    from pymunk_bot.localization.tum import TrajectoryRecorder

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
        """Write every robot's three TUM files; returns their paths. OSError naming the file
        that could not be written (a full disk), after keeping those that were complete."""
        if self.directory.is_dir():
            written = self.recorder.write(self.directory, sim.config.name)
        else:
            written = self._write_new_folder(sim.config.name)
        print(f"wrote {len(written)} trajectories ({len(self.recorder.times)} poses each) "
              f"to {self.directory}")
        return written

    def _write_new_folder(self, scenario: str) -> list[Path]:
        staging = Path(temp_folder_beside(self.directory))
        try:
            written = self.recorder.write(staging, scenario)
        except OSError as exc:
            if any(staging.iterdir()):  # the complete files are kept
                os.rename(staging, self.directory)
            else:
                shutil.rmtree(staging, ignore_errors=True)
            if exc.filename:  # the file's name in DIR, not in the hidden folder
                exc.filename = str(self.directory / Path(exc.filename).name)
            raise
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
        os.rename(staging, self.directory)
        return [self.directory / path.name for path in written]


def _check_directory(directory: Path, robots) -> Path:
    if directory.exists() and not directory.is_dir():
        raise ScenarioError(OPTION, "", f"{directory} exists and is not a directory")
    if not directory.exists():  # made after the run: its parent must take it
        problem = writable_problem(directory)
        if problem is not None:
            raise ScenarioError(OPTION, "", problem)
        return directory
    from pymunk_bot.localization.tum import KINDS

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
    from pymunk_bot.localization.tum import TrajectoryRecorder

    directory = _check_directory(Path(directory), sim.robots)
    return TrajectoryOutput(directory, TrajectoryRecorder().attach(sim))
