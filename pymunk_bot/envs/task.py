"""The navigation task, free of any RL library: scenario preparation and the reward weights.

The Gymnasium env, the vector env and the PettingZoo env all use these pieces and
:class:`~pymunk_bot.envs.robot_task.RobotTask`, so one robot sees, acts and is rewarded the same
way in all three. The observation and the action scaling live in :mod:`pymunk_bot.policy.io`,
which the ``policy`` controller uses too. Units: metres, seconds, radians.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from pymunk_bot.config import ScenarioConfig, load_scenario, parse_scenario, scenario_data
from pymunk_bot.config.errors import ScenarioError
from pymunk_bot.policy.io import MAX_BEAMS

GOAL_SAMPLE_TRIES = 2000  # random goals tried before giving up on a crowded arena
GOAL_MIN_DISTANCE = 1.0  # [m] a random goal at least this far from the start


@dataclass(frozen=True)
class RewardWeights:
    """Reward per control step = progress * (metres closer to the goal)
    + contact * (seconds in contact) + collision * (new contact episodes)
    + clearance * (seconds) * max(0, 1 - clearance / clearance_margin)
    + time * (seconds elapsed) + success (once, on arriving without any contact on the way).

    Seconds in contact: the control period, for every period that ends touching something or
    in which a contact began, so a scrape costs by its length and a graze costs one period.
    The clearance [m] is the nearest LiDAR return less the robot's radius."""

    progress: float = 1.0  # per metre of progress toward the goal
    contact: float = -5.0  # per second in contact
    collision: float = 0.0  # per new contact episode
    clearance: float = -1.0  # per second with no clearance, less further out (see above)
    clearance_margin: float = 0.3  # [m] clearance beyond which the clearance term is 0
    time: float = -0.1  # per simulated second
    success: float = 10.0  # on reaching the goal without any contact on the way

    def as_array(self) -> np.ndarray:
        """progress, contact, collision, clearance, clearance_margin, time, success: the order
        :func:`~pymunk_bot.envs.step_rows.step_rows` reads them in."""
        return np.array((self.progress, self.contact, self.collision, self.clearance,
                         self.clearance_margin, self.time, self.success))

    @classmethod
    def from_any(cls, value: "RewardWeights | Mapping[str, float] | str | None"
                 ) -> "RewardWeights":
        """Weights as given, from a mapping of some of their names, a preset's name
        (``"crowdnav"``: CrowdNav's reward, :data:`CROWDNAV_REWARD`), or the defaults (None)."""
        if value is None:
            return cls()
        if isinstance(value, cls):
            return value
        if isinstance(value, str):
            if value not in REWARD_PRESETS:
                raise ValueError(f"reward must be weights or a preset, one of "
                                 f"{sorted(REWARD_PRESETS)} (got {value!r:.60})")
            value = REWARD_PRESETS[value]
        if not isinstance(value, Mapping):
            raise TypeError(f"reward must be RewardWeights or a mapping of weights (got {value!r})")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(value) - known)
        if unknown:
            raise ValueError(f"unknown reward weight(s) {unknown}; valid: {sorted(known)}")
        weights = {k: float(v) for k, v in value.items()}
        if not all(math.isfinite(v) for v in weights.values()):
            raise ValueError(f"reward weights must be finite (got {weights})")
        if weights.get("clearance_margin", 1.0) <= 0:
            raise ValueError(f"clearance_margin must be > 0 m (got {weights['clearance_margin']})")
        return cls(**weights)


# CrowdNav's reward (Chen et al. 2019; vita-epfl/CrowdNav crowd_sim/envs/crowd_sim.py and
# configs/env.config: success_reward 1, collision_penalty -0.25, discomfort_dist 0.2,
# discomfort_penalty_factor 0.5): +1 on arriving, -0.25 on a collision, and
# (d - 0.2) * 0.5 * dt while the gap d to a body is under 0.2 m; nothing per second or metre.
# As weights: clearance * dt * (1 - d / 0.2) = (d - 0.2) * 0.5 * dt with clearance = -0.1.
CROWDNAV_REWARD = {"progress": 0.0, "contact": 0.0, "collision": -0.25, "clearance": -0.1,
                   "clearance_margin": 0.2, "time": 0.0, "success": 1.0}
