"""Copies of a scenario sharing one Space: with a named substep count each plays exactly the
run it would play alone, and no copy meets or sees another."""
from __future__ import annotations

import numpy as np
import pytest

from pymunk_bot.config import load_scenario, parse_scenario
from pymunk_bot.config.substeps import required_substeps
from pymunk_bot.physics.settings import MAX_REPLICAS
from pymunk_bot.engine.replicas import Replicas
from pymunk_bot.engine.simulation import Simulation


def _named(data: dict, name: str):
    """``data`` parsed with its substep count named: a shared space then takes every substep in
    every tick, as each single run does (the default takes them only where some copy's
    contacts can start: docs/learning.md)."""
    data.setdefault("world", {})["substeps"] = required_substeps(parse_scenario(data, name))
    return parse_scenario(data, name)


def _lidar_default(crate: bool = True):
    """The built-in default (walls, pillars and, with ``crate``, a pushable crate) with a
    90-beam LiDAR, the robot starting in front of where the crate is."""
    data = load_scenario(None).model_dump(exclude_unset=True)
    data["robots"][0]["lidar"] = {"beams": 90, "noise_std": 0.01}
    data["robots"][0].pop("controller", None)
    data["robots"][0]["pose"] = [4.0, 4.7, 0.0]  # facing the crate 1 m ahead
    if not crate:
        data["obstacles"] = [o for o in data["obstacles"] if not o.get("movable")]
    return _named(data, "default")


def _drive(sims, commands) -> None:
    for sim, (v, omega) in zip(sims, commands):
        sim.robots["r1"].set_velocity(float(v), float(omega))


def _wander(config, periods: int, check) -> tuple[Replicas, list[Simulation]]:
    """Three copies and three single runs driven alike into walls (and the crate) for
    ``periods`` x 0.1 s, copy 1 reset half way; ``check(copies, singles, period)`` after each."""
    seeds = [11, 22, 33]
    copies = Replicas(config, seeds)
    alone = [Simulation(config, seed=s) for s in seeds]
    rng = np.random.default_rng(0)
    for period in range(periods):
        commands = np.column_stack([rng.uniform(0.1, 0.5, 3), rng.uniform(-1.5, 1.5, 3)])
        _drive(copies.sims, commands)
        _drive(alone, commands)
        for _ in range(6):
            copies.step()
            for sim in alone:
                sim.step()
        if period == periods // 2:
            copies.reset(1, seed=99)
            alone[1].reset(99)
        check(copies.sims, alone, period)
    assert sum(s.robots["r1"].collisions for s in alone) > 10  # they did meet things
    return copies, alone


def test_each_copy_plays_its_single_run_to_the_bit():
    """Where only the robots move, a copy's run is its single run, float for float."""
    def same(copies, alone, period):
        for shared, single in zip(copies, alone):
            a, b = shared.robots["r1"], single.robots["r1"]
            assert np.array_equal(a.pose, b.pose), period
            assert np.array_equal(a.lidar.latest.ranges, b.lidar.latest.ranges), period
            assert np.array_equal(a.odometry.pose, b.odometry.pose), period

    copies, alone = _wander(_lidar_default(crate=False), 600, same)
    assert [s.result()["robots"] for s in copies.sims] == [s.result()["robots"] for s in alone]


def test_copies_pushing_crates_stay_within_a_millimetre_of_their_single_runs():
    """pymunk orders contacts between moving bodies by their place in the space, so a pushed
    crate's last bits can differ from its single run's, and a long push can grow that."""
    gaps = []

    def close(copies, alone, period):
        for shared, single in zip(copies, alone):
            crate = shared.world.obstacles[4].body.position - single.world.obstacles[4].body.position
            gaps.append(max(np.abs(shared.robots["r1"].pose - single.robots["r1"].pose).max(),
                            abs(crate.x), abs(crate.y)))

    copies, _ = _wander(_lidar_default(crate=True), 600, close)
    assert max(gaps) < 1e-3
    assert any(tuple(s.world.obstacles[4].body.position) != (5.0, 4.8) for s in copies.sims)


def test_copies_neither_meet_nor_see_each_other():
    config = parse_scenario({
        "name": "two", "world": {"size": [6.0, 3.0]},
        "obstacles": [{"type": "box", "center": [3.0, 1.5], "size": [0.4, 0.4],
                       "movable": True, "mass": 1.0}],
        "robots": [{"name": "r1", "pose": [1.0, 1.5, 0.0],
                    "lidar": {"beams": 4, "fov": 6.283185307179586, "max_range": 5.0}}]}, "two")
    copies = Replicas(config, [0, 1])
    pusher, bystander = (sim.robots["r1"] for sim in copies.sims)
    pusher.set_velocity(0.8, 0.0)  # copy 0 drives through where copy 1's robot stands
    ahead = int(np.argmin(np.abs(bystander.lidar.angles)))
    seen = []
    for _ in range(240):
        copies.step()
        if 1.6 < pusher.pose[0] < 2.4:  # copy 0's robot right in front of copy 1's
            seen.append(float(bystander.lidar.scan()[ahead]))
    assert seen and seen == pytest.approx([1.8] * len(seen), abs=1e-9)  # its own crate only
    assert bystander.pose[0] == pytest.approx(1.0, abs=1e-9)  # never pushed by copy 0
    crate_0, crate_1 = (sim.world.obstacles[0].body.position for sim in copies.sims)
    assert crate_0.x > 3.5 and crate_1.x == pytest.approx(3.0)  # copy 0 pushed its own crate only
    # Copy 1 still sees its own crate ahead (its near face at 2.8 m), not copy 0's.
    assert bystander.lidar.scan()[ahead] == pytest.approx(1.8, abs=1e-9)
    assert bystander.collisions == 0


