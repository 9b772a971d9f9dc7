"""Localization and mapping among people: returns short of the map, walkers not burned in."""
import numpy as np
import pytest

from bench.localization_robustness import GLOBAL_TIME, PEOPLE_OCCUPIED, PEOPLE_RMSE, run_one
from pymunk_bot.localization import MappingConfig, OccupancyMapper
from pymunk_bot.localization.dynamic import MAX_SHORT_SHARE, excused_fit, short_returns
from pymunk_bot.localization.likelihood import LikelihoodField
from pymunk_bot.maps.grid import OccupancyGrid
from pymunk_bot.robots.readings import LaserScan


def _walled_grid() -> OccupancyGrid:
    """A 6 x 4 m map, 5 cm cells, with a wall at x = 4 .. 4.2 m."""
    data = np.zeros((80, 120), dtype=np.int8)
    data[:, 80:84] = 100
    return OccupancyGrid(data, 0.05, (0.0, 0.0))


def test_a_return_in_front_of_the_wall_is_short_one_on_it_or_beyond_is_not():
    field = LikelihoodField(_walled_grid(), 2.0)
    pose = np.array([1.0, 2.0, 0.0])  # 3 m from the wall, facing it
    points = np.array([[1.5, 0.0],    # a leg 1.5 m ahead: short
                       [2.8, 0.0],    # 0.2 m before the wall: within the margin
                       [3.0, 0.0],    # on the wall
                       [3.6, 0.0]])   # beyond it: the pose is wrong, not a person
    short = short_returns(field, pose, points, (0.0, 0.0), 8.0, margin=0.3)
    assert short.tolist() == [True, False, False, False]


def test_short_returns_follow_the_sensor_mount_and_heading():
    field = LikelihoodField(_walled_grid(), 2.0)
    pose = np.array([1.0, 2.0, np.pi / 2])  # facing +y: the wall is to the robot's right (-y)
    # a LiDAR mounted 0.1 m ahead; a return 1 m to the right ends 2 m short of the wall
    short = short_returns(field, pose, np.array([[0.1, -1.0], [0.1, -3.0]]), (0.1, 0.0), 8.0, 0.3)
    assert short.tolist() == [True, False]


def test_excused_fit_leaves_out_short_returns_up_to_a_share():
    fits = np.array([True] * 6 + [False] * 4)
    none_short = np.zeros(10, dtype=bool)
    assert excused_fit(fits, none_short) == pytest.approx(0.6)
    four_short = np.array([False] * 6 + [True] * 4)  # the misfits were people
    assert excused_fit(fits, four_short) == pytest.approx(1.0)
    # a scan that is nearly all short (a wrong pose seeing a hall where the robot is in a
    # small room) is not excused beyond MAX_SHORT_SHARE
    all_short = np.ones(10, dtype=bool)
    assert excused_fit(fits, all_short) == 0.0
    assert excused_fit(np.ones(10, dtype=bool), np.array([True] * 9 + [False])) == pytest.approx(
        1 / ((1 - MAX_SHORT_SHARE) * 10))
    assert excused_fit(np.zeros(0, dtype=bool), np.zeros(0, dtype=bool)) == 1.0


def _scan(ranges: np.ndarray, time: float) -> LaserScan:
    return LaserScan(ranges=ranges, angles=np.linspace(-0.3, 0.3, ranges.size), min_range=0.1,
                     max_range=8.0, offset=(0.0, 0.0, 0.0), time=time)


def _walker_then_gone(config: MappingConfig) -> tuple[float, float]:
    """A person 1 m ahead of the robot for 1 s of 10 Hz scans, then gone for 0.3 s: the
    occupancy probability [%] of the person's cell and of the wall's cell at the end."""
    mapper = OccupancyMapper(config, ((0.0, 0.0), (6.0, 4.0)))
    pose = np.array([1.0, 2.0, 0.0])
    for k in range(10):  # the person stands at x = 2 m
        mapper.integrate(pose, _scan(np.full(31, 1.0), 0.1 * k))
    for k in range(3):  # gone: the beams reach the wall at x = 4 m
        mapper.integrate(pose, _scan(np.full(31, 3.0), 1.0 + 0.1 * k))
    grid = mapper.grid
    person = grid.data[grid.cell_of(np.array([2.01, 2.0]))]
    wall = grid.data[grid.cell_of(np.array([4.01, 2.0]))]
    return float(person), float(wall)


