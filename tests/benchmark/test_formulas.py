"""Each metric formula on a case computed by hand."""
import math

import numpy as np
import pytest

from pymunk_bot.outcomes.navigation import formulas
from pymunk_bot.outcomes.navigation.definitions import Thresholds


def test_disc_clearance_is_centre_distance_less_both_radii():
    clear = formulas.disc_clearances(np.array([0.0, 0.0]), 0.2,
                                     np.array([[3.0, 4.0], [0.3, 0.0]]), np.array([0.25, 0.25]))
    assert clear == pytest.approx([5.0 - 0.45, 0.3 - 0.45])  # negative while overlapping


def test_time_to_collision_head_on_miss_apart_and_overlap():
    rel = np.array([[5.0, 0.0], [5.0, 0.0], [5.0, 2.0], [0.3, 0.0]])
    vel = np.array([[-2.0, 0.0], [2.0, 0.0], [-2.0, 0.0], [0.0, 0.0]])
    ttc = formulas.times_to_collision(rel, vel, np.full(4, 0.5))
    assert ttc[0] == pytest.approx((5.0 - 0.5) / 2.0)  # closing at 2 m/s over 4.5 m
    assert math.isinf(ttc[1])  # moving apart
    assert math.isinf(ttc[2])  # passes 2 m to the side: never within 0.5 m
    assert ttc[3] == 0.0  # already touching


def test_kinematics_of_constant_acceleration():
    period = 0.1
    t = np.arange(6) * period
    v = np.column_stack([0.5 * t, np.zeros_like(t)])  # 0.5 m/s^2 along x
    k = formulas.sample_kinematics(v, period)
    assert k["max_acceleration"] == pytest.approx(0.5)
    assert k["mean_acceleration"] == pytest.approx(0.5)
    assert k["max_jerk"] == pytest.approx(0.0, abs=1e-9)
    assert k["max_speed"] == pytest.approx(0.25)
    assert k["min_speed"] == 0.0


def test_failure_to_progress_needs_a_whole_window_without_gain():
    t = np.arange(0, 20.01, 1.0)
    moving = 10.0 - 0.5 * t  # gains 5 m per 10 s window
    assert not formulas.failed_to_progress(t, moving, 10.0, 0.1)
    stuck = np.where(t < 5, 10.0 - t, 5.0)  # no gain from t = 5 s on: a whole window by 15 s
    assert formulas.failed_to_progress(t, stuck, 10.0, 0.1)
    assert not formulas.failed_to_progress(t[:10], stuck[:10], 10.0, 0.1)  # too short to tell


def test_spl():
    assert formulas.spl(True, 4.0, 5.0) == pytest.approx(0.8)
    assert formulas.spl(True, 4.0, 3.9) == 1.0  # a shortcut (tolerance) never scores above 1
    assert formulas.spl(False, 4.0, 4.0) == 0.0


def test_signature_changes_with_every_threshold():
    base = Thresholds()
    assert base.signature() == Thresholds().signature()
    for change in ({"personal_space": 0.4}, {"stall_speed": 0.1}, {"progress_window": 5.0},
                   {"progress_distance": 0.2}, {"sample_period": 0.2}, {"spl_resolution": 0.1}):
        assert Thresholds(**change).signature() != base.signature()
    with pytest.raises(ValueError, match="personal_space"):
        Thresholds(personal_space=-1.0)
