"""Localization and mapping among people: returns short of the map, walkers not burned in."""
import numpy as np
import pytest

from bench.localization_robustness import GLOBAL_TIME, PEOPLE_OCCUPIED, PEOPLE_RMSE, run_one
from pymunk_bot.localization import MappingConfig, OccupancyMapper
from pymunk_bot.localization.dynamic import excused_fit, short_returns
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


def test_excused_fit_leaves_out_short_returns_and_says_nothing_on_too_few_left():
    fits = np.array([True] * 6 + [False] * 4)
    none_short = np.zeros(10, dtype=bool)
    assert excused_fit(fits, none_short, 5) == pytest.approx(0.6)
    four_short = np.array([False] * 6 + [True] * 4)  # the misfits were people
    assert excused_fit(fits, four_short, 5) == pytest.approx(1.0)
    # most of the scan short (a robot wedged among people): the rest is judged alone
    many = np.array([True] * 5 + [False] * 15)
    assert excused_fit(np.ones(20, dtype=bool), ~many, 5) == pytest.approx(1.0)
    assert excused_fit(np.array([True] * 2 + [False] * 18), ~many, 5) == pytest.approx(0.4)
    # fewer returns left than asked: the scan neither confirms nor contradicts
    assert excused_fit(fits, np.array([True] * 6 + [False] * 4), 5) is None
    assert excused_fit(np.zeros(0, dtype=bool), np.zeros(0, dtype=bool), 1) is None


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
    """An office with 30 social-force walkers on the robot's route (seed 3): with returns short
    of the map left out MCL tracks within the issue's 8 cm (1.0 cm when measured), and much
    closer than with every return weighed and Nav2's sigma_hit 0.2 m, which lost itself there
    (109 cm RMSE on 2026-12-05; 5.6 cm on the walk the substep gate's longer horizon gives,
    2026-12-06: the crowd's walk depends on the physics' substeps)."""
    got = run_one("mcl", "office_sf30", "typical", 3)
    assert got is not None and not got.error
    assert got.rmse <= PEOPLE_RMSE, got.line()
    before = run_one("mcl", "office_sf30", "typical", 3, {"reject_short": False,
                                                          "sigma_hit": 0.2})
    assert before is not None and before.rmse > 2.0 * got.rmse, (before.line(), got.line())


@pytest.mark.slow
def test_mapping_among_ten_walkers_keeps_at_most_1_percent_of_their_cells_occupied():
    """Issue 36: the map built with the true pose in an office with 10 social-force walkers
    (seed 3, once the worst of seeds 0-9) holds at most 1 % of the cells only people walked
    through occupied, and fewer than plain log-odds (clear_decay 1) there: 0.32 % against
    0.75 % (plain held 1.26 % before the substep gate's longer horizon changed the walk)."""
    got = run_one("mapping", "office_sf10", "typical", 3)
    assert got is not None and not got.error
    assert got.people_occupied <= PEOPLE_OCCUPIED, got.line()
    assert got.map_precision >= 0.9, got.line()
    plain = run_one("mapping", "office_sf10", "typical", 3, {"clear_decay": 1.0})
    assert plain is not None and plain.people_occupied > got.people_occupied, plain.line()


@pytest.mark.slow
def test_a_global_start_among_thirty_walkers_converges_on_the_right_pose():
    """Issue 36: a global start in the warehouse with 30 ORCA walkers (seed 3; seed 1 until
    the ORCA walkers' larger nudge changed the crowd). With every return weighed while
    localizing (reject_moving off, as before) MCL said `localized` on a wrong pose for 13.6 s
    and converged only at 76.5 s (since ORCA walkers keep 5 mm apart, the crowd differs: it
    converges at 33.2 s, past the bench's 20 s); leaving out the returns of things that move
    (moving.py), it converged at 10.6 s, now at 3.6 s, never wrong."""
    got = run_one("mcl_global", "warehouse_orca30", "typical", 3)
    assert got is not None and not got.error
    assert got.converged_at <= GLOBAL_TIME and got.wrong_localized == 0.0, got.line()
    before = run_one("mcl_global", "warehouse_orca30", "typical", 3, {"reject_moving": False})
    assert before is not None and (before.converged_at > GLOBAL_TIME
                                   or before.wrong_localized > 0.0), before.line()


