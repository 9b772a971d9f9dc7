"""Bumper: touching now, where (robot frame), and contact episodes."""
from __future__ import annotations

import math

import numpy as np
import pytest
from builders import robot, wheels


def test_bumping_a_wall_ahead(make_sim):
    # Heading up (+y): the top wall is straight ahead, whatever the world-frame direction.
    sim = make_sim([robot([5, 8, math.pi / 2], controller=wheels(0.5, 0.5))], size=(10, 10))
    r = sim.robots["r"]
    assert r.bumper.reading.touching is False and r.bumper.episodes == 0
    sim.run(5.0)
    assert r.bumper.touching
    (normal,) = r.bumper.normals
    assert normal == pytest.approx((1.0, 0.0), abs=1e-6)  # straight ahead in the robot frame
    assert r.bumper.episodes == 1
    r.set_wheel_speeds(-0.5, -0.5)
    sim.run(1.0)
    assert not r.bumper.touching and r.bumper.normals == ()
    assert r.bumper.episodes == 1  # episodes are counted, not erased
    r.set_wheel_speeds(0.5, 0.5)
    sim.run(2.0)
    assert r.bumper.touching and r.bumper.episodes == 2 == r.collisions


def test_hit_from_the_side_by_another_robot(make_sim):
    hitter = robot([5, 3, math.pi / 2], name="a", controller=wheels(0.6, 0.6))
    target = robot([5, 6, 0.0], name="b")  # a comes from b's right-hand side
    sim = make_sim([hitter, target], size=(10, 10))
    a, b = sim.robots["a"], sim.robots["b"]
    for _ in range(600):
        sim.step()
        if b.bumper.touching:
            break
    assert a.bumper.touching and b.bumper.touching
    angle_b = math.atan2(*b.bumper.normals[0][::-1])
    # At first contact b has barely turned: a is to its right.
    assert angle_b == pytest.approx(-math.pi / 2, abs=0.05)
    assert a.bumper.normals[0] == pytest.approx((1.0, 0.0), abs=0.05)
    assert a.bumper.episodes == b.bumper.episodes == 1


def test_two_normals_in_a_corner(make_sim):
    sim = make_sim([robot([9, 9, math.pi / 4], controller=wheels(0.5, 0.5))], size=(10, 10))
    r = sim.robots["r"]
    sim.run(4.0)
    normals = sorted(r.bumper.normals, key=lambda n: n[1])
    assert len(normals) == 2  # the right wall and the top wall
    s = math.sqrt(0.5)
    assert np.allclose(normals, [(s, -s), (s, s)], atol=0.02)
    assert sim.observe(r).bumper and sim.observe(r).extra["bumper"].touching
