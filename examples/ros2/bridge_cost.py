"""Measure what `run --rosbridge` costs: the CPU time of a run paced at real time with the
rosbridge server and one /scan subscriber, against the same run paced without the server.

    python examples/ros2/bridge_cost.py [SCENARIO] [--duration 20] [--clients 1] [--repeats 5]

Each run is a fresh process; the subscribers (roslibpy) run in another process, so only the
simulator's own cost is counted. Runs without and with the bridge alternate ``--repeats``
times: a paced run's CPU time varies by +-20 % from one process to the next (sleeps and
wake-ups), more than the bridge costs, so the ratio printed is the median of the pairs'.
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time


def paced(scenario: str, duration: float, bridge: bool, clients: int) -> float:
    """CPU seconds [s] of one paced run in a child process."""
    code = f"""
import time, sys
from pymunk_bot.config import load_scenario
from pymunk_bot.engine.simulation import Simulation
from pymunk_bot.foxglove.live import run_paced
config = load_scenario({scenario!r})
sim = Simulation(config, seed=1, source={scenario!r})
server = None
if {bridge}:
    from pymunk_bot.ros2.bridge import serve_sim
    from pymunk_bot.ros2.worldmap import world_grid
    server = serve_sim(sim, port=0, world_map=world_grid(config), report=lambda line: None)
    print(server.port, flush=True)
    while len(server.subscribed) == 0 or server.clients < {clients}:
        time.sleep(0.05)
start = time.process_time()
run_paced(sim, {duration}, 1.0)
print(time.process_time() - start, flush=True)
if server is not None:
    server.stop()
"""
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert child.stdout is not None
    subscribers = None
    if bridge:
        port = int(child.stdout.readline())
        subscribers = subprocess.Popen([sys.executable, "-c", f"""
import time, roslibpy
clients = [roslibpy.Ros(host="127.0.0.1", port={port}) for _ in range({clients})]
counts = [0] * len(clients)
for k, ros in enumerate(clients):
    ros.run(timeout=10)
    def got(message, k=k):
        counts[k] += 1
    roslibpy.Topic(ros, "/scan", "sensor_msgs/msg/LaserScan").subscribe(got)
time.sleep({duration} + 3)
print("scans received per client:", counts, flush=True)
"""])
    cpu = float(child.stdout.readline())
    child.wait()
    if subscribers is not None:
        subscribers.wait()
    return cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenario", nargs="?", default="warehouse")
    parser.add_argument("--duration", type=float, default=20.0, help="simulated [s]")
    parser.add_argument("--clients", type=int, default=1, help="subscribers to /scan")
    parser.add_argument("--repeats", type=int, default=5, help="pairs of runs (median ratio)")
    args = parser.parse_args()
    ratios = []
    for _ in range(max(1, args.repeats)):
        without = paced(args.scenario, args.duration, False, args.clients)
        time.sleep(1.0)
        with_bridge = paced(args.scenario, args.duration, True, args.clients)
        ratios.append(with_bridge / without)
        print(f"{args.scenario}, {args.duration:g} s paced at real time: CPU {without:.2f} s "
              f"without the bridge, {with_bridge:.2f} s with it and {args.clients} "
              f"subscriber(s): ratio {ratios[-1]:.2f}", flush=True)
    print(f"median ratio of {len(ratios)} pairs: {statistics.median(ratios):.2f}")


if __name__ == "__main__":
    main()
