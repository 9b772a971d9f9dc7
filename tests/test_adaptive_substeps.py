"""world.substeps: adaptive: one pymunk step where no contact can start, every substep where one
can; contacts hold as with the fixed count, and free-space arcs stay exact."""
from __future__ import annotations

import numpy as np
import pytest
from builders import robot, scenario, wheels

from pymunk_bot.config import parse_scenario
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.engine.replicas import Replicas
from pymunk_bot.engine.simulation import Simulation


def _sim(robots, obstacles=None, **extra) -> Simulation:
    return Simulation(parse_scenario(scenario(robots, obstacles, **extra), "test"))


def _fit_circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    a = np.c_[2 * points, np.ones(len(points))]
    c = np.linalg.lstsq(a, (points ** 2).sum(axis=1), rcond=None)[0]
    return c[:2], float(np.sqrt(c[2] + c[:2] @ c[:2]))


def test_open_space_takes_one_step_per_tick_and_keeps_the_arc_exact():
    sim = _sim([robot([10, 10, 0], controller=wheels(0.45, 0.55), track_width=0.3)],
               substeps="adaptive")
    sim.run(1.0)  # the motors settle
    points = []
    for _ in range(120):
        sim.step()
        points.append(sim.robots["r"].pose[:2])
    assert sim.single_substep_ticks >= 0.9 * sim.steps  # nothing near: one step nearly always
    centre, radius = _fit_circle(np.array(points))
    expected = 0.3 / 2 * (0.55 + 0.45) / (0.55 - 0.45)  # track / 2 * (r + l) / (r - l)
    assert radius == pytest.approx(expected, abs=1e-6)
    assert np.hypot(*(np.array(points) - centre).T).std() < 1e-9  # on the circle


def test_a_named_count_takes_every_substep_and_the_default_only_where_contacts_can_start():
    """In open space the default takes one pymunk step per tick; a named count every substep."""
    named = _sim([robot([10, 10, 0], controller=wheels(0.5, 0.5))], substeps=3)
    named.run(1.0)
    assert named.single_substep_ticks == 0
    default = _sim([robot([10, 10, 0], controller=wheels(0.5, 0.5))])
    default.run(1.0)
    assert default.single_substep_ticks >= 0.9 * default.steps


@pytest.mark.parametrize("thickness", [0.01, 0.02])
def test_a_fast_robot_stops_at_a_thin_wall(thickness):
    """Into a thin wall at 2 m/s: every substep where the contact starts, so no crossing and
    no contact deeper than 1 cm; one contact episode."""
    sim = _sim([robot([2, 2, 0], max_wheel_speed=2.0, max_accel=10.0,
                      controller={"type": "velocity", "v": 2.0})],
               [{"type": "wall", "start": [5, 0], "end": [5, 4], "thickness": thickness}],
               size=(8, 4), substeps="adaptive")
    deepest = 0.0
    for _ in range(240):
        sim.step()
        for arbiter_depth in _depths(sim):
            deepest = max(deepest, arbiter_depth)
    r = sim.robots["r"]
    assert r.pose[0] < 5 - thickness / 2 - 0.2 + 0.01  # stopped at the wall's near face
    assert r.collisions == 1
    assert deepest <= 0.01
    assert 0 < sim.single_substep_ticks < sim.steps  # free on the way, substepped at the wall


def _depths(sim: Simulation) -> list[float]:
    body = sim.robots["r"].body
    depths: list[float] = []
    body.each_arbiter(lambda arbiter: depths.extend(
        -point.distance for point in arbiter.contact_point_set.points))
    return depths


def test_a_teleport_makes_the_next_tick_take_every_substep():
    sim = _sim([robot([10, 10, 0], controller=wheels(0.5, 0.5))],
               [{"type": "box", "center": [3, 3], "size": [1, 1]}], substeps="adaptive")
    sim.run(1.0)
    before = sim.single_substep_ticks
    sim.robots["r"].teleport(3.0, 3.75, 0.0)  # beside the box
    sim.step()
    assert sim.single_substep_ticks == before  # no single step right after the jump


