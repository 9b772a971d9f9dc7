"""Sections of things that move by themselves: scripted ``motion`` of obstacles, and pedestrians.

docs/scenario-format.md documents each key; keep the two in step.
"""
from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from pymunk_bot.config.types import (Float, Length, Mass, Name, NonNegativeFloat, PositiveFloat, PositiveInt,
                    Section, Vec2)

MAX_PATH_POINTS = 256
MAX_SCRIPTED_SPEED = 20.0  # [m/s]
MAX_WALKING_SPEED = 5.0  # [m/s]
# A walker's speed cap relative to its desired speed (the substep rule bounds walkers by it).
MAX_SPEED_FACTOR = 1.3

Mode = Literal["loop", "pingpong", "once"]


class MotionConfig(Section):
    """A scripted path for an obstacle's centre: it starts at the first point (= ``center``)."""

    path: list[Vec2] = Field(min_length=2, max_length=MAX_PATH_POINTS)  # [m]
    speed: Annotated[PositiveFloat, Field(le=MAX_SCRIPTED_SPEED)]  # [m/s] along the path
    # loop: back to the first point and around again; pingpong: back and forth; once: stop at
    # the last point
    mode: Mode = "loop"
    angular_speed: Float = 0.0  # [rad/s] the obstacle spins at while it moves (0: keeps its angle)


MAX_NEIGHBORS = 64  # ORCA: half-planes per walker at most (bounds the per-step cost)


class PedestrianObstacle(Section):
    """A person walking between ``goals`` with the social force model (Helbing & Molnar 1995)
    or ORCA (van den Berg et al. 2011)."""

    type: Literal["pedestrian"]
    center: Vec2  # start position [m]
    goals: list[Vec2] = Field(min_length=1, max_length=MAX_PATH_POINTS)  # [m], in order
    mode: Mode = "pingpong"  # after the last goal: loop, pingpong back, or once (stay)
    radius: Annotated[Length, Field(le=1.0)] = 0.25  # [m] body disc (what LiDAR sees)
    speed: Annotated[PositiveFloat, Field(le=MAX_WALKING_SPEED)] = 1.3  # desired speed [m/s]
    speed_std: NonNegativeFloat = 0.0  # [m/s] each run draws the desired speed from N(speed, std)
    mass: Mass = 70.0  # [kg]
    goal_tolerance: PositiveFloat = 0.3  # [m] a goal counts as reached this close
    relaxation_time: PositiveFloat = 0.5  # tau [s]: how fast the walker reaches its wish speed
    # Repulsion of other walkers and robots: V0 exp(-b / sigma), b the semi-minor axis of the
    # ellipse of the other's next step (b measured between body edges here)
    social_strength: NonNegativeFloat = 2.1  # V0 [m^2/s^2]
    social_range: PositiveFloat = 0.3  # sigma [m]
    # Repulsion of walls and obstacles: U0 exp(-d / R), d the distance to the nearest surface
    wall_strength: NonNegativeFloat = 10.0  # U0 [m^2/s^2]
    wall_range: PositiveFloat = 0.2  # R [m]
    fluctuation: NonNegativeFloat = 0.0  # std of a random force per unit mass [m/s^2]
    # social_force: the forces above; orca: the velocity closest to the wished one that no
    # neighbour can collide with within time_horizon (the keys below)
    policy: Literal["social_force", "orca"] = "social_force"
    react_to_robot: bool = True  # false: robots are ignored (walked through, pushed aside)
    group: Name | None = None  # walkers with the same group keep together (and its slowest pace)
    time_horizon: Annotated[PositiveFloat, Field(le=60.0)] = 5.0  # [s] ORCA: other walkers, robots
    obstacle_time_horizon: Annotated[PositiveFloat, Field(le=60.0)] = 2.0  # [s] ORCA: walls
    neighbor_distance: Annotated[PositiveFloat, Field(le=100.0)] = 10.0  # [m] ORCA: who counts
    max_neighbors: Annotated[PositiveInt, Field(le=MAX_NEIGHBORS)] = 10  # ORCA: nearest this many
    # How a walker decides (defaults: this simulator's walkers; CrowdNav's humans in brackets)
    decision_period: Annotated[NonNegativeFloat, Field(le=10.0)] = 0.0  # [s] a new velocity
    # this often, held in between; 0: every tick [CrowdNav: 0.25, its time step]
    max_speed: Annotated[PositiveFloat, Field(le=MAX_WALKING_SPEED)] | None = None  # [m/s]
    # speed cap; None: MAX_SPEED_FACTOR x the desired speed (never above it) [CrowdNav: 1.0]
    keep_right: Annotated[Float, Field(ge=0.0, le=0.5)] = 0.1  # [rad] the wish turned right
    # by this (ORCA; see actors/orca.py) [CrowdNav: 0]
    slow_within: Annotated[NonNegativeFloat, Field(le=10.0)] = 0.0  # [m] within this of its
    # goal the wished speed falls in proportion to the distance [CrowdNav: 1.0 = v_pref x 1 s]
    robot_share: Annotated[Float, Field(ge=0.0, le=1.0)] = 1.0  # ORCA: the share of the
    # avoidance a reacting walker takes against a robot [CrowdNav, robot visible: 0.5]
    orca_margin: Annotated[NonNegativeFloat, Field(le=1.0)] = 0.0  # [m] ORCA: added to every
    # radius the walker's ORCA uses [CrowdNav: 0.01]
    perturbation: Annotated[NonNegativeFloat, Field(le=0.1)] | None = None  # [m/s] the
    # largest random nudge of the walker's velocity each tick, which breaks exact symmetries;
    # None: actors/pedestrians.py's ORCA_PERTURBATION, 0.03, for an ORCA walker, else its
    # PERTURBATION, 0.001 [CrowdNav: 0, none]
