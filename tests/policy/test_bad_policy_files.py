"""Policy files are untrusted input: a malformed, oversized or mismatched ``.npz`` or ``.onnx``
gets one line naming the file and the problem, exit 2, from `validate`, `run` and `evaluate`,
in bounded memory (the refusal comes from headers, before any array is read)."""
from __future__ import annotations

import io
import os
import resource
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from numpy.lib import format as npy_format

from pymunk_bot.cli import main
from pymunk_bot.policy.files import MAX_NPZ_BYTES, PolicyFileError, load_policy

pytest.importorskip("gymnasium")

BEAMS = 16
INPUTS = BEAMS + 8  # the observation of a diff-drive robot with 16 beams
ROOT = Path(__file__).resolve().parents[2]
ADDRESS_SPACE_LIMIT = 2**30  # [bytes] what a refusal may take, the interpreter included


def write_scenario(folder: Path, policy_name: str) -> Path:
    data = {"name": "bad_policy", "world": {"size": [6.0, 4.0], "duration": 1.0},
            "robots": [{"name": "r1", "pose": [1.0, 2.0, 0.0], "localization": "ground_truth",
                        "lidar": {"beams": BEAMS, "max_range": 5.0},
                        "controller": {"type": "policy", "path": policy_name},
                        "goal": {"position": [5.0, 2.1], "tolerance": 0.2}}]}
    path = folder / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def npy_header(shape: tuple[int, ...], descr: str = "<f8") -> bytes:
    out = io.BytesIO()
    npy_format.write_array_header_1_0(out, {"shape": shape, "fortran_order": False,
                                            "descr": descr})
    return out.getvalue()


def zeros_bomb(path: Path, inflated: int) -> None:
    """An .npz whose W0 of zeros deflates ``inflated`` bytes to a few megabytes."""
    columns = inflated // 8 // INPUTS
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as archive:
        with archive.open("W0.npy", "w", force_zip64=True) as stream:
            stream.write(npy_header((INPUTS, columns)))
            chunk, left = bytes(2**24), INPUTS * columns * 8
            while left > 0:
                stream.write(chunk[:left])
                left -= len(chunk)
        archive.writestr("b0.npy", npy_header((2,)) + bytes(16))


def commands(policy: Path, scenario: Path) -> dict[str, list[str]]:
    return {"validate": ["validate", str(scenario)],
            "run": ["run", str(scenario), "--headless"],
            "evaluate": ["evaluate", str(policy), str(scenario), "--episodes", "2"]}


def assert_one_line_exit_2(status: int, stderr: str, policy: Path, *words: str) -> None:
    lines = stderr.strip().splitlines()
    assert status == 2, stderr
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    assert policy.name in lines[0], lines[0]
    for word in words:
        assert word in lines[0], lines[0]


def run_in_process(capfd, argv: list[str]) -> tuple[int, str]:
    """Exit status and stderr (at the descriptor: what onnxruntime itself writes counts)."""
    status = main(argv)
    return status, capfd.readouterr().err


# ---------------------------------------------------------------------------------------- .npz
def plain_npy(path: Path) -> None:
    with path.open("wb") as file:
        np.save(file, np.zeros((INPUTS, 2)))


def huge_header(path: Path) -> None:
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("W0.npy", npy_header((10**6, 10**6)))
        archive.writestr("b0.npy", npy_header((2,)) + bytes(16))


def object_array(path: Path) -> None:
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("W0.npy", npy_header((INPUTS, 2), "|O") + bytes(8 * INPUTS * 2))
        archive.writestr("b0.npy", npy_header((2,)) + bytes(16))


@pytest.mark.parametrize("make, words", [
    (plain_npy, "a plain .npy array, not an .npz archive"),
    (huge_header, "claims the shape (1000000, 1000000)"),
    (object_array, "not real numbers"),
])
@pytest.mark.parametrize("command", ["validate", "run", "evaluate"])
def test_malformed_npz_is_one_line_exit_2(tmp_path, capfd, make, words, command):
    policy = tmp_path / "nav.npz"
    make(policy)
    argv = commands(policy, write_scenario(tmp_path, policy.name))[command]
    assert_one_line_exit_2(*run_in_process(capfd, argv), policy, words)


def test_an_npz_bomb_is_refused_from_its_zip_directory(tmp_path, monkeypatch):
    zeros_bomb(tmp_path / "nav.npz", 2 * MAX_NPZ_BYTES)
    assert (tmp_path / "nav.npz").stat().st_size < MAX_NPZ_BYTES / 50  # passes the file cap

    def no_reading(*args, **kwargs):
        raise AssertionError("an array was read before the limits were checked")

    monkeypatch.setattr("numpy.lib.format.read_array", no_reading)
    monkeypatch.setattr("numpy.lib._format_impl.read_array", no_reading)
    with pytest.raises(PolicyFileError, match=r"inflates to 128 MB \(at most 64 MB\)"):
        load_policy(tmp_path / "nav.npz")