def test_a_walker_seen_through_three_times_is_not_left_in_the_map():
    person, wall = _walker_then_gone(MappingConfig())
    assert person < 50  # free (it read 86 % with plain log-odds, clear_decay 1)
    assert wall > 65
    person_plain, _ = _walker_then_gone(MappingConfig(clear_decay=1.0))
    assert person_plain > 65  # the plain model keeps it: what the decay is for


@pytest.mark.slow
def test_mcl_tracks_among_thirty_walkers():
    """An office with 30 social-force walkers on the robot's route (seed 3): MCL with every
    return weighed and Nav2's sigma_hit 0.2 m lost itself (109 cm RMSE, measured 2026-12-05
    after the walkers' speculative contact changed the crowd: seed 1, this test's seed before,
    then tracked either way); with returns short of the map left out, 1.0 cm."""
    got = run_one("mcl", "office_sf30", "typical", 3)
    assert got is not None and not got.error
    assert got.rmse <= PEOPLE_RMSE, got.line()
    before = run_one("mcl", "office_sf30", "typical", 3, {"reject_short": False,
                                                          "sigma_hit": 0.2})
    assert before is not None and before.rmse > PEOPLE_RMSE, before.line()


@pytest.mark.slow
def test_mapping_among_ten_walkers_keeps_at_most_1_percent_of_their_cells_occupied():
    """Issue 36: the map built with the true pose in an office with 10 social-force walkers
    (seed 3, the worst of seeds 0-9) holds at most 1 % of the cells only people walked through
    occupied; plain log-odds (clear_decay 1) held 1.26 % there."""
    got = run_one("mapping", "office_sf10", "typical", 3)
    assert got is not None and not got.error
    assert got.people_occupied <= PEOPLE_OCCUPIED, got.line()
    assert got.map_precision >= 0.9, got.line()
    plain = run_one("mapping", "office_sf10", "typical", 3, {"clear_decay": 1.0})
    assert plain is not None and plain.people_occupied > PEOPLE_OCCUPIED, plain.line()


@pytest.mark.slow
def test_a_global_start_among_thirty_walkers_converges_on_the_right_pose():
    """Issue 36: a global start in the warehouse with 30 ORCA walkers (seed 3; seed 1 until
    the ORCA walkers' larger nudge changed the crowd). With every return weighed while
    localizing (reject_moving off, as before) MCL said `localized` on a wrong pose for 13.6 s
    and converged only at 76.5 s; leaving out the returns of things that move (moving.py), it
    converges at 10.6 s, never wrong."""
    got = run_one("mcl_global", "warehouse_orca30", "typical", 3)
    assert got is not None and not got.error
    assert got.converged_at <= GLOBAL_TIME and got.wrong_localized == 0.0, got.line()
    before = run_one("mcl_global", "warehouse_orca30", "typical", 3, {"reject_moving": False})
    assert before is not None and before.wrong_localized > 0.0, before.line()


@pytest.mark.slow
def test_mcl_leaves_out_short_returns_however_few_are_left():
    """Issue 36: the warehouse with 10 walkers, seed 12, a 3.5 m LiDAR (20 returns in the
    open aisles). Walkers hid more than half of them; with fewer than 10 left the scan used to
    be weighed whole, people included: one scan fitted 40 %, the filter gave up tracking and
    settled 17 m away (12.3 m RMSE). Now they stay out however few are left: 2.1 cm."""
    got = run_one("mcl", "warehouse_sf10", "typical", 12)
    assert got is not None and not got.error
    assert got.rmse <= PEOPLE_RMSE, got.line()
