"""The ES recipe runs end to end: CMA-ES generations, a saved .npz the policy controller loads,
a learning-curve plot (the measured 10-minute run is in docs/learning.md)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")

SCRIPT = Path(__file__).resolve().parents[2] / "examples" / "train_es.py"
sys.path.insert(0, str(SCRIPT.parent))
import train_es  # noqa: E402


def test_a_short_run_learns_saves_and_plots(tmp_path):
    pytest.importorskip("cma")  # here, not at collection: importing cma costs 0.4 s
    theta, shapes, history = train_es.train(minutes=0.03, seed=0, popsize=4, episodes=1,
                                            workers=1, progress=False)
    assert history and {"mean_return", "best_return", "success"} <= history[0].keys()
    policy = train_es.to_policy(theta, shapes)
    assert policy.inputs == 32 + 8 and policy.outputs == 2
    policy.save(tmp_path / "p.npz")
    from pymunk_bot.policy.files import load_policy

    np.testing.assert_array_equal(load_policy(tmp_path / "p.npz").weights[0], policy.weights[0])
    train_es.plot(history, tmp_path / "curve.png", "test")
    assert (tmp_path / "curve.png").stat().st_size > 5_000


def test_a_guided_run_records_its_guidance(tmp_path):
    pytest.importorskip("cma")
    theta, shapes, history = train_es.train(None, seed=0, popsize=4, episodes=1, workers=1,
                                            progress=False, generations=1, guided=True,
                                            kind="office")
    assert history
    train_es.to_policy(theta, shapes, guided=True).save(tmp_path / "p.npz")
    from pymunk_bot.policy.files import load_policy

    assert load_policy(tmp_path / "p.npz").plan_guidance is not None  # evaluate turns it on


# ------------------------------------------------------------------ beyond one machine

SHORT = {"seed": 3, "popsize": 6, "episodes": 2, "generations": 3}  # about 4 s of CPU a run


def arrays(policy) -> list[np.ndarray]:
    return [*policy.weights, *policy.biases]


@pytest.mark.slow  # about 16 s of CPU: a scheduler, two workers and three trainings
def test_a_dask_cluster_trains_the_same_policy_bit_for_bit_as_local_processes(tmp_path):
    """The script, run as a user runs it, on a scheduler and 2 workers on 127.0.0.1 that
    cannot import it (they run elsewhere), and train() called from this module: the same
    policy as 2 local processes."""
    pytest.importorskip("cma")
    from bounds import HANG_GUARD, children_cpu
    from dask_cluster import loopback_dask_cluster

    from pymunk_bot.policy.files import load_policy

    out = tmp_path / "dask.npz"
    with loopback_dask_cluster(tmp_path, workers=2) as address:
        before = children_cpu()
        proc = subprocess.run(
            [sys.executable, str(SCRIPT), "--generations", "3", "--seed", "3",
             "--popsize", "6", "--train-episodes", "2", "--backend", "dask",
             "--address", address, "--out", str(out), "--episodes", "1", "--workers", "1"],
            capture_output=True, text=True, timeout=HANG_GUARD, cwd=tmp_path)
        cpu = children_cpu() - before
        # The module imported here, its code shipped to workers that cannot import it
        shipped = train_es.train(None, backend="dask", address=address, progress=False,
                                 **SHORT)[0]
    assert proc.returncode == 0, proc.stderr
    assert "3 generations" in proc.stdout
    assert cpu < 60  # the driver's share: CMA and the held-out episode (about 5 s)
    theta, layer_shapes, history = train_es.train(None, workers=2, progress=False, **SHORT)
    assert len(history) == 3
    local = train_es.to_policy(theta, layer_shapes)
    remote = load_policy(out)
    assert np.array_equal(shipped, theta)
    assert len(arrays(remote)) == len(arrays(local)) == 4
    for got, expected in zip(arrays(remote), arrays(local)):
        assert np.array_equal(got, expected)
    assert not np.array_equal(local.weights[0], 0)  # it moved from the start: not trivially equal


@pytest.mark.slow  # about 6 s of CPU: a serial run and three worker processes
def test_worker_count_and_order_of_completion_do_not_change_the_policy():
    pytest.importorskip("cma")
    serial = train_es.train(None, backend="serial", progress=False, **SHORT)[0]
    three = train_es.train(None, backend="process", workers=3, progress=False, **SHORT)[0]
    assert np.array_equal(serial, three)  # one env played all episodes, or three split them


@pytest.mark.parametrize("address, reason", [("127.0.0.1:9", "refused"),
                                             ("127.0.0.1:99999", "port")])
def test_an_unreachable_scheduler_is_one_line_and_exit_2(tmp_path, capsys, address, reason):
    pytest.importorskip("cma")
    pytest.importorskip("distributed")
    with pytest.raises(SystemExit) as exit_:
        train_es.main(["--generations", "1", "--backend", "dask", "--address", address,
                       "--out", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1
    assert err.startswith(f"error: cannot reach the Dask scheduler at {address}") and reason in err
    assert not (tmp_path / "p.npz").exists()


def test_address_without_a_cluster_backend_is_refused(tmp_path, capsys):
    pytest.importorskip("cma")
    with pytest.raises(SystemExit) as exit_:
        train_es.main(["--generations", "1", "--address", "127.0.0.1:8786",
                       "--out", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err == ("error: --address is for the dask and ray "
                                             "backends, not 'process'\n")


def test_ray_trains_the_same_policy_bit_for_bit_as_local_processes():
    pytest.importorskip("cma")
    pytest.importorskip("ray", reason="ray is not installed: pip install 'pymunk-bot[ray]'")
    if os.environ.get("PYMUNK_BOT_TEST_RAY") != "1":
        pytest.skip("Ray's servers listen on every interface (see tests/sweep), so it runs only "
                    "when asked for: PYMUNK_BOT_TEST_RAY=1")
    on_ray = train_es.train(None, backend="ray", workers=2, progress=False, **SHORT)[0]
    local = train_es.train(None, backend="process", workers=2, progress=False, **SHORT)[0]
    assert np.array_equal(on_ray, local)


@pytest.mark.parametrize("argv, message", [
    (["--minutes", "0"], "error: --minutes must be a number of minutes in (0, 10080] (got 0.0)"),
    (["--minutes", "nan"], "error: --minutes must be a number of minutes in (0, 10080] (got nan)"),
    (["--generations", "0"], "error: --generations must be in [1, 100000] (got 0)"),
    (["--generations", "1", "--backend", "process", "--workers", "0"],
     "error: --workers must be in [1, 1024] (got 0)"),
])
def test_a_bad_budget_is_one_line_and_exit_2(tmp_path, capsys, argv, message):
    pytest.importorskip("cma")
    with pytest.raises(SystemExit) as exit_:
        train_es.main([*argv, "--out", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1 and err.startswith(message)
    assert not (tmp_path / "p.npz").exists()


# ------------------------------------------------------------------ every world family

FAMILIES = {"kind": "clutter,office,maze", "maps": ("maps/office.yaml",)}


def test_training_episodes_come_from_every_family():
    from pymunk_bot.envs import NavigationEnv

    env = NavigationEnv(**train_es.env_kwargs(train_es.TRAIN_WORLDS, True, True, **FAMILIES))
    seen = set()
    for seed in range(16):
        env.reset(seed=seed)
        world = env.sim.config.world
        seen.add("map" if world.map is not None else world.size)
    # each kind at its own default size, and the ROS map
    assert seen == {(12.0, 8.0), (16.0, 10.0), (8.4, 8.4), "map"}
    assert env.episode.task.guide is not None
    assert env.episode.time_limit == train_es.TRAIN_SECONDS


def test_a_run_over_every_family_records_guidance(tmp_path):
    pytest.importorskip("cma")
    theta, shapes, history = train_es.train(None, seed=0, popsize=4, episodes=4, workers=1,
                                            progress=False, generations=1, guided=True,
                                            **FAMILIES)
    assert len(history) == 1
    train_es.to_policy(theta, shapes, guided=True).save(tmp_path / "p.npz")
    from pymunk_bot.policy.files import load_policy

    assert load_policy(tmp_path / "p.npz").plan_guidance is not None


@pytest.mark.parametrize("argv, message", [
    (["--generate", "clutter,forest"], "error: --generate takes kinds from clutter, office, maze"),
    (["--maps", "nowhere.yaml"], "error: --maps: no such map file: nowhere.yaml"),
])
def test_bad_families_are_one_line_and_exit_2(tmp_path, capsys, argv, message):
    pytest.importorskip("cma")
    with pytest.raises(SystemExit) as exit_:
        train_es.main([*argv, "--generations", "1", "--out", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1 and err.startswith(message), err
    assert not (tmp_path / "p.npz").exists()
