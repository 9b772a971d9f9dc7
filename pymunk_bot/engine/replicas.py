"""Copies of one scenario in one pymunk Space, advanced as one: the vector env's core.

Each copy is a whole :class:`~pymunk_bot.engine.simulation.Simulation` of its own (robots, sensors, seed,
clock, results) and can be reset alone. The arena and fixed obstacles are built once and
shared; each copy's moving shapes (robots, crates, scripted movers) are in a category of their
own, so they meet, and their sensors see, only the fixed world and their own copy. One tick
steps the Space once for every copy, steers every robot in one pass and casts every due LiDAR
in one call.

    replicas = Replicas(config, seeds=[0, 1, 2, 3])
    replicas.step()                      # every copy advances dt
    replicas.reset(2, seed=7)            # copy 2 starts again, the others run on
    replicas.sims[2].robots["r1"].pose
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pymunk

from pymunk_bot.config import ScenarioConfig
from pymunk_bot.engine.batch import Batch
from pymunk_bot.physics.settings import MAX_REPLICAS
from pymunk_bot.physics.propulsion import Propulsion
from pymunk_bot.engine.simulation import Simulation
from pymunk_bot.robots.rows import SharedRows
from pymunk_bot.robots.stacking import Stack
from pymunk_bot.physics.world import World


class NotShareable(ValueError):
    """Copies of this scenario cannot share a space (it has pedestrians)."""


class Replicas:
    """``len(seeds)`` copies of ``config`` (at most MAX_REPLICAS) sharing one Space."""

    def __init__(self, config: ScenarioConfig, seeds: Sequence[int],
                 source: str | None = None) -> None:
        if not 1 <= len(seeds) <= MAX_REPLICAS:
            raise ValueError(f"a shared space holds 1 to {MAX_REPLICAS} copies (got {len(seeds)})")
        self.ground = World.ground(config)
        # Every copy's per-robot state, in arrays the copies share from birth (robots/rows.py).
        self.rows = SharedRows(len(seeds))
        self.sims = [Simulation(config, seed, source, ground=self.ground, replica=r,
                                rows=self.rows.of_copy(r))
                     for r, seed in enumerate(seeds)]
        for actor in self.sims[0].world.actors:
            if not getattr(actor, "keeps_to_its_copy", False):  # it may meet the other copies
                raise NotShareable(f"copies of scenario '{config.name}' cannot share a space: "
                                   f"its {type(actor).__name__} would meet the other copies")
        self.dt = self.sims[0].dt
        self.substeps = self.sims[0].substeps
        self._propulsion: Propulsion | None = None
        self._stack: Stack | None = None
        self._batch: Batch | None = None
        self._assemble()

    def reset(self, index: int, seed: int | None = None) -> None:
        """Rebuild copy ``index`` (with a new ``seed``); the other copies are untouched."""
        self.sims[index].reset_copy(seed)
        self._assemble()

    @property
    def stacked(self) -> bool:
        """Whether the copies' bookkeeping is stacked (see :mod:`pymunk_bot.robots.stacking`)."""
        return self._stack is not None

    def set_velocities(self, robot: str, copies: Sequence[int], v: np.ndarray,
                       omega: np.ndarray) -> None:
        """``robots[robot].set_velocity(v[j], omega[j])`` in each copy ``copies[j]`` (arrays
        [m/s], [rad/s]): one call for them all where their diff drives are stacked."""
        sims = [self.sims[c] for c in copies]
        stack = self._stack
        if stack is not None and sims:
            index = list(sims[0].robots).index(robot)
            where = [stack.row_of[c * stack.per_copy + index] for c in copies]
            whole = where[0][0]
            if hasattr(whole, "set_velocities") and all(w is whole for w, _ in where):
                whole.set_velocities(np.array([row for _, row in where]), v, omega)
                for sim in sims:
                    sim.robots[robot].take_over()  # as Robot.command does
                return
        for sim, v_j, omega_j in zip(sims, v.tolist(), omega.tolist()):
            sim.robots[robot].set_velocity(v_j, omega_j)

    def robot_states(self, robot: str, copies: Sequence[int]) -> dict[str, np.ndarray]:
        """Robot ``robot`` of each copy in ``copies``, read at once: ``x``, ``y`` [m],
        ``theta`` [rad], ``vx``, ``vy`` [m/s] (world frame), ``omega`` [rad/s], ``goal_x``,
        ``goal_y`` [m] (NaN: none), ``collisions``, ``reached`` (goal reached) and ``time``
        (each copy's clock [s]); the same floats the robots' handles give one by one. Needs
        the copies' bookkeeping stacked (``stacked``)."""
        propulsion, stack = self._propulsion, self._stack
        if propulsion is None or stack is None:
            raise RuntimeError("robot_states reads stacked copies: this scenario's groups "
                               "do not stack")
        index = list(self.sims[0].robots).index(robot)
        rows = np.array([c * stack.per_copy + index for c in copies], dtype=np.intp)
        xy = propulsion.position_array()[rows]
        motion = propulsion.motion_array()[rows]
        fleet = stack.fleet  # every copy's fleet in one
        goal, collisions = fleet.goal[rows], fleet.collisions[rows]
        reached = ~np.isnan(fleet.time_to_goal[rows])
        return {"x": xy[:, 0], "y": xy[:, 1], "theta": motion[:, 0], "vx": motion[:, 1],
                "vy": motion[:, 2], "omega": motion[:, 3], "goal_x": goal[:, 0],
                "goal_y": goal[:, 1], "collisions": collisions, "reached": reached,
                "time": np.array([self.sims[c].time for c in copies])}

    def step(self) -> None:
        """Advance every copy by one physics step of ``dt``: the tick of
        :meth:`Simulation.step <pymunk_bot.engine.simulation.Simulation.step>` for all of them at once."""
        assert self._batch is not None
        self._batch.step()

    def _assemble(self) -> None:
        """One Propulsion for every copy's robots and their bookkeeping stacked (both rebuilt
        after a reset: a copy's bodies are new, its rows hold its fresh state), keeping what
        the old Propulsion knew about the bodies that stayed."""
        self._stack = Stack.of(self.sims, self.rows) if len(self.sims) > 1 else None
        bodies: list[pymunk.Body] = []
        controls: list[pymunk.Body] = []
        groups: list[tuple[Any, list[int]]] = []
        for sim in self.sims:
            start = len(bodies)
            for robot in sim.robots.values():
                bodies.append(robot.body)
                controls.append(robot.control)
            for group, idx in sim.built.drive_groups:
                groups.append((group, [start + i for i in idx]))
        propulsion = Propulsion(self.ground.contact_space, bodies, controls, groups,
                                self._stack.drive_groups if self._stack else None, copies=True)
        if self._propulsion is not None:
            propulsion.adopt(self._propulsion)
        self._propulsion = propulsion
        self._batch = Batch(self.sims, self.ground, propulsion, self._stack, self._batch)
