"""CrowdNav's protocol (docs/benchmark.md, "CrowdNav's protocol"): its test cases exactly, the
crowdnav_orca controller on the pedestrians' true states, episodes that end at the first
collision, and the reproduction of CrowdNav's ORCA row kept on 40 of its 500 test cases."""
import math

import numpy as np
import pytest

import pymunk_bot as pb
from pymunk_bot.benchmark.controllers import controller_choices
from pymunk_bot.benchmark.crowdnav import circle_crossing, square_crossing
from pymunk_bot.benchmark.runner import run_benchmark
from pymunk_bot.benchmark.suite import load_suite

# The 500-episode run of docs/benchmark.md:
#   pymunk-bot benchmark crowdnav --controller crowdnav_orca --seeds 0:500 --out episodes.csv
MEASURED_500 = {"success": 0.428, "collision": 0.568, "timeout": 0.004}
MEASURED_TIME_TO_GOAL = 10.78  # [s], mean over the successes
EPISODES = 40


def test_the_layout_is_crowdnavs_test_case():
    start, goal, routes = circle_crossing(0, 5, 4.0, 0.3, 0.3, 1.0)
    assert start.tolist() == [0.0, -4.0] and goal.tolist() == [0.0, 4.0]
    # CrowdNav seeds its test case 0 with 1000 and draws angle, x noise, y noise in turn; the
    # first human's first draw is clear of the robot, so it is that human's start.
    u = np.random.RandomState(1000).random_sample(3)
    angle = 2 * math.pi * u[0]
    first = [4 * math.cos(angle) + u[1] - 0.5, 4 * math.sin(angle) + u[2] - 0.5]
    assert routes[0][0].tolist() == pytest.approx(first, abs=1e-12)
    placed = [(start, goal)]
    for s, g in routes:
        assert g.tolist() == pytest.approx((-s).tolist())  # the far side, through the centre
        assert abs(math.hypot(*s) - 4.0) <= math.sqrt(0.5) + 1e-9  # noise: half a metre each way
        for s0, g0 in placed:  # 0.3 + 0.3 + 0.2 m from every earlier start and goal
            assert math.hypot(*(s - s0)) >= 0.8 and math.hypot(*(s - g0)) >= 0.8
        placed.append((s, g))


@pytest.mark.slow  # about 5 s of CPU: 40 CrowdNav test cases
def test_crowdnav_orca_reproduces_its_row_on_40_test_cases():
    """Each rate within the binomial 99 % interval of 40 draws at the 500-episode rate."""
    from scipy.stats import binom  # here: scipy.stats costs every test worker 0.4 s to import

    rows = run_benchmark(load_suite("crowdnav"), controller_choices(["crowdnav_orca"]),
                         range(EPISODES))
    assert all(r["status"] == "ok" for r in rows)
    for name, rate in MEASURED_500.items():
        low, high = binom.interval(0.99, EPISODES, rate)
        assert low <= sum(r[name] for r in rows) <= high, name
    for r in rows:  # CrowdNav's three ends: exactly one per episode
        assert r["success"] + r["collision"] + r["timeout"] == 1.0
        if r["collision"]:  # the episode ended there, before the goal and the time limit
            assert r["reached"] == 0.0 and r["sim_time"] < 25.0
            assert r["discomfort"] > 0.0  # it came within 0.2 m before touching
            assert r["min_distance_to_human"] < 1e-3
        assert 0.0 <= r["discomfort"] <= 1.0
    times = [r["time_to_goal"] for r in rows if r["success"]]
    assert np.mean(times) == pytest.approx(MEASURED_TIME_TO_GOAL, rel=0.1)


def test_humans_that_see_the_robot_let_crowdnav_orca_through():
    rows = run_benchmark(load_suite("crowdnav_visible"), controller_choices(["crowdnav_orca"]),
                         range(10))
    assert [r["success"] for r in rows] == [1.0] * 10  # CrowdNav's visible case: 500 of 500


def crowd_scene(sensor=None):
    data = {"name": "crowd_state", "world": {"size": [10.0, 6.0], "duration": 4.0},
            "obstacles": [{"type": "pedestrian", "center": [x, 3.0], "goals": [[x, 5.0]],
                           "radius": r, "mode": "once"}
                          for x, r in ((3.0, 0.2), (6.0, 0.3), (9.0, 0.25))],
            "robots": [{"name": "r1", "drive": "omni", "pose": [1.0, 1.0, 0.0],
                        "max_speed": 1.0, "controller": {"type": "crowdnav_orca"},
                        "goal": {"position": [8.0, 1.0]}}]}
    if sensor is not None:
        data["robots"][0]["crowd_state"] = sensor
    return data


def test_crowd_state_gives_the_nearest_humans_true_states():
    sim = pb.Simulation.from_dict(crowd_scene({"max_humans": 2}))
    sim.run(1.0)
    reading = sim.robots["r1"].readings()["crowd_state"]
    walkers = [o for o in sim.world.obstacles if o.config.type == "pedestrian"]
    robot = np.array(sim.robots["r1"].pose[:2])
    by_distance = sorted(walkers, key=lambda w: math.dist(robot, tuple(w.body.position)))[:2]
    assert reading.positions.tolist() == [list(w.body.position) for w in by_distance]
    assert reading.velocities.tolist() == [list(w.body.velocity) for w in by_distance]
    assert reading.radii.tolist() == [w.config.radius for w in by_distance]
    assert reading.time == pytest.approx(sim.time)