@pytest.mark.slow
def test_a_global_start_among_thirty_walkers_is_not_drawn_to_a_look_alike_by_their_legs():
    """Issue 36: a global start in the warehouse with 30 ORCA walkers (seed 16). Instrumented
    per update: the true pose explained the scan worse than a look-alike aisle 33-42 m away,
    turned 90 deg, by 0.04-0.2 mean log pz a return, because 2-7 of its 30-40 weighed returns
    ended on walkers the moving test had not caught (seen entering free space a moment before,
    then walking away along the beam or beside a shelf); MCL said `localized` there at 52 s and
    converged only at 68 s. Walkers seen moving stay left out for `moving_window`
    (`moving_track`): converged at 13.3 s, never localized on a wrong pose."""
    got = run_one("mcl_global", "warehouse_orca30", "typical", 16)
    assert got is not None and not got.error
    assert got.converged_at <= GLOBAL_TIME and got.wrong_localized == 0.0, got.line()
    before = run_one("mcl_global", "warehouse_orca30", "typical", 16, {"moving_track": 0.0})
    assert before is not None and (before.converged_at > GLOBAL_TIME
                                   or before.wrong_localized > 0.0), before.line()


@pytest.mark.slow
def test_mcl_leaves_out_short_returns_however_few_are_left():
    """Issue 36: the warehouse with 10 walkers, seed 12, a 3.5 m LiDAR (20 returns in the
    open aisles). Walkers hid more than half of them; with fewer than 10 left the scan used to
    be weighed whole, people included: one scan fitted 40 %, the filter gave up tracking and
    settled 17 m away (12.3 m RMSE). Now they stay out however few are left: 2.1 cm."""
    got = run_one("mcl", "warehouse_sf10", "typical", 12)
    assert got is not None and not got.error
    assert got.rmse <= PEOPLE_RMSE, got.line()


def _room_grid() -> OccupancyGrid:
    """A closed 6 x 4 m room, 5 cm cells, walls 10 cm thick at its edges."""
    data = np.zeros((80, 120), dtype=np.int8)
    data[:2, :] = data[-2:, :] = data[:, :2] = data[:, -2:] = 100
    return OccupancyGrid(data, 0.05, (0.0, 0.0))


def _room_scan(pose: np.ndarray, people: np.ndarray, time: float, beams: int = 360) -> LaserScan:
    """A noiseless scan from ``pose`` in _room_grid's room (inner faces at 0.1 and 5.9 m, 0.1
    and 3.9 m) with ``people`` (k, 2) discs of radius 0.25 m in the way."""
    angles = np.linspace(-np.pi, np.pi, beams, endpoint=False)
    heading = pose[2] + angles
    dx, dy = np.cos(heading), np.sin(heading)
    with np.errstate(divide="ignore"):
        to_x = np.where(dx > 0, (5.9 - pose[0]) / dx, (0.1 - pose[0]) / dx)
        to_y = np.where(dy > 0, (3.9 - pose[1]) / dy, (0.1 - pose[1]) / dy)
    ranges = np.minimum(np.abs(to_x), np.abs(to_y))
    for centre in people:  # the nearer root of |pose + r (dx, dy) - centre| = 0.25
        ox, oy = pose[0] - centre[0], pose[1] - centre[1]
        b = ox * dx + oy * dy
        disc = b * b - (ox * ox + oy * oy - 0.25 ** 2)
        r = -b - np.sqrt(np.maximum(disc, 0.0))
        ranges = np.where((disc > 0) & (r > 0), np.minimum(ranges, r), ranges)
    return LaserScan(ranges=ranges, angles=angles, min_range=0.1, max_range=8.0,
                     offset=(0.0, 0.0, 0.0), time=time)