def test_what_cannot_share_a_space_is_refused():
    with pytest.raises(ValueError, match=f"1 to {MAX_REPLICAS}"):
        Replicas(_lidar_default(), list(range(MAX_REPLICAS + 1)))
    with pytest.raises(RuntimeError, match="Replicas.step"):
        Replicas(_lidar_default(), [0]).sims[0].step()
    with pytest.raises(RuntimeError, match="Replicas.reset"):  # its stack would miss it
        Replicas(_lidar_default(), [0, 1]).sims[1].reset(5)


def _two_robot_fleet():
    """Two diff robots (one with noisy, quantised odometry) that bump into pillars and walls
    and reach goals at different times."""
    noisy = {"wheel_noise_std": 0.02, "left_scale_error": 0.01, "track_width_error": -0.02,
             "encoder_resolution": 0.001}
    return _named({
        "name": "pair", "world": {"size": [6.0, 4.0]},
        "obstacles": [{"type": "circle", "center": [3.0, 2.0], "radius": 0.3},
                      {"type": "box", "center": [4.5, 1.0], "size": [0.4, 0.4]}],
        "robots": [{"name": "a", "pose": [1.0, 1.0, 0.0], "odometry": noisy,
                    "goal": {"position": [1.5, 1.0], "tolerance": 0.3}},
                   {"name": "b", "pose": [1.0, 3.0, 0.0],
                    "goal": {"position": [1.6, 3.1], "tolerance": 0.4}}]}, "pair")


def test_copies_bookkept_together_keep_every_robot_state_of_their_single_runs():
    """The copies' fleets, drives and odometry are stacked into one each: distances, goal
    times, collisions, odometry and its covariance still equal each copy's single run, across
    a copy's reset and a goal set while running."""
    config = _two_robot_fleet()
    seeds = [5, 6, 7]
    copies = Replicas(config, seeds)
    assert copies._stack is not None  # bookkept together
    alone = [Simulation(config, seed=s) for s in seeds]
    rng = np.random.default_rng(4)
    for period in range(120):
        commands = rng.uniform([0.0, -2.0], [0.6, 2.0], size=(3, 2, 2))
        for group in (copies.sims, alone):
            for sim, pair in zip(group, commands):
                for name, (v, omega) in zip("ab", pair):
                    sim.robots[name].set_velocity(float(v), float(omega))
        for _ in range(6):
            copies.step()
            for sim in alone:
                sim.step()
        if period == 40:
            copies.reset(2, seed=70)
            alone[2].reset(70)
        if period == 60:  # a new goal where robot b is: reached on the next tick
            here = (float(alone[0].robots["b"].pose[0]), float(alone[0].robots["b"].pose[1]))
            for sim in (copies.sims[0], alone[0]):
                sim.robots["b"].set_goal(here, tolerance=0.3)
        for shared, single in zip(copies.sims, alone):
            for name in "ab":
                a, b = shared.robots[name], single.robots[name]
                assert np.array_equal(a.pose, b.pose), (period, name)
                assert np.array_equal(a.odometry.pose, b.odometry.pose), (period, name)
                assert np.array_equal(a.odometry.covariance, b.odometry.covariance)
                assert (a.distance, a.collisions, a.time_to_goal, a.distance_to_goal) == \
                    (b.distance, b.collisions, b.time_to_goal, b.distance_to_goal), (period, name)
    results = [s.result()["robots"] for s in copies.sims]
    assert results == [s.result()["robots"] for s in alone]
    assert sum(r["collisions"] for copy in results for r in copy.values()) >= 3
    assert sum(r["goal_reached"] for copy in results for r in copy.values()) >= 3
    assert copies.sims[0].robots["b"].time_to_goal == pytest.approx(6.1 + 1 / 60)  # next tick


NOISY_ODOMETRY = {
    "parking": {"wheel_noise_std": 0.02, "encoder_resolution": 0.001, "steer_noise_std": 0.01,
                "steer_resolution": 0.002, "steer_offset": 0.01, "wheelbase_error": 0.02},
    "omni_aisle": {"wheel_noise_std": 0.02, "scale_errors": [0.01, -0.01],
                   "encoder_resolution": 0.001, "wheel_distance_error": 0.02},
}


