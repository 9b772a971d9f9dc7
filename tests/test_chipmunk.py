"""Compiled code reads and writes bodies and joints through Chipmunk's own functions
(physics/chipmunk.py): every accessor gives what pymunk's properties give, on bodies of every
kind, in a Space or out of one."""
from __future__ import annotations

import numba
import numpy as np
import pymunk

from pymunk_bot.physics import chipmunk
from pymunk_bot.physics.chipmunk import CALLS, addresses, read_motions, read_poses, read_states


@numba.njit(cache=False)
def _write(calls: np.ndarray, body: int, joint: int, values: np.ndarray) -> None:
    chipmunk.set_vect(calls[chipmunk.SET_VELOCITY], body, values[0], values[1])
    chipmunk.set_scalar(calls[chipmunk.SET_SPIN], body, values[2])
    chipmunk.set_scalar(calls[chipmunk.SET_ANGLE], body, values[3])
    chipmunk.set_vect(calls[chipmunk.SET_ANCHOR], joint, values[4], values[5])


def _bodies(rng: np.random.Generator) -> tuple[pymunk.Space, list[pymunk.Body]]:
    space = pymunk.Space()
    bodies = [pymunk.Body(1.0, 2.0), pymunk.Body(body_type=pymunk.Body.KINEMATIC),
              pymunk.Body(3.0, 1.0)]
    for body in bodies:
        body.position = tuple(rng.uniform(-50, 50, 2))
        body.angle = float(rng.uniform(-10, 10))
        body.velocity = tuple(rng.uniform(-3, 3, 2))
        body.angular_velocity = float(rng.uniform(-4, 4))
        space.add(body, pymunk.Circle(body, 0.2))
    return space, bodies + [pymunk.Body(1.0, 1.0)]  # the last in no Space


def test_reads_give_what_pymunks_properties_give() -> None:
    _, bodies = _bodies(np.random.default_rng(1))
    at = addresses(bodies)
    poses, motions, states = np.empty((4, 3)), np.empty((4, 4)), np.empty((4, 5))
    read_poses(CALLS, at, poses)
    read_motions(CALLS, at, motions)
    read_states(CALLS, at, states)
    for k, b in enumerate(bodies):
        assert tuple(poses[k]) == (b.position.x, b.position.y, b.angle)
        assert tuple(motions[k]) == (b.angle, b.velocity.x, b.velocity.y, b.angular_velocity)
        assert tuple(states[k]) == (*b.position, *b.velocity, b.angular_velocity)


def test_writes_do_what_pymunks_setters_do() -> None:
    rng = np.random.default_rng(2)
    space, bodies = _bodies(rng)
    theirs_space, theirs = _bodies(np.random.default_rng(2))
    for k in range(3):
        values = rng.uniform(-5, 5, 6)
        mine = pymunk.PivotJoint(bodies[k], bodies[-1], (0, 0))
        their = pymunk.PivotJoint(theirs[k], theirs[-1], (0, 0))
        _write(CALLS, int(addresses([bodies[k]])[0]), int(addresses([mine])[0]), values)
        theirs[k].velocity = (values[0], values[1])
        theirs[k].angular_velocity = values[2]
        theirs[k].angle = values[3]
        their.anchor_a = (values[4], values[5])
        assert mine.anchor_a == their.anchor_a == (values[4], values[5])
    for _ in range(5):  # the transforms written with the angle move them alike
        space.step(0.01)
        theirs_space.step(0.01)
    for mine_body, their_body in zip(bodies, theirs):
        assert mine_body.position == their_body.position
        assert mine_body.angle == their_body.angle
        assert mine_body.rotation_vector == their_body.rotation_vector
        assert mine_body.velocity == their_body.velocity
