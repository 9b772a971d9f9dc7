"""The learned crowd policy (scenarios/policies/crowdnav.npz, examples/train_crowd.py) on
CrowdNav's protocol: its success on 40 of the 500 test cases kept to the 500-episode run, a
straight-line driver on the same observation failing that bound, and the same episodes on
every backend."""
from pathlib import Path

import numpy as np
import pytest

from pymunk_bot.benchmark.controllers import controller_choices
from pymunk_bot.benchmark.runner import run_benchmark
from pymunk_bot.benchmark.suite import load_suite
from pymunk_bot.policy.crowd_io import HUMAN_FEATURES
from pymunk_bot.policy.files import MlpPolicy, load_policy

SHIPPED = Path(__file__).resolve().parents[2] / "scenarios" / "policies"
CONTROLLER = SHIPPED / "crowdnav_policy.yaml"
# The 500-episode run of docs/benchmark.md:
#   pymunk-bot benchmark crowdnav --controller scenarios/policies/crowdnav_policy.yaml \
#       --seeds 0:500 --out episodes.csv
MEASURED_500_SUCCESS = 0.988  # 494 of 500 (imitation + DAgger; the CMA-ES policy had 0.432)
EPISODES = 40


def binomial_low(rate: float, n: int) -> float:
    """The lower end of the binomial 99 % interval of n draws at ``rate``."""
    from scipy.stats import binom  # here: scipy.stats costs every test worker 0.4 s to import

    return float(binom.interval(0.99, n, rate)[0])


def successes(controller: str | Path, seeds) -> list[dict]:
    rows = run_benchmark(load_suite("crowdnav"), controller_choices([str(controller)]), seeds)
    assert all(r["status"] == "ok" for r in rows)
    return rows


@pytest.mark.slow  # about 10 s of CPU: 40 CrowdNav test cases
def test_the_shipped_policy_keeps_its_success_on_40_test_cases():
    policy = load_policy(SHIPPED / "crowdnav.npz")
    assert policy.crowd_humans == 5  # it records the crowd_state observation it sees
    rows = successes(CONTROLLER, range(EPISODES))
    assert sum(r["success"] for r in rows) >= binomial_low(MEASURED_500_SUCCESS, EPISODES)
    for r in rows:  # CrowdNav's three ends: exactly one per episode
        assert r["success"] + r["collision"] + r["timeout"] == 1.0


@pytest.mark.slow
def test_a_straight_line_driver_fails_the_bound(tmp_path):
    """The same observation, the network replaced by one that heads straight for the goal
    at full speed: it must fall below the bound, or the test above could not fail."""
    inputs = 3 + 3 + HUMAN_FEATURES * 5
    w = np.zeros((inputs, 3))
    w[1, 0] = w[2, 2] = 1.0  # v = cos, vy = sin of the goal bearing
    MlpPolicy([w], [np.zeros(3)], crowd_humans=5).save(tmp_path / "straight.npz")
    (tmp_path / "straight.yaml").write_text(
        "controller: {type: policy, path: straight.npz, rate: 4.0, give_up_after: 25.0}\n")
    rows = successes(tmp_path / "straight.yaml", range(EPISODES))
    assert sum(r["success"] for r in rows) < binomial_low(MEASURED_500_SUCCESS, EPISODES)


@pytest.mark.slow  # about 20 s on a loaded machine: two worker processes start
def test_the_same_episodes_on_the_serial_and_process_backends():
    suite, choices = load_suite("crowdnav"), controller_choices([str(CONTROLLER)])
    serial = run_benchmark(suite, choices, range(4))
    process = run_benchmark(suite, choices, range(4), backend="process", workers=2)
    assert [r["signature"] for r in serial] == [r["signature"] for r in process]
    assert [{k: repr(v) for k, v in r.items()} for r in serial] == \
        [{k: repr(v) for k, v in r.items()} for r in process]  # repr: NaN equals NaN