def test_crowdnav_orca_without_the_sensor_is_bad_input():
    with pytest.raises(pb.ScenarioError) as raised:
        pb.Simulation.from_dict(crowd_scene())
    assert raised.value.path == "robots[0].controller"
    assert "crowd_state" in raised.value.problem


def test_benchmarking_crowdnav_orca_on_a_suite_without_true_states_is_refused():
    """Not 72 silent timeouts: one line before anything runs."""
    with pytest.raises(pb.ScenarioError) as raised:
        run_benchmark(load_suite("crowds"), controller_choices(["crowdnav_orca"]), range(1))
    assert "crowd_state" in raised.value.problem


def test_a_walker_holds_its_velocity_between_decisions():
    data = crowd_scene({})
    for o in data["obstacles"]:
        o.update(policy="orca", decision_period=0.25, speed=1.0, max_speed=1.0)
    sim = pb.Simulation.from_dict(data)
    walker = next(o for o in sim.world.obstacles if o.config.type == "pedestrian")
    seen = []
    for _ in range(60):  # 1 s at 60 Hz
        sim.step()
        seen.append(tuple(walker.body.velocity))
    # a new velocity only at 0, 0.25, 0.5 and 0.75 s: one value per quarter second
    blocks = [set(seen[i:i + 15]) for i in range(0, 60, 15)]
    assert all(len(b) == 1 for b in blocks)
    assert len({next(iter(b)) for b in blocks}) > 1  # it does decide again


@pytest.mark.parametrize("world, key", [({"size": [9.0, 9.0]}, "worlds.small.size"),
                                        ({"generate": "clutter"}, "worlds.small")])
def test_crowdnavs_layout_needs_an_open_room_around_its_circle(tmp_path, world, key):
    spec = tmp_path / "cn.yaml"
    spec.write_text("suite: cn\nrobot: {name: r1}\nlayouts: [crowdnav_circle_crossing]\n"
                    "densities: {five: 5}\nworlds:\n  small: " + str(world).replace("'", "")
                    + "\n")
    with pytest.raises(pb.ScenarioError) as raised:
        load_suite(str(spec))
    assert raised.value.path == key and "crowdnav_circle_crossing" in raised.value.problem


# Test case 0 of CrowdNav's square crossing as its own code draws it: crowd_sim.py's
# generate_random_human_position(5, "square_crossing") after np.random.seed(1000), run here on
# the fetched vita-epfl/CrowdNav (its 500 test cases agreed to the bit) -- (px, py, gx, gy).
CROWDNAV_SQUARE_CASE_0 = [
    (-0.5750347156220287, 4.502828643490245, 2.410957007139991, 3.7247453518203533),
    (0.20354812384544563, -1.028055386542942, -1.1656609867418999, 3.417407242530616),
    (3.7123476679120433, -1.078458721911587, -0.9112825997619217, 2.4353941459214),
    (4.426686021903754, 4.526443992215418, -4.655717173387554, -0.8456904695509215),
    (4.910137422990989, -1.6036231636471143, -3.533435969444019, -1.3812293239243822)]


def test_the_square_layout_is_crowdnavs_test_case():
    start, goal, routes = square_crossing(0, 5, 4.0, 10.0, 0.3, 0.3)
    assert start.tolist() == [0.0, -4.0] and goal.tolist() == [0.0, 4.0]
    assert [(*s, *g) for s, g in routes] == CROWDNAV_SQUARE_CASE_0
    for case in range(50):  # every human crosses to the other half, clear of those before
        start, goal, routes = square_crossing(case, 5, 4.0, 10.0, 0.3, 0.3)
        agents = [(start, goal, 0.3)]
        for s, g in routes:
            assert s[0] * g[0] < 0 and max(abs(s).max(), abs(g).max()) <= 5.0
            for s0, g0, r in agents:
                assert math.hypot(*(s - s0)) >= 0.5 + r and math.hypot(*(g - g0)) >= 0.5 + r
            agents.append((s, g, 0.3))


def test_the_square_suite_runs_crowdnavs_square_episodes():
    entries = load_suite("crowdnav_square")
    rows = run_benchmark(entries, controller_choices(["crowdnav_orca"]), range(4))
    assert [r["status"] for r in rows] == ["ok"] * 4
    assert sum(r["success"] for r in rows) >= 2  # 0.85 over its first 40 cases


def test_the_square_needs_its_side_and_2_m_beyond(tmp_path):
    spec = tmp_path / "cn.yaml"
    spec.write_text("suite: cn\nrobot: {name: r1}\nlayouts: [crowdnav_square_crossing]\n"
                    "densities: {five: 5}\nsquare_width: 12\nworlds:\n  small: {size: [15, 15]}\n")
    with pytest.raises(pb.ScenarioError) as raised:
        load_suite(str(spec))
    assert raised.value.path == "worlds.small.size" and "16 m" in raised.value.problem
