"""The IR-SIM side of ``benchmarks/irsim.py``: run by IR-SIM's own venv, never imported.

    /tmp/irsim-venv/bin/python irsim_runner.py WORLD.yaml REQUEST.json

Reads REQUEST.json ({"steps": n, "actions": [[v, omega], ...] one per robot}), builds the IR-SIM
environment headless, then in-loop ``steps`` times: ``env.step(actions)`` and every robot's
``get_lidar_scan()``. Prints one JSON line: the loop's CPU time (time.process_time, setup and
imports excluded), the first scan of every robot after one zero-velocity step (for checking that
the two worlds are the same), and the final poses. Depends only on IR-SIM and the standard library.
"""
from __future__ import annotations

import json
import sys
import time


def main(world: str, request_path: str) -> None:
    import irsim  # in IR-SIM's venv only

    with open(request_path) as f:
        request = json.load(f)
    steps, actions = int(request["steps"]), request["actions"]
    ids = list(range(len(actions)))
    env = irsim.make(world, headless=True, log_level="WARNING", seed=0)
    robots = env.robot_list
    env.step([[0.0, 0.0]] * len(ids), action_id=ids)  # still: the scans check the world
    first = [[float(r) for r in robot.get_lidar_scan()["ranges"]] for robot in robots]
    scans = None
    started = time.process_time()
    for _ in range(steps):
        env.step(actions, action_id=ids)
        scans = [robot.get_lidar_scan()["ranges"] for robot in robots]
    cpu = time.process_time() - started
    assert scans is not None and len(scans) == len(ids)
    poses = [[float(v) for v in robot.state.ravel()[:3]] for robot in robots]
    print(json.dumps({"cpu_s": cpu, "steps": steps, "step_time": env.step_time,
                      "first_scans": first, "final_poses": poses,
                      "version": irsim.__version__}))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
