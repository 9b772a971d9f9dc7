"""Trained navigation policies read from files: a plain MLP in ``.npz``, or an ONNX model.

An ``.npz`` MLP holds ``W0, b0, W1, b1, ...``, ``W_i`` of shape (inputs, outputs) and ``b_i`` of
shape (outputs,): ``x = tanh(x @ W_i + b_i)`` for every layer but the last,
``action = clip(x @ W_last + b_last, -1, 1)``, in float64. An ONNX model (what Stable-Baselines3
and PyTorch export) takes a float32 batch of observations (its first input) and returns
actions (its first output), clipped to [-1, 1]; it runs on onnxruntime (the ``onnx`` extra).
The observation and the action are :mod:`pymunk_bot.policy.io`'s.
"""
from __future__ import annotations

import io
import re
import zipfile
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from pymunk_bot.outcomes.results import write_atomic

MAX_POLICY_BYTES = 256 * 2**20  # a policy file larger than this is a mistake
MAX_LAYERS = 64
_NAME = re.compile(r"^([Wb])(\d+)$")
ONNX_INSTALL = "pip install 'pymunk-bot[onnx]'"


class PolicyFileError(ValueError):
    """A policy file that cannot be used: missing, malformed, or of the wrong size."""


class Policy(Protocol):
    """What a policy file gives: observation rows in, clipped actions out."""

    inputs: int | None  # observation length it takes (None: the file does not say)
    outputs: int | None  # action length it gives (None: the file does not say)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Actions (n x outputs, float64, in [-1, 1]) of observations (n x inputs, float32)."""
        ...


class MlpPolicy:
    """A multi-layer perceptron: tanh hidden layers, a linear output clipped to [-1, 1]."""

    def __init__(self, weights: list[np.ndarray], biases: list[np.ndarray]) -> None:
        if not weights or len(weights) != len(biases) or len(weights) > MAX_LAYERS:
            raise PolicyFileError(f"an MLP needs 1 to {MAX_LAYERS} layers, a bias for each "
                                  f"weight matrix (got {len(weights)} W and {len(biases)} b)")
        self.weights = [np.asarray(w, dtype=np.float64) for w in weights]
        self.biases = [np.asarray(b, dtype=np.float64) for b in biases]
        for i, (w, b) in enumerate(zip(self.weights, self.biases)):
            if w.ndim != 2 or b.shape != (w.shape[1],):
                raise PolicyFileError(f"W{i} must be (inputs, outputs) and b{i} (outputs,) "
                                      f"(got {w.shape} and {b.shape})")
            if i and w.shape[0] != self.weights[i - 1].shape[1]:
                raise PolicyFileError(f"W{i} takes {w.shape[0]} inputs but layer {i - 1} gives "
                                      f"{self.weights[i - 1].shape[1]}")
            if not (np.isfinite(w).all() and np.isfinite(b).all()):
                raise PolicyFileError(f"W{i} or b{i} holds a NaN or infinite number")
        self.inputs: int | None = self.weights[0].shape[0]
        self.outputs: int | None = self.weights[-1].shape[1]

    @classmethod
    def load(cls, path: str | Path) -> "MlpPolicy":
        """Read an ``.npz`` MLP; PolicyFileError says what is wrong with it."""
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {name: data[name] for name in data.files}
        except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
            raise PolicyFileError(f"not a readable .npz file ({exc})") from None
        numbered: dict[str, dict[int, np.ndarray]] = {"W": {}, "b": {}}
        for name, array in arrays.items():
            match = _NAME.match(name)
            if match is None:
                raise PolicyFileError(f"unexpected array '{name}' (an MLP holds W0, b0, W1, "
                                      "b1, ...)")
            if not np.issubdtype(array.dtype, np.number):
                raise PolicyFileError(f"{name} is not numeric (dtype {array.dtype})")
            numbered[match.group(1)][int(match.group(2))] = array
        count = len(numbered["W"])
        for kind in ("W", "b"):
            if sorted(numbered[kind]) != list(range(count)):
                raise PolicyFileError(f"the arrays must be W0..W{count - 1} and b0..b{count - 1} "
                                      f"(got {sorted(arrays)})")
        return cls([numbered["W"][i] for i in range(count)],
                   [numbered["b"][i] for i in range(count)])

    def save(self, path: str | Path) -> None:
        """Write the MLP as ``.npz`` (atomically: a reader never sees half a file)."""
        arrays: dict[str, Any] = {}
        for i, (w, b) in enumerate(zip(self.weights, self.biases)):
            arrays[f"W{i}"], arrays[f"b{i}"] = w, b
        data = io.BytesIO()
        np.savez(data, **arrays)
        write_atomic(path, data.getvalue())

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Actions (n x outputs, float64, clipped to [-1, 1]) of observations (n x inputs)."""
        x = np.asarray(obs, dtype=np.float64)
        for w, b in zip(self.weights[:-1], self.biases[:-1]):
            x = np.tanh(x @ w + b)
        return np.clip(x @ self.weights[-1] + self.biases[-1], -1.0, 1.0)


class OnnxPolicy:
    """An ONNX model run by onnxruntime on the CPU."""

    def __init__(self, path: str | Path) -> None:
        try:
            import onnxruntime
        except ImportError:
            raise PolicyFileError(f"ONNX policies need onnxruntime: {ONNX_INSTALL}") from None
        options = onnxruntime.SessionOptions()
        options.intra_op_num_threads = 1  # one robot's small net: threads cost more than they give
        options.log_severity_level = 3
        try:
            self.session = onnxruntime.InferenceSession(str(path), options,
                                                        providers=["CPUExecutionProvider"])
        except Exception as exc:  # onnxruntime raises its own exception types
            raise PolicyFileError(f"not a usable ONNX model ({str(exc).splitlines()[0][:200]})") \
                from None
        first = self.session.get_inputs()[0]
        self.input_name = first.name
        self.inputs = _last_dim(first.shape)
        self.outputs = _last_dim(self.session.get_outputs()[0].shape)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Actions (n x outputs, float64, clipped to [-1, 1]) of observations (n x inputs),
        run as a float32 batch."""
        batch = np.asarray(obs, dtype=np.float32).reshape(-1, obs.shape[-1])
        out = np.asarray(self.session.run(None, {self.input_name: batch})[0], dtype=np.float64)
        return np.clip(out.reshape(batch.shape[0], -1), -1.0, 1.0)


def _last_dim(shape: Any) -> int | None:
    """The size of a model's last axis, if the model fixes it."""
    last = shape[-1] if shape else None
    return last if isinstance(last, int) and last > 0 else None


def load_policy(path: str | Path) -> MlpPolicy | OnnxPolicy:
    """The policy in ``path`` (``.npz`` or ``.onnx``); PolicyFileError if it cannot be used."""
    file = Path(path)
    if file.suffix not in (".npz", ".onnx"):
        raise PolicyFileError(f"a policy file is .npz or .onnx (got '{file.name}')")
    if not file.is_file():
        raise PolicyFileError(f"no such file '{file}'")
    if file.stat().st_size > MAX_POLICY_BYTES:
        raise PolicyFileError(f"'{file}' is larger than {MAX_POLICY_BYTES // 2**20} MB")
    return MlpPolicy.load(file) if file.suffix == ".npz" else OnnxPolicy(file)