@pytest.fixture(scope="module")
def bomb(tmp_path_factory) -> Path:
    """The fuzzer's case: a 9 MB .npz of 2 GiB inflated."""
    path = tmp_path_factory.mktemp("bomb") / "nav.npz"
    zeros_bomb(path, 2**31)
    return path


def limit_address_space() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE_LIMIT, ADDRESS_SPACE_LIMIT))


@pytest.mark.parametrize("command", ["validate", "evaluate"])
def test_an_npz_bomb_is_refused_within_1_gb(bomb, tmp_path, command):
    scenario = write_scenario(tmp_path, str(bomb))
    out = subprocess.run([sys.executable, "-m", "pymunk_bot",
                          *commands(bomb, scenario)[command]],
                         capture_output=True, text=True, timeout=300,
                         preexec_fn=limit_address_space,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert_one_line_exit_2(out.returncode, out.stderr, bomb, "inflates to 2048 MB")


# ---------------------------------------------------------------------------------------- .onnx
def onnx_model(path: Path, inputs: list, weight_rows: int = INPUTS, weight_type=np.float32,
               output_type: int | None = None, output_shape: list | None = None,
               nan: bool = False) -> None:
    """``action = obs @ W`` (+ the second input, if there is one; ``nan``: sqrt(-1 - |.|))."""
    onnx = pytest.importorskip("onnx")
    from onnx import TensorProto, helper, numpy_helper

    inits = [numpy_helper.from_array(np.zeros((weight_rows, 2), weight_type), "W"),
             numpy_helper.from_array(np.ones(1, np.float32), "one")]
    nodes = [helper.make_node("MatMul", ["obs", "W"], ["m"])]
    if len(inputs) > 1:
        nodes.append(helper.make_node("Add", ["m", inputs[1].name], ["action"]))
    elif nan:
        nodes += [helper.make_node("Abs", ["m"], ["a"]), helper.make_node("Add", ["a", "one"], ["p"]),
                  helper.make_node("Neg", ["p"], ["n"]), helper.make_node("Sqrt", ["n"], ["action"])]
    else:
        nodes.append(helper.make_node("Identity", ["m"], ["action"]))
    output = helper.make_tensor_value_info("action", output_type or TensorProto.FLOAT,
                                           output_shape or [None, 2])
    graph = helper.make_graph(nodes, "policy", inputs, [output], inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, str(path))


def onnx_cases():
    onnx = pytest.importorskip("onnx")
    t, value = onnx.TensorProto, onnx.helper.make_tensor_value_info
    return {
        "dynamic width 30": (lambda p: onnx_model(p, [value("obs", t.FLOAT, [None, "width"])],
                                                  weight_rows=30),
                             "fails on observations of 24 numbers"),
        "float64 input": (lambda p: onnx_model(p, [value("obs", t.DOUBLE, [None, INPUTS])],
                                               weight_type=np.float64, output_type=t.DOUBLE),
                          "input 'obs' is tensor(double)"),
        "rank-3 input": (lambda p: onnx_model(p, [value("obs", t.FLOAT, [None, 1, INPUTS])],
                                              output_shape=[None, 1, 2]),
                         "rank 3"),
        "second input": (lambda p: onnx_model(p, [value("obs", t.FLOAT, [None, INPUTS]),
                                                  value("state", t.FLOAT, [None, 2])]),
                         "takes 2 inputs (obs, state)"),
    }


@pytest.mark.parametrize("case", ["dynamic width 30", "float64 input", "rank-3 input",
                                  "second input"])
@pytest.mark.parametrize("command", ["validate", "run", "evaluate"])
def test_an_onnx_model_that_does_not_fit_is_one_line_exit_2(tmp_path, capfd, case, command):
    pytest.importorskip("onnxruntime")
    make, words = onnx_cases()[case]
    policy = tmp_path / "nav.onnx"
    make(policy)
    argv = commands(policy, write_scenario(tmp_path, policy.name))[command]
    assert_one_line_exit_2(*run_in_process(capfd, argv), policy, words)


def test_evaluate_reports_a_nan_action_in_one_line(tmp_path, capfd):
    pytest.importorskip("onnxruntime")
    from onnx import TensorProto, helper

    policy = tmp_path / "nav.onnx"
    onnx_model(policy, [helper.make_tensor_value_info("obs", TensorProto.FLOAT, [None, INPUTS])],
               nan=True)
    argv = commands(policy, write_scenario(tmp_path, policy.name))["evaluate"]
    assert_one_line_exit_2(*run_in_process(capfd, argv), policy, "[nan nan]", "seed 0",
                           "not finite")