REWARD_PRESETS = {"crowdnav": CROWDNAV_REWARD}


def load_config(scenario: str | Path | dict | ScenarioConfig | None) -> tuple[ScenarioConfig, str]:
    """(config, source name) from a path, shipped name, dict, config or None (built-in)."""
    if isinstance(scenario, ScenarioConfig):
        return scenario, f"scenario '{scenario.name}'"
    if isinstance(scenario, dict):
        return parse_scenario(scenario, "<dict>"), "<dict>"
    return load_scenario(scenario), "default" if scenario is None else str(scenario)


def prepare_scenario(config: ScenarioConfig, source: str, agents: list[str] | None,
                     lidar: Mapping[str, Any] | None, control_period: float,
                     need_goal: bool = True) -> tuple[ScenarioConfig, list[str]]:
    """The scenario the agents drive: their controllers removed, a LiDAR that scans once per
    control period (overrides from ``lidar``), a goal each. Returns (config, agent names).

    Errors name the key path, as for a scenario file.
    """
    data = scenario_data(config, exclude_unset=True)  # unset keys stay unset (no localizer)
    names = [r["name"] for r in data["robots"]]
    agents = names[:1] if agents is None else list(agents)
    for name in agents:
        if name not in names:
            raise ScenarioError(source, "robots", f"no robot named '{name}' (robots: {names})")
    overrides = dict(lidar or {})
    for name in agents:
        index = names.index(name)
        robot = data["robots"][index]
        controller = robot.pop("controller", None) or {}
        if robot.get("goal") is None and controller.get("goal") is not None:
            robot["goal"] = {"position": controller["goal"]}
        if need_goal and robot.get("goal") is None:
            raise ScenarioError(source, f"robots[{index}].goal",
                                "the navigation task needs a goal (or random_goal=True)")
        scan = dict(robot.get("lidar") or {})
        scan["rate"] = 1.0 / control_period  # one fresh scan per action
        scan.update(overrides)
        robot["lidar"] = scan
    prepared = parse_scenario(data, source)
    for name in agents:
        lidar_config = prepared.robots[names.index(name)].lidar
        if lidar_config is None:  # given to every agent above
            raise ScenarioError(source, f"robots[{names.index(name)}].lidar", "missing")
        beams = lidar_config.beams
        if beams > MAX_BEAMS:
            raise ScenarioError(source, f"robots[{names.index(name)}].lidar.beams",
                                f"at most {MAX_BEAMS} beams in an observation (got {beams})")
    return prepared, agents


def sample_goal(sim, robot, rng: np.random.Generator) -> tuple[float, float]:
    """A goal in free space: clear of every obstacle by the robot's radius and a margin, and
    at least GOAL_MIN_DISTANCE from the robot."""
    import pymunk

    world = sim.world
    clearance = robot.radius + 0.1  # [m]
    everything = pymunk.ShapeFilter()
    x0, y0 = robot.pose[:2]
    for _ in range(GOAL_SAMPLE_TRIES):
        x, y = world.random_point(rng, clearance)
        if math.hypot(x - x0, y - y0) < GOAL_MIN_DISTANCE:
            continue
        if world.map is not None and world.map.is_solid(x, y):  # inside a map's solid
            continue
        if world.space.point_query_nearest((x, y), clearance, everything) is None:
            return x, y
    raise ScenarioError(sim.source, "random_goal", f"no free goal found in {GOAL_SAMPLE_TRIES} "
                        f"tries: no open space {clearance:g} m clear of everything, "
                        f"{GOAL_MIN_DISTANCE:g} m from the robot")


def end_info(sim, name: str) -> dict:
    """What ``info`` gains when robot ``name``'s episode ends: ``result`` (see
    :func:`robot_result`) and, when the run measures them (a scenario with pedestrians, or an
    ``expect`` bounding one), ``metrics``: the navigation metrics of docs/benchmark.md."""
    result = robot_result(sim, name)
    info = {"result": result}
    if "metrics" in result:
        info["metrics"] = result["metrics"]
    return info


def robot_result(sim, name: str) -> dict:
    """The result fields of one robot (``Simulation.result()``'s robots entry) plus ``passed``."""
    result = sim.result()
    fields_ = dict(result["robots"][name])
    fields_["passed"] = result["passed"]
    return fields_
