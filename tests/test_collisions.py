"""Collision regression tests: what a robot does when it meets walls, crates and other robots."""
from __future__ import annotations

import numpy as np
import pytest
from builders import robot, wheels

RADIUS = 0.2


def thin_wall(x: float, thickness: float = 0.02) -> dict:
    return {"type": "wall", "start": [x, 1.0], "end": [x, 19.0], "thickness": thickness}


def test_head_on_stop_at_the_wall(make_sim):
    sim = make_sim([robot([1, 10, 0], controller=wheels(1.0, 1.0))], [thin_wall(5.0)])
    r = sim.robots["r"]
    face = 5.0 - 0.01
    deepest, xs = 0.0, []
    for _ in range(600):
        sim.step()
        xs.append(r.pose[0])
        deepest = max(deepest, r.pose[0] + RADIUS - face)
    assert deepest <= 0.01  # penetration [m]
    assert r.collisions == 1  # one contact episode, no chatter
    assert r.pose[0] == pytest.approx(face - RADIUS, abs=0.01)
    assert abs(r.velocity[0]) < 1e-6  # stopped, not bouncing
    assert max(xs[-100:]) - min(xs[-100:]) < 1e-6


def test_blocked_robot_does_not_shoot_off_when_released(make_sim):
    """No wind-up: after pushing a wall for seconds, turning away gives the commanded speed."""
    sim = make_sim([robot([1, 10, 0], controller=wheels(1.0, 1.0))], [thin_wall(5.0)])
    r = sim.robots["r"]
    sim.run(8.0)
    r.set_wheel_speeds(-0.5, -0.5)
    peak = 0.0
    for _ in range(120):
        sim.step()
        peak = max(peak, float(np.hypot(*r.body.velocity)))
    assert peak <= 1.0 + 1e-6
    assert r.velocity[0] == pytest.approx(-0.5, abs=1e-6)


@pytest.mark.parametrize("heading", [0.5, 0.9, 1.3])
def test_shallow_angle_slides_along_the_wall(make_sim, heading):
    sim = make_sim([robot([4.0, 3.0, heading], controller=wheels(1.0, 1.0))], [thin_wall(5.0, 0.05)])
    r = sim.robots["r"]
    sim.run(8.0)
    x, y, _ = r.pose
    assert x == pytest.approx(5.0 - 0.025 - RADIUS, abs=0.01)  # against the wall
    assert y > 4.5  # and well along it
    assert r.body.velocity.y > 0.05  # still sliding
    assert r.collisions == 1


def test_steep_angle_sticks_by_coulomb_friction(make_sim):
    """Friction 0.5 x 0.5: a push 0.1 rad off the normal cannot overcome it, as on a real floor."""
    sim = make_sim([robot([4.0, 10.0, 0.1], controller=wheels(1.0, 1.0))], [thin_wall(5.0)])
    sim.run(6.0)
    assert abs(sim.robots["r"].body.velocity.y) < 1e-3


def crate(x: float, y: float, mass: float = 2.0, **keys) -> dict:
    return {"type": "box", "center": [x, y], "size": [0.5, 0.5], "movable": True, "mass": mass,
            **keys}


def test_robot_pushes_a_crate_which_stops_when_released(make_sim):
    sim = make_sim([robot([1, 10, 0], controller=wheels(0.5, 0.5))], [crate(3.0, 10.0)])
    r, box = sim.robots["r"], sim.world.obstacles[0].body
    sim.run(8.0)
    assert box.position.x > 5.0  # pushed about 2.4 m
    assert box.position.x - r.pose[0] == pytest.approx(0.25 + RADIUS, abs=0.02)  # in contact
    assert r.collisions == 1
    r.set_wheel_speeds(0.0, 0.0)
    sim.run(3.0)
    assert box.velocity.length < 1e-6  # ground friction stopped it
    assert box.position.x - r.pose[0] < 0.6  # it slid only a little


def test_too_heavy_crate_stops_the_robot(make_sim):
    """Drive force is capped: a crate whose floor friction exceeds it does not move."""
    sim = make_sim([robot([1, 10, 0], controller=wheels(0.5, 0.5))],
                   [crate(3.0, 10.0, mass=200.0, ground_friction=1.0)])
    box = sim.world.obstacles[0].body
    sim.run(6.0)
    assert box.position.x == pytest.approx(3.0, abs=0.01)


@pytest.mark.parametrize("phase", np.linspace(0.0, 1.0, 12, endpoint=False))
def test_no_tunnelling_through_a_2cm_wall_at_max_speed(make_sim, phase):
    """A fast robot (10 m/s) never passes a 2 cm wall, whatever its start phase against the step."""
    speed = 10.0
    start = 1.0 + phase * speed / 60.0
    sim = make_sim([robot([start, 10, 0], max_wheel_speed=speed, max_accel=50.0,
                          controller=wheels(speed, speed))], [thin_wall(5.0)])
    assert sim.substeps > 1  # computed, not the default
    sim.run(2.0)
    assert sim.robots["r"].pose[0] < 5.0


def test_robot_robot_contact_counts_for_both(make_sim):
    sim = make_sim([robot([8, 10, 0], name="a", controller=wheels(0.5, 0.5)),
                    robot([12, 10, np.pi], name="b", controller=wheels(0.5, 0.5))])
    sim.run(6.0)
    a, b = sim.robots["a"], sim.robots["b"]
    assert a.collisions == 1 and b.collisions == 1
    assert b.pose[0] - a.pose[0] == pytest.approx(2 * RADIUS, abs=0.01)
    assert a.bumper.touching and b.bumper.touching  # still pressed together


def test_concave_polygon_is_solid_in_its_notch_outline(make_sim):
    """A concave obstacle is split into convex pieces, not its hull: the notch stays free."""
    u_shape = {"type": "polygon", "points": [[8, 8], [12, 8], [12, 12], [11, 12], [11, 9],
                                             [9, 9], [9, 12], [8, 12]]}
    sim = make_sim([robot([10, 11.5, -np.pi / 2], controller=wheels(0.5, 0.5))], [u_shape])
    sim.run(5.0)
    r = sim.robots["r"]
    assert r.pose[1] == pytest.approx(9.0 + RADIUS, abs=0.01)  # stopped on the notch floor
    assert r.collisions == 1