def _track_among(people_bearings: np.ndarray) -> tuple[list[bool], float, int]:
    """MCL (defaults, known start) driving 1.2 m along the room in 0.15 m steps, one scan each,
    with people 0.6 m away at ``people_bearings`` [rad] walking along with it: whether it said
    ``localized`` after each update, its worst position error [m] and how many scans left too
    few returns (not short) to judge the fit by."""
    from pymunk_bot.localization import MclConfig, MclLocalizer
    from pymunk_bot.localization.base import LocalizerContext, LocalizerInputs
    from pymunk_bot.robots.readings import RobotSpec

    start = np.array([2.0, 1.7, 0.0])
    context = LocalizerContext(robot=RobotSpec("r1", 0.2, 0.3, 1.0, 3.0), start_pose=start,
                               rng=np.random.default_rng(5), arena=(6.0, 4.0), map=_room_grid())
    mcl = MclLocalizer(MclConfig(), context)
    mcl.update(LocalizerInputs(0.0, start.copy(), _room_scan(start, np.zeros((0, 2)), 0.0)))
    said, worst = [], 0.0
    for k in range(1, 9):
        pose = start + np.array([0.15 * k, 0.0, 0.0])
        around = np.column_stack([np.cos(people_bearings), np.sin(people_bearings)])
        people = pose[:2] + 0.6 * around
        time = 0.2 * k
        mcl.update(LocalizerInputs(time, pose.copy(), _room_scan(pose, people, time)))
        said.append(mcl.localized)
        worst = max(worst, float(np.hypot(*(mcl.pose[:2] - pose[:2]))))
    return said, worst, mcl.inconclusive_scans


@pytest.mark.parametrize("people", [5, 6])
def test_mcl_wedged_among_people_keeps_tracking(people):
    """Five or six people 0.6 m around the robot hide 68 or 82 % of its beams (the warehouse
    with 30 ORCA walkers, seeds 2, 5, 18, 19: 70-75 % of the used returns short, all on
    walkers, the estimate within 5 cm). Until 2026-12-05 short returns past 60 % of the scan
    counted as misfits: the fit fell below 0.7 on such a scan, the filter stopped saying
    ``localized`` and weighed the people (here: every other update with five people, lost by
    3.4 m with six; 12-17 m RMSE in those runs). Now the returns that are not short fit the
    map (five people), or too few are left to judge the fit by (six): it stays localized,
    within a few centimetres."""
    said, worst, unjudged = _track_among(np.deg2rad(np.arange(people) * 60.0))
    assert all(said), said
    assert worst < 0.05
    assert unjudged == (0 if people == 5 else len(said))


def test_mcl_among_people_still_notices_a_kidnapping():
    """Excusing every short return must not hide a kidnapping: with three people beside the
    robot (about 40 % of the beams on them), the robot carried 2 m across the room and turned
    (the odometry not told) is no longer ``localized`` after the next update."""
    from pymunk_bot.localization import MclConfig, MclLocalizer
    from pymunk_bot.localization.base import LocalizerContext, LocalizerInputs
    from pymunk_bot.robots.readings import RobotSpec

    start = np.array([2.0, 1.7, 0.0])
    context = LocalizerContext(robot=RobotSpec("r1", 0.2, 0.3, 1.0, 3.0), start_pose=start,
                               rng=np.random.default_rng(5), arena=(6.0, 4.0), map=_room_grid())
    mcl = MclLocalizer(MclConfig(), context)
    bearings = np.deg2rad([0.0, 120.0, 240.0])
    for k in range(4):
        odometry = start + np.array([0.15 * k, 0.0, 0.0])
        people = odometry[:2] + 0.6 * np.column_stack([np.cos(bearings), np.sin(bearings)])
        mcl.update(LocalizerInputs(0.2 * k, odometry.copy(), _room_scan(odometry, people, 0.2 * k)))
    assert mcl.localized
    carried = np.array([4.3, 2.6, 1.2])
    odometry = odometry + np.array([0.15, 0.0, 0.0])  # the odometry goes on from where it was
    people = carried[:2] + 0.6 * np.column_stack([np.cos(bearings), np.sin(bearings)])
    mcl.update(LocalizerInputs(1.0, odometry, _room_scan(carried, people, 1.0)))
    assert not mcl.localized and mcl.scan_fit < 0.7


@pytest.mark.slow
def test_mcl_tracks_while_wedged_among_thirty_walkers():
    """Issue 36: the warehouse with 30 ORCA walkers, seed 2: a scan with 13 of its 18 used
    returns short, all on walkers, fitted 0.69 with the 60 % cap (until 2026-12-05): the filter
    gave up a pose 5 cm from the truth and ended 1453 cm RMSE off. Now 2.2 cm."""
    got = run_one("mcl", "warehouse_orca30", "typical", 2)
    assert got is not None and not got.error
    assert got.rmse <= PEOPLE_RMSE, got.line()
