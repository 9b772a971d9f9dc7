"""ORCA's half-planes and LP on hand-computed cases, and the pedestrian options."""
import math

import numpy as np
import pytest

import pymunk_bot as pb
from pymunk_bot.actors.orca import neighbour_lines, nudged_within
from pymunk_bot.actors.orca_lp import solve_all


def test_head_on_half_plane_by_hand():
    # A at 0 going +x at 1 m/s, B 2 m ahead coming at 1 m/s, r = 0.5 + 0.5, tau = 2 s:
    # w = v - p / tau = (1, 0) is beyond the cutoff, on the right leg (sqrt3/2, -1/2).
    q, n = neighbour_lines(np.zeros((1, 2)), np.array([[1.0, 0.0]]), np.array([0.5]),
                           np.array([[[2.0, 0.0]]]), np.array([[[-1.0, 0.0]]]),
                           np.array([[0.5]]), np.array([[0.5]]), np.array([2.0]), 0.1)
    s3 = math.sqrt(3.0)
    assert n[0, 0] == pytest.approx([-0.5, -s3 / 2])
    assert q[0, 0] == pytest.approx([1.0 - 0.25, -s3 / 4])  # v_A + u / 2, u = (-1/2, -sqrt3/2)
    # the LP moves the wished (1, 0) onto that line: (1, 0) - ((1, 0) - q) . n n
    v = solve_all(q, n, np.array([1]), np.array([0]), np.array([2.0]), np.array([[1.0, 0.0]]))
    assert v[0] == pytest.approx([0.75, -s3 / 4])


def test_lp_keeps_the_speed_limit_and_least_violation_when_infeasible():
    n = np.array([[[1.0, 0.0], [-1.0, 0.0]]])
    q = np.array([[[0.5, 0.0], [-0.5, 0.0]]])  # x >= 0.5 and x <= -0.5: no room
    v = solve_all(q, n, np.array([2]), np.array([0]), np.array([1.0]), np.array([[0.0, 3.0]]))
    assert v[0, 0] == pytest.approx(0.0, abs=1e-9)  # halfway: each violated by 0.5
    free = solve_all(q[:, :1], n[:, :1], np.array([1]), np.array([0]), np.array([1.0]),
                     np.array([[0.0, 3.0]]))
    assert np.hypot(*free[0]) == pytest.approx(1.0)  # the wish, cut to the speed limit
    assert free[0, 0] >= 0.5 - 1e-9


def test_a_nudge_out_of_a_corner_slides_the_answer_along_its_border():
    # A corner: v . (1/2, +-sqrt3/2) >= 0, the wedge within 30 deg of +x. The walker wishes -x,
    # so its answer is the apex 0, and it stays there for any wish within 60 deg of -x.
    s3 = math.sqrt(3.0)
    n = np.array([[[0.5, s3 / 2], [0.5, -s3 / 2]]])
    q = np.zeros((1, 2, 2))
    ok, hard, vmax = np.ones((1, 2), dtype=bool), np.array([0]), np.array([1.5])
    chosen = solve_all(q, n, np.array([2]), hard, vmax, np.array([[-1.3, 0.1]]))
    assert chosen[0] == pytest.approx([0.0, 0.0], abs=1e-12)
    # a nudge straight up points out of the wedge: the walker slides up its lower border
    moved = nudged_within(q, n, ok, hard, vmax, chosen, np.array([[0.0, 0.01]]))
    assert moved[0] == pytest.approx([0.01 * s3 / 4, 0.01 / 4])  # (0, 0.01) onto (s3/2, 1/2)
    assert (moved[0] @ n[0].T >= -1e-12).all()  # still inside both half-planes
    unmoved = nudged_within(q, n, ok, hard, vmax, chosen, np.zeros((1, 2)))
    assert unmoved[0].tobytes() == chosen[0].tobytes()  # no nudge: bit for bit (CrowdNav's)
    # no room (x >= 0.5 and x <= -0.5): the least-violating answer is kept as it is
    n_tight = np.array([[[1.0, 0.0], [-1.0, 0.0]]])
    q_tight = np.array([[[0.5, 0.0], [-0.5, 0.0]]])
    least = solve_all(q_tight, n_tight, np.array([2]), hard, vmax, np.array([[0.0, 1.0]]))
    kept = nudged_within(q_tight, n_tight, ok, hard, vmax, least, np.array([[0.01, 0.0]]))
    assert kept[0].tobytes() == least[0].tobytes()


