"""Trained navigation policies read from files: a plain MLP in ``.npz``, or an ONNX model.

An ``.npz`` MLP holds ``W0, b0, W1, b1, ...``, ``W_i`` of shape (inputs, outputs) and ``b_i`` of
shape (outputs,): ``x = tanh(x @ W_i + b_i)`` for every layer but the last,
``action = clip(x @ W_last + b_last, -1, 1)``, in float64; a policy trained with plan-guided
goal features also holds ``plan_guidance``, its settings as numbers
(:meth:`~pymunk_bot.config.controllers.PlanGuidanceConfig.as_array`), so that whoever runs it
turns the guidance on (:func:`guidance_for`); a policy trained on the ``crowd_state``
observation (:mod:`pymunk_bot.policy.crowd_io`) holds ``crowd_state``, the number of humans it
sees, so that whoever runs it builds that observation (:func:`observation_for`). An ONNX model (what Stable-Baselines3
and PyTorch export) takes a float32 batch of observations (its first input) and returns
actions (its first output), clipped to [-1, 1]; it runs on onnxruntime (the ``onnx`` extra).
The observation and the action are :mod:`pymunk_bot.policy.io`'s.

Policy files are untrusted input: an ``.npz`` is bounded from its zip directory and array
headers before any array is read (:mod:`pymunk_bot.policy.npz_bounded`), an ONNX model's inputs and
outputs are checked when it loads, and :func:`check_runs_on` tries a policy on one zero
observation of a robot's size before a run or an evaluation starts.
"""
from __future__ import annotations

import io
import re
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from pymunk_bot.config.guidance import PlanGuidanceConfig
from pymunk_bot.policy.crowd_io import MAX_HUMANS_OBSERVED
from pymunk_bot.policy.npz_bounded import NpzError, first_line, read_npz
from pymunk_bot.outcomes.results import write_atomic

MAX_POLICY_BYTES = 256 * 2**20  # an ONNX file larger than this is a mistake
MAX_NPZ_BYTES = 64 * 2**20  # an .npz larger than this, on disk or inflated, is a mistake
MAX_LAYERS = 64
ONNX_FLOAT_TYPES = ("tensor(float)", "tensor(double)", "tensor(float16)")  # action outputs
_NAME = re.compile(r"^([Wb])(\d+)$")
GUIDANCE_ARRAY = "plan_guidance"  # an .npz MLP's record of its plan guidance settings
CROWD_ARRAY = "crowd_state"  # an .npz MLP's record of the humans its crowd observation holds
ONNX_INSTALL = "pip install 'pymunk-bot[onnx]'"


class PolicyFileError(ValueError):
    """A policy file that cannot be used: missing, malformed, or of the wrong size."""


class Policy(Protocol):
    """What a policy file gives: observation rows in, clipped actions out."""

    inputs: int | None  # observation length it takes (None: the file does not say)
    outputs: int | None  # action length it gives (None: the file does not say)
    records_guidance: bool  # the file says whether it was trained with plan guidance
    plan_guidance: PlanGuidanceConfig | None  # what it was trained with (None: without)
    crowd_humans: int | None  # humans of the crowd_state observation it was trained on
    # (None: the LiDAR observation, or an ONNX file, which records nothing)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Actions (n x outputs, float64, in [-1, 1]) of observations (n x inputs, float32)."""
        ...