def test_adaptive_runs_are_deterministic_alone_and_as_copies():
    data = scenario([robot([3, 3, 0.3], controller=wheels(0.6, 0.8))],
                    [{"type": "box", "center": [6, 4], "size": [1, 1]}], size=(10, 8),
                    substeps="adaptive")
    config = parse_scenario(data, "test")
    a, b = Simulation(config, seed=3), Simulation(config, seed=3)
    a.run(8.0)
    b.run(8.0)
    assert a.result()["robots"] == b.result()["robots"]
    twice = [Replicas(config, [1, 2]) for _ in range(2)]
    for replicas in twice:
        for _ in range(480):
            replicas.step()
    assert [s.result()["robots"] for s in twice[0].sims] == \
        [s.result()["robots"] for s in twice[1].sims]


def test_substeps_accepts_adaptive_and_refuses_other_words():
    parse_scenario(scenario([robot([1, 1, 0])], substeps="adaptive"), "test")
    with pytest.raises(ScenarioError, match="world.substeps"):
        parse_scenario(scenario([robot([1, 1, 0])], substeps="auto"), "test")


def test_a_failed_test_grants_no_single_steps_to_the_movers_it_did_not_look_at():
    """The contact bench's head-on trial 443 (two robots at 2.6 m/s, dt 1/120 s), by default:
    after passing each other they race to opposite walls. A test that fails stops at the
    first mover that can touch something soon; the other one, nearer its wall, was not looked
    at, and must not take single steps into it (it did: 12.9 mm deep)."""
    from bench import contacts
    rng = np.random.default_rng(0)  # the bench's trials draw in turn from one generator
    for i in range(443):
        contacts.trial_scenario(contacts.KINDS[i % len(contacts.KINDS)], rng)
    crossed, deepest = contacts.run_trial("head-on", rng)  # the default: adaptive
    assert not crossed and deepest <= 0.01


@pytest.mark.parametrize("spacing, single", [(3.0, True), (0.5, False)])
def test_a_large_fleet_takes_single_steps_only_when_its_robots_are_apart(spacing, single):
    """60 robots (the gate finds their pairs with a k-d tree) driving side by side at 0.3 m/s:
    far apart in open space most ticks take one step; 0.5 m apart (a 0.1 m gap) every tick
    takes the substeps that speed needs (fewer than the scenario's count, which is for robots
    at their 1 m/s top speed)."""
    robots = [robot([10 + spacing * (k % 10), 10 + spacing * (k // 10), 0], name=f"r{k}",
                    controller=wheels(0.3, 0.3)) for k in range(60)]
    sim = _sim(robots, size=(60.0, 60.0))
    sim.run(0.5)  # the motors reach their 0.3 m/s
    ones, steps, ticks = sim.single_substep_ticks, sim.pymunk_steps, sim.steps
    sim.run(0.5)
    ticks = sim.steps - ticks
    # 0.3 m/s, plus what the motors could add within two ticks, closing head-on: 2 substeps
    needed = sim.world.need.count(0.3 + 3.0 * 2 * sim.dt)
    assert (needed, sim.substeps) == (2, 5)
    if single:
        assert sim.single_substep_ticks - ones >= 0.8 * ticks
    else:
        assert sim.single_substep_ticks == ones
        assert sim.pymunk_steps - steps == needed * ticks
    assert all(r.collisions == 0 for r in sim.robots.values())


def test_the_substeps_a_speed_needs_come_from_the_scenarios_own_formula():
    """The gate's table of speeds gives, for every speed up to the top, the count the
    scenario's formula gives (robots, a crate and a walker), and the top speed's is the
    scenario's count."""
    from pymunk_bot.config.substeps import required_substeps, substep_need
    from pymunk_bot.physics.substeps import SubstepGate
    config = parse_scenario(scenario(
        [robot([2, 2, 0]), robot([5, 2, 0], name="s")],
        [{"type": "box", "center": [8, 8], "size": [0.3, 0.3], "movable": True, "mass": 2.0}]),
        "test")
    need = substep_need(config)
    assert need.full == required_substeps(config) == 6  # the crate: 6 mm steps
    gate = SubstepGate(Simulation(config).world.space, [], need.full, config.world.dt,
                       lambda: False, need, lambda seconds: 0.0)
    for speed in np.linspace(0.0, need.top_speed, 401):
        gate._driven = lambda seconds, v=float(speed): v
        assert gate._graded() == need.count(float(speed))