def walkers(policy, extra=None, n=2):
    people = [{"type": "pedestrian", "center": [1.0, 5.0], "goals": [[9.0, 5.0]], "mode": "once",
               "policy": policy},
              {"type": "pedestrian", "center": [9.0, 5.0], "goals": [[1.0, 5.0]], "mode": "once",
               "policy": policy}][:n]
    for p in people:
        p.update(extra or {})
    return {"name": "walkers", "world": {"size": [10.0, 10.0], "duration": 15.0},
            "obstacles": people, "robots": [{"name": "r1", "pose": [0.5, 0.5, 0.0]}]}


@pytest.mark.parametrize("policy", ["orca", "social_force"])
def test_two_walkers_meeting_head_on_pass_each_other(policy):
    sim = pb.Simulation.from_dict(walkers(policy))
    bodies = [o.body for o in sim.world.obstacles]
    closest = math.inf
    for _ in range(int(14.0 / sim.dt)):
        sim.step()
        closest = min(closest, math.dist(bodies[0].position, bodies[1].position))
    assert bodies[0].position.x > 8.5 and bodies[1].position.x < 1.5  # both arrived
    assert closest >= 0.5 - 0.01  # two 0.25 m bodies never overlapped


@pytest.mark.parametrize("policy", ["orca", "social_force"])
def test_react_to_robot(policy):
    """A robot parked on a walker's line: one that reacts walks around it, one that does
    not walks into it."""
    def run(react):
        data = walkers(policy, {"react_to_robot": react}, n=1)
        data["robots"] = [{"name": "r1", "pose": [5.0, 5.0, 0.0], "radius": 0.3}]
        sim = pb.Simulation.from_dict(data)
        sim.run(5.0)
        return sim.robots["r1"].collisions
    assert run(True) == 0
    assert run(False) >= 1


def test_a_group_keeps_together_at_its_slowest_pace():
    data = walkers("social_force", n=2)
    data["obstacles"] = [
        {"type": "pedestrian", "center": [1.0, 4.6], "goals": [[9.0, 4.6]], "mode": "once",
         "speed": 1.0, "group": "pair"},
        {"type": "pedestrian", "center": [1.0, 5.4], "goals": [[9.0, 5.4]], "mode": "once",
         "speed": 1.6, "group": "pair"}]
    sim = pb.Simulation.from_dict(data)
    a, b = (o.body for o in sim.world.obstacles)
    for _ in range(int(5.0 / sim.dt)):
        sim.step()
        assert abs(a.position.x - b.position.x) < 0.3  # side by side
    # at the slower pace (1 m/s after a ~0.5 s ramp), not the faster one's 1.6 m/s
    assert 4.5 < b.position.x < 1.0 + 5.0 * 1.0 + 0.1


def test_body_states_match_the_properties_after_the_space_changes():
    import pymunk

    from pymunk_bot.actors.body_state import BodyStates

    space = pymunk.Space()
    bodies = []
    for i in range(12):
        body = pymunk.Body(1.0, 1.0)
        body.position, body.velocity = (i, 2.0 * i), (0.5 * i, -i)
        space.add(body, pymunk.Circle(body, 0.2))
        bodies.append(body)
    bodies[4].center_of_gravity = (0.3, -0.1)  # a centre of gravity off the origin
    bodies[4].angle = 0.7
    states = BodyStates(bodies[::2])
    expected = [[*b.local_to_world(b.center_of_gravity), *b.velocity] for b in bodies[::2]]
    assert np.allclose(states.read(), expected, rtol=0, atol=1e-12)
    space.remove(bodies[1], *bodies[1].shapes)  # the Space's body order changes
    extra = pymunk.Body(1.0, 1.0)
    space.add(extra)
    assert np.allclose(states.read(), expected, rtol=0, atol=1e-12)
    states.set_velocities(np.array([[1.0, 2.0], [3.0, 4.0]]))  # the first two
    assert bodies[0].velocity == (1.0, 2.0) and bodies[2].velocity == (3.0, 4.0)
    assert bodies[4].velocity == (2.0, -4.0)  # the others keep theirs