class MlpPolicy:
    """A multi-layer perceptron: tanh hidden layers, a linear output clipped to [-1, 1]."""

    records_guidance = True

    def __init__(self, weights: list[np.ndarray], biases: list[np.ndarray],
                 plan_guidance: PlanGuidanceConfig | None = None,
                 crowd_humans: int | None = None) -> None:
        self.plan_guidance = plan_guidance  # what its observations were trained with
        # the crowd_state observation's humans it was trained on (None: the LiDAR observation)
        self.crowd_humans = crowd_humans
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
            arrays = read_npz(path, 2 * MAX_LAYERS + 1, MAX_NPZ_BYTES)
        except NpzError as exc:
            raise PolicyFileError(f"not a readable .npz file: {exc}") from None
        guidance = None
        if GUIDANCE_ARRAY in arrays:
            try:
                guidance = PlanGuidanceConfig.from_array(arrays.pop(GUIDANCE_ARRAY).reshape(-1))
            except ValueError as exc:
                raise PolicyFileError(f"array '{GUIDANCE_ARRAY}': {first_line(exc)}") from None
        humans = None
        if CROWD_ARRAY in arrays:
            record = arrays.pop(CROWD_ARRAY).reshape(-1)
            if record.size != 1 or not (1 <= record[0] <= MAX_HUMANS_OBSERVED) or (
                    record[0] != int(record[0])):
                raise PolicyFileError(f"array '{CROWD_ARRAY}' must hold one whole number of "
                                      f"humans in [1, {MAX_HUMANS_OBSERVED}] (got "
                                      f"{np.array2string(record[:4])})")
            humans = int(record[0])
        numbered: dict[str, dict[int, np.ndarray]] = {"W": {}, "b": {}}
        for name, array in arrays.items():
            match = _NAME.match(name)
            if match is None:
                raise PolicyFileError(f"unexpected array '{name}' (an MLP holds W0, b0, W1, "
                                      f"b1, ... and maybe {GUIDANCE_ARRAY}, {CROWD_ARRAY})")
            numbered[match.group(1)][int(match.group(2))] = array
        count = len(numbered["W"])
        for kind in ("W", "b"):
            if sorted(numbered[kind]) != list(range(count)):
                raise PolicyFileError(f"the arrays must be W0..W{count - 1} and b0..b{count - 1} "
                                      f"(got {sorted(arrays)})")
        return cls([numbered["W"][i] for i in range(count)],
                   [numbered["b"][i] for i in range(count)], guidance, humans)

    def save(self, path: str | Path) -> None:
        """Write the MLP as ``.npz`` (atomically: a reader never sees half a file)."""
        arrays: dict[str, Any] = {}
        for i, (w, b) in enumerate(zip(self.weights, self.biases)):
            arrays[f"W{i}"], arrays[f"b{i}"] = w, b
        if self.plan_guidance is not None:
            arrays[GUIDANCE_ARRAY] = np.array(self.plan_guidance.as_array())
        if self.crowd_humans is not None:
            arrays[CROWD_ARRAY] = np.array([self.crowd_humans])
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
    """An ONNX model run by onnxruntime on the CPU (it does not record plan guidance: the
    scenario's or the env's ``plan_guidance`` decides)."""

    records_guidance = False
    plan_guidance: PlanGuidanceConfig | None = None
    crowd_humans: int | None = None

    def __init__(self, path: str | Path) -> None:
        try:
            import onnxruntime
        except ImportError:
            raise PolicyFileError(f"ONNX policies need onnxruntime: {ONNX_INSTALL}") from None
        options = onnxruntime.SessionOptions()
        options.intra_op_num_threads = 1  # one robot's small net: threads cost more than they give
        options.log_severity_level = 4  # fatal only: a refusal is reported in one line, by us
        try:
            self.session = onnxruntime.InferenceSession(str(path), options,
                                                        providers=["CPUExecutionProvider"])
        except Exception as exc:  # onnxruntime raises its own exception types
            raise PolicyFileError(f"not a usable ONNX model ({first_line(exc)})") from None
        inputs, outputs = self.session.get_inputs(), self.session.get_outputs()
        if len(inputs) != 1:
            raise PolicyFileError(f"the model takes {len(inputs)} inputs "
                                  f"({', '.join(i.name for i in inputs)}); a policy takes one, "
                                  "the observation batch")
        first = inputs[0]
        if first.type != "tensor(float)":
            raise PolicyFileError(f"the model's input '{first.name}' is {first.type}; a policy "
                                  "takes float32 observations (tensor(float))")
        if len(first.shape) != 2:
            raise PolicyFileError(f"the model's input '{first.name}' has shape {first.shape} "
                                  f"(rank {len(first.shape)}); a policy takes (batch, "
                                  "observation), rank 2")
        if isinstance(first.shape[0], int) and first.shape[0] != 1:
            raise PolicyFileError(f"the model's input '{first.name}' has a fixed batch of "
                                  f"{first.shape[0]}; a policy sees one observation at a time "
                                  "(export the batch axis as dynamic or 1)")
        if not outputs or outputs[0].type not in ONNX_FLOAT_TYPES:
            raise PolicyFileError("the model's first output must be float actions (got "
                                  f"{outputs[0].type if outputs else 'no output'})")
        self.input_name = first.name
        self.inputs = _last_dim(first.shape)
        self.outputs = _last_dim(outputs[0].shape)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Actions (n x outputs, float64, clipped to [-1, 1]) of observations (n x inputs),
        run as a float32 batch; PolicyFileError if onnxruntime refuses them."""
        batch = np.asarray(obs, dtype=np.float32).reshape(-1, obs.shape[-1])
        try:
            out = np.asarray(self.session.run(None, {self.input_name: batch})[0],
                             dtype=np.float64)
        except Exception as exc:  # onnxruntime raises its own exception types
            raise PolicyFileError(f"the model fails on observations of {batch.shape[1]} "
                                  f"numbers ({first_line(exc)})") from None
        return np.clip(out.reshape(batch.shape[0], -1), -1.0, 1.0)


def _last_dim(shape: Any) -> int | None:
    """The size of a model's last axis, if the model fixes it."""
    last = shape[-1] if shape else None
    return last if isinstance(last, int) and last > 0 else None