@pytest.mark.parametrize("scenario", sorted(NOISY_ODOMETRY))
def test_car_and_omni_copies_stay_exact_across_other_copies_resets(scenario):
    """Car-like and omni copies (planners driving them, noisy odometry) are stacked too; a
    copy's rebuild takes its joints out of the shared space and the others' keep the order
    the solver applies them in: every copy still plays its single run to the bit."""
    data = load_scenario(scenario).model_dump(exclude_unset=True)
    for robot in data["robots"]:
        robot["odometry"] = NOISY_ODOMETRY[scenario]
        robot["localization"] = {"type": "ground_truth"}  # its planner: no replans on drift
    config = _named(data, scenario)
    seeds = [1, 2, 3]
    copies = Replicas(config, seeds)
    assert copies._stack is not None
    alone = [Simulation(config, seed=s) for s in seeds]
    for tick in range(360):
        copies.step()
        for sim in alone:
            sim.step()
        if tick in (100, 200):
            k = 1 if tick == 100 else 0
            copies.reset(k, seed=tick)
            alone[k].reset(tick)
    for shared, single in zip(copies.sims, alone):
        for name in shared.robots:
            a, b = shared.robots[name], single.robots[name]
            assert np.array_equal(a.pose, b.pose)
            assert np.array_equal(a.odometry.pose, b.odometry.pose)
            assert np.array_equal(a.odometry.covariance, b.odometry.covariance)
            assert a.odometry.covariance.any()  # the noise model ran
    assert [s.result()["robots"] for s in copies.sims] == [s.result()["robots"] for s in alone]


def test_a_teleport_in_a_stacked_copy_counts_no_distance():
    """A kidnapped robot jumps: the jump is no path travelled, in a copy whose bookkeeping is
    stacked with the others' as in a run of its own."""
    config = _lidar_default(crate=False)
    copies = Replicas(config, [1, 2])
    assert copies.stacked
    robots = [sim.robots["r1"] for sim in copies.sims]
    for _ in range(6):
        copies.step()
    before = [r.distance for r in robots]
    robots[1].teleport(1.0, 1.0, 0.0)  # several metres from where it stood
    copies.step()
    assert robots[1].distance - before[1] < 0.01
    assert robots[0].distance - before[0] < 0.01


def test_a_copy_rebuilt_among_others_still_stops_at_the_arena_wall():
    """With adaptive substeps (the vector env's default) a copy's rebuild keeps what the
    shared substep planner knows of the fixed world (its cells are not built again for every
    reset): the rebuilt copy's robot, driven at the arena's wall, stops at it."""
    data = load_scenario(None).model_dump(exclude_unset=True)
    data["obstacles"] = []  # open ground up to the wall at x = 10 m
    data["robots"][0].pop("controller", None)
    data["robots"][0]["pose"] = [7.0, 3.0, 0.0]
    config = parse_scenario(data, "wall")
    copies = Replicas(config, [1, 2, 3])
    gate = copies._batch.gate
    assert gate is not None  # adaptive substeps
    for round_ in range(3):
        copies.reset(round_ % 3, seed=10 + round_)
        assert copies._batch.gate.fixed is gate.fixed  # kept, not built again
        for sim in copies.sims:
            sim.robots["r1"].set_velocity(sim.robots["r1"].spec.max_speed, 0.0)
        for _ in range(300):  # 5 s: at most 3 m from x = 7 m, into the wall
            copies.step()
        radius = copies.sims[round_ % 3].robots["r1"].spec.radius
        for sim in copies.sims:
            x = sim.robots["r1"].pose[0]
            assert 10.0 - radius - 0.05 < x < 10.0 - radius + 0.01  # at the wall, not through it


def _fields(sim: Simulation) -> list[np.ndarray]:
    """Every per-robot field of a copy's groups (their ``ROWS``, and their encoders')."""
    built = sim.built
    groups = [built.fleet] + [g for g, _ in built.drive_groups + built.odometry_groups]
    groups += [g.encoders for g, _ in built.odometry_groups]
    return [getattr(g, name) for g in groups for name in type(g).ROWS]


def test_every_copy_holds_its_rows_in_the_shared_arrays_from_birth_and_a_reset_rebinds_none():
    """Copies are built on rows they share (robots/rows.py): each copy's per-robot fields are
    its block of one array per field from the start; a copy rebuilt writes its fresh state into
    the same block, and no other copy's arrays, nor the stack's, move."""
    config = _two_robot_fleet()
    copies = Replicas(config, [5, 6, 7])
    stack = copies._stack
    assert stack is not None
    before = [[f.ctypes.data for f in _fields(sim)] for sim in copies.sims]
    whole = stack.fleet.distance
    for sim in copies.sims:
        for field in _fields(sim):
            assert field.base is not None and not field.flags.owndata  # a view, from birth
    for sim in copies.sims:
        sim.robots["a"].set_velocity(0.5, 0.2)
    for _ in range(60):
        copies.step()
    assert copies.sims[1].robots["a"].distance > 0.3
    copies.reset(1, seed=9)
    assert copies.sims[1].robots["a"].distance == 0.0  # fresh rows, written in place
    assert [[f.ctypes.data for f in _fields(sim)] for sim in copies.sims] == before
    assert copies._stack is not None and copies._stack.fleet.distance is whole
    assert whole[2:4].tolist() == [0.0, 0.0]  # copy 1's rows of the whole, fresh too
