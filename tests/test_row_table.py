"""Compiled passes given their arrays by address (physics/row_table.py): the table checks what
it is given, and the passes built on it (a differential drive's coast and hold, the
bookkeeping after the physics) give the very floats that the components' own calls give."""
from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from pymunk_bot.engine.simulation import Simulation
from pymunk_bot.physics.row_table import RowTable


class _Rows:
    def __init__(self, n: int) -> None:
        self.xy = np.arange(2.0 * n).reshape(n, 2)


def test_the_table_refuses_an_array_a_pass_cannot_view_in_place() -> None:
    rows = _Rows(3)
    rows.xy = rows.xy[:, ::-1]  # a strided view
    with pytest.raises(TypeError, match="_Rows.xy must be a C-contiguous 2-D array of float64"):
        RowTable([(rows, "xy", np.float64, 2)])
    rows.xy = np.zeros((3, 2), dtype=np.float32)
    with pytest.raises(TypeError, match="float64"):
        RowTable([(rows, "xy", np.float64, 2)])


def _scenario(odometry: dict[str, Any] | None = None) -> dict[str, Any]:
    """Two diff-drive robots circling among boxes (they meet walls: contacts, substeps), one
    with a goal, and an omni robot (its own drive group and odometry)."""
    robots: list[dict[str, Any]] = [
        {"name": "a", "pose": [2.0, 2.0, 0.0], "goal": {"position": [6.0, 6.0]},
         "controller": {"type": "wheels", "left": 0.8, "right": 1.0}},
        {"name": "b", "pose": [8.0, 3.0, 1.0], "controller": {"type": "wheels", "left": 1.2,
                                                                "right": 0.7}},
        {"name": "c", "drive": "omni", "pose": [5.0, 8.0, 0.0],
         "controller": {"type": "velocity", "v": 0.5, "vy": 0.3, "omega": 0.4}}]
    if odometry is not None:
        for robot in robots[:2]:
            robot["odometry"] = odometry
    return {"name": "passes", "world": {"size": [10.0, 10.0]},
            "obstacles": [{"type": "box", "center": [5.0, 5.0], "size": [1.0, 2.0]},
                          {"type": "box", "center": [3.0, 7.0], "size": [0.6, 0.6]}],
            "robots": robots}


def _run(data: dict[str, Any], fused: bool) -> np.ndarray:
    sim = Simulation.from_dict(data, source="passes")
    if not fused:  # every group through its own calls: the drive's, the hold's, the odometry's
        built = sim.built
        propulsion = built.propulsion
        propulsion._wheels = [None] * len(propulsion._wheels)
        pairs = [(drive, odometry) for (drive, _), (odometry, _)
                 in zip(built.drive_groups, built.odometry_groups)]
        sim._bookkeeping = _Unfused(built, pairs)
    sim.run(12.0)
    return np.concatenate([np.concatenate([r.pose, r.odometry.pose, [r.distance]])
                           for r in sim.robots.values()])


class _Unfused:
    """The bookkeeping as each component does it on its own: positions read, the fleet's
    advance, each odometry fed by its drive."""

    def __init__(self, built: Any, pairs: list[tuple[Any, Any]]) -> None:
        from pymunk_bot.robots.progress import odometry_feed
        self.built = built
        self.feeds = [odometry_feed(drive, odometry) for drive, odometry in pairs]

    def after_tick(self, now: float) -> None:
        self.built.fleet.advance(self.built.propulsion.positions(), now)
        for feed in self.feeds:
            feed()


# plain encoders (dead-reckoned in the bookkeeping pass) and scaled, noisy ones (their own)
@pytest.mark.parametrize("odometry", [None, {"left_scale_error": 0.02, "wheel_noise_std": 0.01}])
def test_the_fused_passes_give_the_floats_of_each_components_own_calls(odometry) -> None:
    data = _scenario(odometry)
    fused, unfused = _run(data, True), _run(data, False)
    assert np.array_equal(fused, unfused)
    assert np.isfinite(fused).all() and fused[6] > 3.0  # robot a drove a few metres