def check_runs_on(policy: Policy, inputs: int, outputs: int) -> None:
    """PolicyFileError unless the policy maps one observation of ``inputs`` numbers (all zero)
    to an action of ``outputs`` numbers: what a model whose sizes are dynamic does is known
    only by running it (a NaN action is not refused here: a run reports it as it happens)."""
    action = policy.act(np.zeros((1, inputs), dtype=np.float32))
    if action.shape != (1, outputs):
        raise PolicyFileError(f"gives {action.size} numbers for an observation of {inputs}; "
                              f"the robot takes {outputs}")


def guidance_for(policy: Policy, setting: PlanGuidanceConfig | bool | None
                 ) -> PlanGuidanceConfig | None:
    """The plan guidance a policy runs with, given a scenario's ``plan_guidance`` (None: as
    the file records; True: on, with the file's settings or the defaults; False: off;
    settings: these). PolicyFileError if the setting contradicts what the file records."""
    recorded = policy.plan_guidance
    if setting is None:
        return recorded
    if policy.records_guidance and (recorded is None) != (setting is False):
        raise PolicyFileError(guidance_mismatch(recorded is not None))
    if setting is False:
        return None
    if setting is True:
        return recorded or PlanGuidanceConfig()
    return setting


def check_guidance(policy: Policy, guidance: PlanGuidanceConfig | None) -> None:
    """PolicyFileError if the policy records that it was trained with plan guidance and the
    env has none, or the reverse."""
    if policy.records_guidance and (policy.plan_guidance is None) != (guidance is None):
        raise PolicyFileError(guidance_mismatch(policy.plan_guidance is not None))


def guidance_mismatch(trained_with: bool) -> str:
    """Why a policy trained with (or without) plan guidance cannot run the other way."""
    if trained_with:
        return ("was trained with plan guidance (its goal features come from a path; the file "
                f"records '{GUIDANCE_ARRAY}'): run it with plan guidance on")
    return ("was trained without plan guidance (its goal features are the final goal's): run "
            "it with plan_guidance off (false)")


def observation_for(policy: Policy, setting: str | None) -> str:
    """The observation a policy runs on, given a scenario's or a command's ``observation``
    (None: as the file records, "lidar" for a file that records nothing). PolicyFileError if
    the setting contradicts what the file records."""
    recorded = "crowd_state" if policy.crowd_humans is not None else "lidar"
    if setting is None:
        return recorded
    if policy.records_guidance and setting != recorded:
        raise PolicyFileError(observation_mismatch(recorded))
    return setting


def check_observation(policy: Policy, observation: str) -> None:
    """PolicyFileError if the policy records that it was trained on another observation than
    ``observation`` ("lidar" or "crowd_state")."""
    observation_for(policy, observation)


def observation_mismatch(recorded: str) -> str:
    """Why a policy trained on one observation cannot run on the other."""
    if recorded == "crowd_state":
        return (f"was trained on the crowd_state observation (the humans' true states; the "
                f"file records '{CROWD_ARRAY}'): run it with observation crowd_state")
    return ("was trained on the LiDAR observation (the file records no "
            f"'{CROWD_ARRAY}'): run it with observation lidar")


def load_policy(path: str | Path) -> MlpPolicy | OnnxPolicy:
    """The policy in ``path`` (``.npz`` or ``.onnx``); PolicyFileError if it cannot be used."""
    file = Path(path)
    if file.suffix not in (".npz", ".onnx"):
        raise PolicyFileError(f"a policy file is .npz or .onnx (got '{file.name}')")
    if not file.is_file():
        raise PolicyFileError(f"no such file '{file}'")
    limit = MAX_NPZ_BYTES if file.suffix == ".npz" else MAX_POLICY_BYTES
    if file.stat().st_size > limit:
        raise PolicyFileError(f"'{file}' is larger than {limit // 2**20} MB")
    return MlpPolicy.load(file) if file.suffix == ".npz" else OnnxPolicy(file)
