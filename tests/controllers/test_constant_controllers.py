"""Controllers that read nothing (constant wheels or velocity) get no observation built."""
from __future__ import annotations

from pymunk_bot.engine.observing import Observer
from pymunk_bot.engine.simulation import Simulation


def _scenario(controller: dict) -> dict:
    return {"name": "constant", "world": {"size": [6.0, 6.0]},
            "robots": [{"name": "r1", "pose": [1.0, 3.0, 0.0], "controller": controller},
                       {"name": "r2", "pose": [1.0, 1.0, 0.0],
                        "controller": {"type": "go_to_goal", "goal": [5.0, 1.0]}}]}


def test_a_constant_controller_drives_without_observations(monkeypatch):
    seen = []
    original = Observer.observe_many

    def spy(self, indices, now):
        seen.extend(indices)
        return original(self, indices, now)

    monkeypatch.setattr(Observer, "observe_many", spy)
    for controller in ({"type": "wheels", "left": 0.5, "right": 0.5},
                       {"type": "velocity", "v": 0.5, "omega": 0.0}):
        seen.clear()
        sim = Simulation.from_dict(_scenario(controller))
        sim.run(2.0)
        assert set(seen) == {1}  # only the go-to-goal robot was observed
        assert sim.robots["r1"].pose[0] > 1.8  # the constant one drove all the same
        assert sim.robots["r2"].pose[0] > 1.8
