"""`controller: {type: policy}`: the env's observation and action scaling, bit for bit; bad
policy files refused with one line."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import pymunk_bot as pb
from pymunk_bot.config.guidance import PlanGuidanceConfig
from pymunk_bot.policy.files import MlpPolicy, PolicyFileError, load_policy

gym = pytest.importorskip("gymnasium")

from pymunk_bot.envs import NavigationEnv  # noqa: E402
from command import pymunk_bot

BEAMS = 16


def random_mlp(rng, inputs=BEAMS + 8, hidden=8, outputs=2, forward=0.6) -> MlpPolicy:
    return MlpPolicy([rng.normal(0, 0.5, (inputs, hidden)), rng.normal(0, 0.5, (hidden, outputs))],
                     [rng.normal(0, 0.1, hidden), np.array([forward, 0.0][:outputs])])


def scenario(policy_path, beams=BEAMS, localization="ground_truth", **robot_keys) -> dict:
    """A box in the way of a robot with a noisy LiDAR; the policy drives it."""
    robot = {"name": "r1", "pose": [1.0, 2.0, 0.0], "localization": localization,
             "lidar": {"beams": beams, "max_range": 5.0, "noise_std": 0.02},
             "controller": {"type": "policy", "path": str(policy_path)},
             "goal": {"position": [5.0, 2.1], "tolerance": 0.2}, **robot_keys}
    return {"name": "policy_box", "world": {"size": [6.0, 4.0], "duration": 15.0},
            "obstacles": [{"type": "box", "center": [3.0, 2.2], "size": [0.5, 0.5]}],
            "robots": [robot], "expect": {"r1": {"max_collisions": 0}}}


def test_npz_mlp_is_the_documented_formula(tmp_path):
    rng = np.random.default_rng(1)
    policy = random_mlp(rng)
    policy.save(tmp_path / "p.npz")
    loaded = load_policy(tmp_path / "p.npz")
    x = rng.uniform(-1, 1, (3, BEAMS + 8)).astype(np.float32)
    w0, b0, w1, b1 = policy.weights[0], policy.biases[0], policy.weights[1], policy.biases[1]
    expected = np.clip(np.tanh(x.astype(np.float64) @ w0 + b0) @ w1 + b1, -1, 1)
    np.testing.assert_array_equal(loaded.act(x), expected)
    assert loaded.inputs == BEAMS + 8 and loaded.outputs == 2


@pytest.mark.parametrize("localization, pose_source, guided", [
    ("ground_truth", "ground_truth", None), ("odometry", "odometry", None),
    ("ground_truth", "ground_truth", "file"), ("odometry", "odometry", "scenario")])
def test_controller_drives_exactly_as_the_env_steps(tmp_path, localization, pose_source, guided):
    # guided: plan guidance recorded in the policy file, or set by the scenario's key
    policy = random_mlp(np.random.default_rng(7))
    guidance = PlanGuidanceConfig(replan_period=0.3) if guided else None
    if guided:  # "scenario": the file records the defaults, the scenario's key overrides them
        policy.plan_guidance = guidance if guided == "file" else PlanGuidanceConfig()
    policy.save(tmp_path / "p.npz")
    data = scenario(tmp_path / "p.npz", localization=localization)
    if guided:  # a crate off the map, that the LiDAR sees: replans around it
        data["obstacles"].append({"type": "box", "center": [4.2, 1.5], "size": [0.4, 0.4],
                                  "movable": True})
    if guided == "scenario":
        data["robots"][0]["controller"]["plan_guidance"] = {"replan_period": 0.3}
    env = NavigationEnv(data, pose_source=pose_source, plan_guidance=guidance)
    obs, info = env.reset(seed=3)
    stepped = []
    for _ in range(120):
        obs, _, terminated, truncated, _ = env.step(policy.act(obs[None])[0])
        stepped.append(env.sim.robots["r1"].pose)
        if terminated or truncated:
            break
    sim = pb.Simulation.from_dict(data, seed=info["sim_seed"])
    driven = []
    for _ in stepped:
        for _ in range(env.episode.steps_per_action):
            sim.step()
        driven.append(sim.robots["r1"].pose)
    assert len(stepped) > 20
    np.testing.assert_array_equal(np.array(driven), np.array(stepped))  # bit for bit
    if guided:
        guide = sim.robots["r1"].controller.guide
        assert guide is not None and guide.plans >= 2  # it replanned, as the env's did
        # the env observes once more, after the last step, than the controller has computed
        assert env.episode.task.guide.plans - guide.plans in (0, 1)
        unguided = NavigationEnv(data, pose_source=pose_source)
        obs, _ = unguided.reset(seed=3)
        for _ in range(20):
            obs, *_ = unguided.step(policy.act(obs[None])[0])
        assert not np.array_equal(unguided.sim.robots["r1"].pose, stepped[19])  # it matters


def test_the_controller_stops_at_the_goal(tmp_path):
    # A policy that ignores the LiDAR and steers to the goal bearing: W maps sin(bearing) to omega.
    inputs = BEAMS + 8
    w = np.zeros((inputs, 2))
    w[BEAMS + 5, 1] = 2.0
    MlpPolicy([w], [np.array([0.8, 0.0])]).save(tmp_path / "p.npz")
    data = scenario(tmp_path / "p.npz")
    data["obstacles"] = []
    sim = pb.Simulation.from_dict(data, seed=0)
    sim.run(12.0)
    result = sim.result()["robots"]["r1"]
    assert result["goal_reached"] and result["controller_status"] == "arrived"
    assert np.hypot(*(sim.robots["r1"].pose[:2] - [5.0, 2.1])) < 0.3  # stopped there


def write_scenario(tmp_path, data) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("make, words", [
    (lambda d: None, "no such file"),
    (lambda d: np.savez(d / "p.npz", W0=np.zeros((BEAMS + 8, 2))), "b0"),
    (lambda d: np.savez(d / "p.npz", W0=np.full((BEAMS + 8, 2), np.nan), b0=np.zeros(2)), "NaN"),
    (lambda d: (d / "p.npz").write_text("not a zip"), "not a readable .npz"),
    (lambda d: random_mlp(np.random.default_rng(0), inputs=36 + 8).save(d / "p.npz"),
     "takes 44 inputs, but a robot with 16 LiDAR beams gives 24"),
])
def test_bad_policy_files_are_one_line_exit_2(tmp_path, make, words):
    make(tmp_path)
    path = write_scenario(tmp_path, scenario("p.npz"))  # relative to the scenario's folder
    out = pymunk_bot("validate", path)
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "robots[0].controller" in lines[0] and words in lines[0]
    assert "Traceback" not in out.stderr


def test_shipped_policy_scenario_runs_from_the_cli(tmp_path):
    out = pymunk_bot("run", "policy_clutter", "--headless", "--out", tmp_path / "r.json")
    assert out.returncode == 0, out.stderr
    result = yaml.safe_load((tmp_path / "r.json").read_text())
    assert result["robots"]["r1"]["goal_reached"] and result["robots"]["r1"]["collisions"] == 0


# ---------------------------------------------------------------------------- ONNX
def onnx_mlp(policy: MlpPolicy, path: Path, nan: bool = False) -> None:
    """The same MLP as an ONNX graph (float32); ``nan``: its output is sqrt(-1 - |y|)."""
    onnx = pytest.importorskip("onnx")
    from onnx import TensorProto, helper, numpy_helper

    nodes, inits, x = [], [], "obs"
    layers = len(policy.weights)
    for i, (w, b) in enumerate(zip(policy.weights, policy.biases)):
        inits += [numpy_helper.from_array(w.astype(np.float32), f"W{i}"),
                  numpy_helper.from_array(b.astype(np.float32), f"b{i}")]
        nodes += [helper.make_node("MatMul", [x, f"W{i}"], [f"m{i}"]),
                  helper.make_node("Add", [f"m{i}", f"b{i}"], [f"y{i}"])]
        x = f"y{i}"
        if i < layers - 1:
            nodes.append(helper.make_node("Tanh", [x], [f"h{i}"]))
            x = f"h{i}"
    if nan:
        inits.append(numpy_helper.from_array(np.array([1.0], np.float32), "one"))
        nodes += [helper.make_node("Abs", [x], ["a"]), helper.make_node("Add", ["a", "one"], ["p"]),
                  helper.make_node("Neg", ["p"], ["n"]), helper.make_node("Sqrt", ["n"], ["nan"])]
        x = "nan"
    nodes.append(helper.make_node("Identity", [x], ["action"]))
    graph = helper.make_graph(
        nodes, "mlp", [helper.make_tensor_value_info("obs", TensorProto.FLOAT,
                                                     [None, policy.inputs])],
        [helper.make_tensor_value_info("action", TensorProto.FLOAT, [None, policy.outputs])],
        inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, str(path))


def test_onnx_policy_acts_as_its_npz_twin(tmp_path):
    pytest.importorskip("onnxruntime")
    policy = random_mlp(np.random.default_rng(2))
    onnx_mlp(policy, tmp_path / "p.onnx")
    loaded = load_policy(tmp_path / "p.onnx")
    assert loaded.inputs == BEAMS + 8 and loaded.outputs == 2
    x = np.random.default_rng(3).uniform(-1, 1, (4, BEAMS + 8)).astype(np.float32)
    np.testing.assert_allclose(loaded.act(x), policy.act(x), atol=1e-5)
    policy.save(tmp_path / "p.npz")
    poses = []
    for name in ("p.onnx", "p.npz"):
        sim = pb.Simulation.from_dict(scenario(tmp_path / name), seed=0)
        sim.run(3.0)
        poses.append(sim.robots["r1"].pose)
    assert np.hypot(*(poses[0][:2] - [1.0, 2.0])) > 0.2  # it drives, as its twin does
    np.testing.assert_allclose(poses[0], poses[1], atol=0.01)


def test_nan_output_fails_the_run_with_the_reason(tmp_path):
    pytest.importorskip("onnxruntime")
    onnx_mlp(random_mlp(np.random.default_rng(2)), tmp_path / "p.onnx", nan=True)
    path = write_scenario(tmp_path, scenario("p.onnx"))
    out = pymunk_bot("run", path, "--headless", "--duration", "1", "--out", tmp_path / "r.json")
    assert out.returncode == 1, out.stderr
    robot = yaml.safe_load((tmp_path / "r.json").read_text())["robots"]["r1"]
    assert robot["controller_status"] == "failed" and "not 2 finite numbers" in \
        robot["controller_message"]
    assert robot["distance"] == 0.0  # it never moved


def test_missing_onnxruntime_names_the_install_command(tmp_path, monkeypatch):
    (tmp_path / "p.onnx").write_bytes(b"\x08\x08")
    monkeypatch.setitem(sys.modules, "onnxruntime", None)
    with pytest.raises(PolicyFileError, match=r"pip install 'pymunk-bot\[onnx\]'"):
        load_policy(tmp_path / "p.onnx")
