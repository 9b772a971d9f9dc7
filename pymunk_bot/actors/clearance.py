"""The social-force walkers' hard core: their velocities close no gap within a step.

The social force model (Helbing & Molnar 1995) is soft at contact: its repulsion at touching
distance (V0 / sigma exp(-b / sigma), about 1.3 m/s^2 for two people side by side) is weaker than
the driving force (v0 / tau = 2.6 m/s^2 from rest), so walkers that converge from several sides
(a symmetric crossing) met at up to 0.6 m/s and stayed pressed together, the contact solver's
slop (5 mm) deep. Helbing, Farkas & Vicsek (Nature 407, 487, 2000) add a body force
k (r_ij - d_ij) and sliding friction once bodies overlap; here pymunk's rigid contacts play that
part, and what keeps walkers from overlapping in the first place is a speculative contact
(Catto's, as in Box2D) on the velocities the forces give, before pymunk's step:

    (v_a - v_b) . u <= max(clearance - CONTACT_MARGIN, 0) / step

for every body b a walker a could reach before it next chooses (``step``: the tick, or its
decision period), u the unit direction from a toward b's nearest point. Between two walkers an
excess closing speed is removed by equal and opposite impulses (their masses weigh them, so
momentum is kept: a walker pressed from behind pushes the one ahead, and dense counterflows
shove through as they did with contacts); against a wall, obstacle or robot footprint (v_b
taken as 0: a robot that drives into a walker pushes it, a contact the robot counts) or an ORCA
walker (v_b its velocity), which do not yield to it, the walker takes all of it. Gauss-Seidel
sweeps over every walker's constraints, ITERATIONS times, like pymunk's own solver, then the
surfaces' alone (what the sweeps leave goes to pairs of walkers). A walker loses speed only
toward a body closer than a step's travel, and slides along it freely.
"""
from __future__ import annotations

import numba
import numpy as np

CONTACT_MARGIN = 0.005  # [m] walkers stop this short of touching (the contact solver's slop)
MAX_CONTACTS = 8  # the nearest bodies per walker that bind it (6 equal discs can touch one)
ITERATIONS = 10  # Gauss-Seidel sweeps (pymunk's solver: 10 to 30)
SURFACE = -1  # the ``other`` of a wall, obstacle or robot footprint


class Clearances:
    """Per walker, the nearest bodies it could reach before it chooses again, as the kernels
    of :mod:`.social_forces` and :mod:`.surfaces` record them: ``near`` (n, ``contacts``, 4)
    holds each one's room [m] (clearance beyond CONTACT_MARGIN), the unit direction toward it
    and the other walker's index (SURFACE for a surface), smallest room first (ORCA walkers'
    pairs, :func:`.orca.closing_limits`: how far the pair may close along a direction, in
    their neighbours' order); ``count`` (n,)
    how many (:func:`.social_forces.social_forces` starts each tick's afresh); ``reach`` (n,)
    [m] how far each walker can go in a step (its owner keeps it)."""

    def __init__(self, walkers: int, contacts: int = MAX_CONTACTS) -> None:
        self.near = np.zeros((walkers, contacts, 4))
        self.count = np.zeros(walkers, dtype=np.int64)
        self.reach = np.zeros(walkers)  # [m]

    def limit(self, velocity: np.ndarray, step: np.ndarray, mass: np.ndarray,
              bound: np.ndarray) -> None:
        """Limit ``velocity`` (n, 2) [m/s] of the walkers ``bound`` (n,) (bool; the others are
        held as they are), of ``mass`` (n,) [kg], in place, to what closes no recorded gap
        within ``step`` (n,) [s] (module doc)."""
        limit_closing(velocity, self.near, self.count, step, mass, bound)

    def add_surfaces(self, source: "Clearances", walkers: np.ndarray) -> None:
        """Append the surfaces ``source`` recorded for ``walkers`` (indices) to their rows here,
        as many as there is room for."""
        rows = source.near[walkers]
        surface = (rows[..., 3] == SURFACE) & (
            np.arange(rows.shape[1])[None, :] < source.count[walkers][:, None])
        slot = self.count[walkers][:, None] + np.cumsum(surface, axis=1) - 1
        keep = surface & (slot < self.near.shape[1])
        whose = np.broadcast_to(walkers[:, None], keep.shape)[keep]
        self.near[whose, slot[keep]] = rows[keep]
        self.count[walkers] += keep.sum(axis=1)


@numba.njit(cache=True, nogil=True)
def record(near: np.ndarray, count: np.ndarray, i: int, clearance: float, ux: float,
           uy: float, other: int) -> None:
    """Note a body ``clearance`` [m] from walker ``i`` in direction (``ux``, ``uy``) (walker
    ``other``, or SURFACE): inserted among the walker's nearest, smallest room first, keeping
    at most near.shape[1]."""
    room = max(clearance - CONTACT_MARGIN, 0.0)
    keep = near.shape[1]
    j = count[i]
    while j > 0 and room < near[i, j - 1, 0]:
        if j < keep:
            near[i, j] = near[i, j - 1]
        j -= 1
    if j < keep:
        near[i, j, 0], near[i, j, 1], near[i, j, 2], near[i, j, 3] = room, ux, uy, other
        count[i] = min(count[i] + 1, keep)


@numba.njit(cache=True, nogil=True)
def limit_closing(velocity: np.ndarray, near: np.ndarray, count: np.ndarray, step: np.ndarray,
                  mass: np.ndarray, bound: np.ndarray) -> None:
    """See :meth:`Clearances.limit`."""
    for _ in range(ITERATIONS):
        for i in range(len(velocity)):
            if not bound[i]:
                continue
            for k in range(count[i]):
                ux, uy, other = near[i, k, 1], near[i, k, 2], int(near[i, k, 3])
                closing = velocity[i, 0] * ux + velocity[i, 1] * uy
                if other != SURFACE:
                    closing -= velocity[other, 0] * ux + velocity[other, 1] * uy
                excess = closing - near[i, k, 0] / step[i]
                if excess <= 0.0:
                    continue
                mine = 1.0  # the walker's part of the correction
                if other != SURFACE and bound[other]:
                    mine = mass[other] / (mass[i] + mass[other])
                    velocity[other, 0] += (1.0 - mine) * excess * ux
                    velocity[other, 1] += (1.0 - mine) * excess * uy
                velocity[i, 0] -= mine * excess * ux
                velocity[i, 1] -= mine * excess * uy
    # The sweeps converge geometrically (a walker running into a queue against a wall leaves 1 %
    # of its speed after 10); what is left is put on walker pairs, never into a wall: a last
    # projection onto the surfaces' half-planes alone (two passes: exact in a right-angled
    # corner).
    for i in range(len(velocity)):
        if not bound[i]:
            continue
        for _ in range(2):
            for k in range(count[i]):
                if int(near[i, k, 3]) != SURFACE:
                    continue
                excess = (velocity[i, 0] * near[i, k, 1] + velocity[i, 1] * near[i, k, 2]
                          - near[i, k, 0] / step[i])
                if excess > 0.0:
                    velocity[i, 0] -= excess * near[i, k, 1]
                    velocity[i, 1] -= excess * near[i, k, 2]
