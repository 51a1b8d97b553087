"""Checkpoints a killed run resumes from: ``torch.save`` of plain data, loaded with
``weights_only=True``; written atomically; a corrupted one raises and is never overwritten.

A checkpoint may come from anyone, so it is read as data and checked before anything of it is
used: read through the bounded reader (a regular file of at most
:data:`~empathy_zoo.limits.MAX_CHECKPOINT_BYTES`), every tensor dense, of a numeric dtype, and every
floating one finite; an ensemble's checkpoint (:func:`check_checkpoint_keys`) also has every
counter within its range and consistent with the others and with the settings of its runs (from
the list of runs beside it, when there is one), every log entry and evaluation of its type and
range, every array of the environments of its shape and dtype, every cell on the grid. Anything
else is refused as corrupted, naming the file (:func:`corrupted`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import torch

from empathy_zoo.atomic import write_with_atomic
from empathy_zoo.bounded_read import open_data, read_json_data
from empathy_zoo.environments import DEFAULT_ARGUMENTS
from empathy_zoo.limits import MAX_STEPS
from empathy_zoo.metrics import INTEGER_METRICS, METRIC_NAMES, METRIC_RANGES
from empathy_zoo.result_file import PRICE_COLUMN
from empathy_zoo.safe_data import from_safe, to_safe

__all__ = [
    "save_checkpoint",
    "load_checkpoint",
    "check_checkpoint_keys",
    "corrupted",
    "to_safe",
    "from_safe",
    "CheckpointError",
    "RUNS_LIST_SUFFIX",
    "runs_list_path",
]

FORMAT = 1
RUNS_LIST_SUFFIX = ".runs.json"
"""Suffix of the file beside a checkpoint that lists its runs' specs (:mod:`empathy_zoo.training.resume`)."""
TENSOR_DTYPES = frozenset(
    {
        torch.bool,
        torch.uint8,
        torch.int8,
        torch.int16,
        torch.int32,
        torch.int64,
        torch.float16,
        torch.bfloat16,
        torch.float32,
        torch.float64,
    }
)
"""The dtypes a checkpoint's tensors may have."""
LOG_COLUMNS = ("episode_end_step", *METRIC_NAMES)
"""The columns of a run's training log in an ensemble's checkpoint (and :data:`PRICE_COLUMN`, the
price of its cost after each episode, for a run whose reward transform prices costs when sampled)."""


MESSAGE_CHARS = 300
"""Most characters of what was wrong that a refused checkpoint's message quotes."""


class CheckpointError(ValueError):
    """A checkpoint exists but cannot be used."""


def save_checkpoint(path: Path, payload: dict[str, Any]) -> None:
    """Write ``payload`` to ``path`` atomically, streamed into the temporary file (no copy of the
    checkpoint is held in memory: an ensemble's replay memories are ≈ 1 GB in the paper profile).

    A write that fails (a full disk) raises ``OSError`` with its ``errno``, naming the checkpoint
    and saying whether an earlier one is kept (torch reports a failed write as a ``RuntimeError``
    of its zip writer, the ``OSError`` in its context)."""
    try:
        write_with_atomic(path, lambda handle: torch.save({"format": FORMAT, **payload}, handle))
    except (OSError, RuntimeError) as error:
        cause = error if isinstance(error, OSError) else error.__context__
        if not isinstance(cause, OSError):  # (a torch error that is no failed write)
            raise
        kept = (
            f"the previous checkpoint {path} is kept: free space and run the same command again to resume from it"
            if path.exists()
            else "no earlier checkpoint was written: free space and run the same command again to start these runs again"
        )
        raise OSError(cause.errno, f"cannot write checkpoint {path} ({cause.strerror or cause}); {kept}") from error


def runs_list_path(checkpoint: Path) -> Path:
    """The list of runs beside ``checkpoint`` (``<name>.runs.json``)."""
    return checkpoint.with_name(checkpoint.stem + RUNS_LIST_SUFFIX)


def load_checkpoint(path: Path) -> dict[str, Any]:
    """Load a checkpoint through the bounded reader (streamed: it is not held twice in memory) and
    check every tensor in it (dense, of a dtype of :data:`TENSOR_DTYPES`, finite where floating);
    raises :class:`CheckpointError` naming the file when it is unusable."""
    try:
        handle = open_data(path, "checkpoint")
    except ValueError as error:
        raise corrupted(path, str(error)) from None
    try:
        with handle:
            payload = torch.load(handle, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises many kinds for a damaged file
        raise corrupted(path, error) from error
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise CheckpointError(f"checkpoint {path} has an unknown format; delete or move it to restart")
    for where, tensor in _tensors(payload, "the checkpoint"):
        problem = _tensor_problem(tensor, finite=where.startswith("the checkpoint['learner']"))
        if problem:
            raise corrupted(path, f"{where} {problem}")
    return payload


def _tensors(value: Any, where: str) -> Iterator[tuple[str, torch.Tensor]]:
    """Every tensor in ``value`` (dicts and lists, any depth), with where it is."""
    if isinstance(value, torch.Tensor):
        yield where, value
    elif isinstance(value, dict):
        for key, item in value.items():
            yield from _tensors(item, f"{where}[{key!r}]")
    elif isinstance(value, (list, tuple)):
        for index, item in enumerate(value):
            yield from _tensors(item, f"{where}[{index}]")


def _tensor_problem(tensor: torch.Tensor, finite: bool) -> str:
    """What is wrong with a tensor of a checkpoint (``""``: nothing); a floating one must be finite
    where ``finite`` (a learner's weights and memories)."""
    if tensor.layout != torch.strided or tensor.is_quantized:
        return f"is a {tensor.layout} tensor, not a dense one"
    if tensor.dtype not in TENSOR_DTYPES:
        return f"has dtype {tensor.dtype}"
    if finite and tensor.is_floating_point() and not bool(torch.isfinite(tensor).all()):
        return "holds a value that is no finite number"
    return ""


def corrupted(path: Path, error: BaseException | str) -> CheckpointError:
    """The error of checkpoint ``path``, unusable because of ``error`` (what was wrong in it), in one
    line: ``error``'s message with its line breaks made spaces, cut at :data:`MESSAGE_CHARS`."""
    why = error if isinstance(error, str) else f"{type(error).__name__}: {error}"
    why = " ".join(why.split())  # (one line: torch's messages span several)
    if len(why) > MESSAGE_CHARS:
        why = why[: MESSAGE_CHARS - 3] + "..."
    return CheckpointError(
        f"checkpoint {path} is corrupted or unreadable ({why}); "
        "it was left untouched: delete or move it to restart those runs from scratch"
    )


def check_checkpoint_keys(path: Path, payload: dict[str, Any], keys: dict[str, type | tuple[type, ...]]) -> dict[str, Any]:
    """``payload`` (checkpoint ``path`` as loaded) if it holds every key of ``keys`` with a value of
    its type and, for an ensemble's checkpoint (``run_ids``, ``step``, ``elapsed``, ``learner``,
    ``vector``, ``logs``, ``evaluations``), every value within its range and consistent with the
    settings of its runs (see the module page); else the :func:`corrupted` error naming what is
    missing or wrong."""
    missing = [key for key in keys if key not in payload]
    if missing:
        raise corrupted(path, f"it holds no {', '.join(map(repr, missing))}")
    wrong = [key for key, kind in keys.items() if isinstance(payload[key], bool) or not isinstance(payload[key], kind)]
    if wrong:
        raise corrupted(path, ", ".join(f"{key!r} is a {type(payload[key]).__name__}" for key in wrong))
    if {"run_ids", "step", "elapsed", "learner", "vector", "logs", "evaluations"} <= set(keys):  # (an ensemble's)
        _check_ensemble(path, payload)
    return payload


def _runs_settings(path: Path) -> dict[str, int] | None:
    """The settings of checkpoint ``path``'s runs that bound what it may hold (``steps``,
    ``eval_interval``, ``eval_episodes``, ``max_cycles``, ``cells``), from the list of runs beside
    it; ``None`` when there is none, or it cannot tell them (the list is checked where it is read)."""
    try:
        document = read_json_data(runs_list_path(path), "list of runs")
        records = document["runs"]
        settings = []
        for record in records:
            kwargs = {**DEFAULT_ARGUMENTS[record["env"]], **record["env_kwargs"]}
            settings.append(
                {
                    "steps": record["steps"],
                    "eval_interval": record["eval_interval"],
                    "eval_episodes": record["eval_episodes"],
                    "max_cycles": kwargs["max_cycles"],
                    "cells": kwargs["size"] ** 2,
                }
            )
    except (ValueError, OSError, KeyError, TypeError):
        return None
    if not settings or any(one != settings[0] for one in settings):
        return None
    first = settings[0]
    if not all(isinstance(value, int) and not isinstance(value, bool) and value >= 1 for value in first.values()):
        return None
    return first


def _check_ensemble(path: Path, payload: Mapping[str, Any]) -> None:
    """An ensemble's checkpoint (see the module page), else the :func:`corrupted` error."""
    ids = payload["run_ids"]
    if not ids or not all(isinstance(run_id, str) for run_id in ids):
        raise corrupted(path, "its run ids are no list of names")
    runs = _runs_settings(path)
    step, steps = payload["step"], (runs["steps"] if runs else MAX_STEPS)
    if not 1 <= step <= steps:
        raise corrupted(path, f"its step {step!r} is not in [1, {steps:,}] (the runs' steps)")
    if not math.isfinite(payload["elapsed"]) or payload["elapsed"] < 0:
        raise corrupted(path, f"its elapsed time {payload['elapsed']!r} is no finite number >= 0")
    if not len(payload["logs"]) == len(payload["evaluations"]) == len(ids):
        counts = len(payload["logs"]), len(payload["evaluations"])
        raise corrupted(path, f"it holds the logs of {counts[0]} runs and the evaluations of {counts[1]}, not {len(ids)}")
    max_cycles = runs["max_cycles"] if runs else None
    for run, log in enumerate(payload["logs"]):
        _check_log(path, f"logs[{run}]", log, step, max_cycles)
    expected = _evaluation_steps(runs, step)
    for run, evaluations in enumerate(payload["evaluations"]):
        _check_evaluations(
            path, f"evaluations[{run}]", evaluations, step, expected, runs["eval_episodes"] if runs else None, max_cycles
        )
    _check_learner(path, payload["learner"], step)
    _check_vector(path, payload["vector"], payload.get("obs"), len(ids), runs)


def _value_problem(value: Any, metric: str, max_cycles: int | None, whole: bool) -> bool:
    """Whether ``value`` is no value ``metric`` takes in an episode (an ``int`` where ``whole``)."""
    if isinstance(value, bool) or not isinstance(value, int if whole else (int, float)):
        return True
    low, high = METRIC_RANGES[metric]
    high = max_cycles if metric == "survival" else high
    return not math.isfinite(value) or value < low or (high is not None and value > high)


def _check_log(path: Path, where: str, log: Any, step: int, max_cycles: int | None) -> None:
    columns = sorted(log) if isinstance(log, dict) else None
    if columns not in (sorted(LOG_COLUMNS), sorted((*LOG_COLUMNS, PRICE_COLUMN))) or not all(
        isinstance(c, list) for c in log.values()
    ):
        raise corrupted(path, f"{where} is no table of the columns {', '.join(LOG_COLUMNS)} (and {PRICE_COLUMN})")
    if len({len(column) for column in log.values()}) != 1:
        raise corrupted(path, f"{where} has columns of different lengths")
    ends = log["episode_end_step"]
    for i, end in enumerate(ends):
        if isinstance(end, bool) or not isinstance(end, int) or not (ends[i - 1] if i else 0) < end <= step:
            raise corrupted(path, f"{where}['episode_end_step'][{i}] is {end!r}, no step after the one before and <= {step}")
    for metric in METRIC_NAMES:
        for i, value in enumerate(log[metric]):
            if _value_problem(value, metric, max_cycles, metric in INTEGER_METRICS):
                raise corrupted(path, f"{where}[{metric!r}][{i}] is {value!r}, no {metric} of an episode")
    for i, price in enumerate(log.get(PRICE_COLUMN, [])):
        if isinstance(price, bool) or not isinstance(price, (int, float)) or not math.isfinite(price) or price < 0:
            raise corrupted(path, f"{where}[{PRICE_COLUMN!r}][{i}] is {price!r}, no finite price >= 0")


def _evaluation_steps(runs: Mapping[str, int] | None, step: int) -> list[int] | None:
    """The steps a run was evaluated at up to ``step`` (every ``eval_interval``, and the last)."""
    if runs is None:
        return None
    expected = list(range(runs["eval_interval"], step + 1, runs["eval_interval"]))
    return expected + [step] if step == runs["steps"] and expected[-1:] != [step] else expected


def _check_evaluations(
    path: Path, where: str, evaluations: Any, step: int, expected: list[int] | None, episodes: int | None, max_cycles: int | None
) -> None:
    if not isinstance(evaluations, list):
        raise corrupted(path, f"{where} is no list of evaluations")
    for i, entry in enumerate(evaluations):
        if not isinstance(entry, dict) or sorted(entry) != sorted(("step", *METRIC_NAMES)):
            raise corrupted(path, f"{where}[{i}] is no table of step and {', '.join(METRIC_NAMES)}")
        at = entry["step"]
        before = evaluations[i - 1]["step"] if i else 0
        if isinstance(at, bool) or not isinstance(at, int) or not before < at <= step:
            raise corrupted(path, f"{where}[{i}]['step'] is {at!r}, no step after {before} and <= {step}")
        for metric in METRIC_NAMES:
            values = entry[metric]
            count = episodes if episodes is not None else len(evaluations[0][metric])
            if not isinstance(values, list) or len(values) != count:
                raise corrupted(path, f"{where}[{i}][{metric!r}] is no list of {count} values")
            if any(_value_problem(value, metric, max_cycles, False) for value in values):
                raise corrupted(path, f"{where}[{i}][{metric!r}] holds a value that is no {metric} of an episode")
    if expected is not None and [entry["step"] for entry in evaluations] != expected:
        raise corrupted(path, f"{where} holds evaluations at other steps than every eval_interval up to step {step}")


def _check_learner(path: Path, state: Mapping[str, Any], step: int) -> None:
    """Empathic DQN's counters (and those of a learner keeping the same names) within their range
    and consistent with ``step`` and with each other, its replay memory's size and position with
    its buffers."""
    env_steps, grad_steps = state.get("env_steps"), state.get("grad_steps")
    if "env_steps" in state and (isinstance(env_steps, bool) or env_steps != step):
        raise corrupted(path, f"its learner has taken {env_steps!r} steps, its ensemble {step}")
    if "grad_steps" in state and (isinstance(grad_steps, bool) or not isinstance(grad_steps, int) or not 0 <= grad_steps <= step):
        raise corrupted(path, f"its learner has made {grad_steps!r} updates in {step} steps")
    replay = state.get("replay")
    if isinstance(replay, dict) and {"size", "position"} <= set(replay):
        size, position = replay["size"], replay["position"]
        if not isinstance(size, int) or not isinstance(position, int) or not 0 <= position <= size <= step:
            raise corrupted(
                path, f"its replay memory's size {size!r} and position {position!r} are not 0 <= position <= size <= step {step}"
            )
        for key, buffer in replay.items():
            if isinstance(buffer, torch.Tensor) and (buffer.dim() < 2 or buffer.shape[1] != size):
                raise corrupted(path, f"its replay memory's {key!r} has shape {tuple(buffer.shape)}, not (runs, {size}, ...)")


def _check_vector(path: Path, saved: Any, obs: Any, runs: int, settings: Mapping[str, int] | None) -> None:
    """The environments' state: each array's shape and dtype, every cell on the grid, every clock
    within an episode, every floating value finite."""
    try:
        state, observations = from_safe(saved), from_safe(obs)
    except (ValueError, TypeError, KeyError, AttributeError) as error:
        raise corrupted(path, f"its environments' state cannot be read ({error})") from None
    engine = state.get("engine") if isinstance(state, dict) else None
    if not isinstance(engine, dict):
        raise corrupted(path, "it holds no state of its environments' engine")
    for key, array in engine.items():
        if isinstance(array, np.ndarray) and (array.ndim == 0 or array.shape[0] != runs):
            raise corrupted(path, f"its engine's {key!r} has shape {array.shape}, not ({runs}, ...) for its {runs} runs")
        if isinstance(array, np.ndarray) and array.dtype.kind == "f" and not np.isfinite(array).all():
            raise corrupted(path, f"its engine's {key!r} holds a value that is no finite number")
    for key, high in (
        ("cells", settings["cells"] - 1 if settings else None),
        ("t", settings["max_cycles"] if settings else None),
    ):
        array = engine.get(key)
        if not isinstance(array, np.ndarray) or array.dtype.kind not in "iu":
            raise corrupted(path, f"its engine's {key!r} is no array of whole numbers")
        if array.size and (array.min() < 0 or (high is not None and array.max() > high)):
            raise corrupted(path, f"its engine's {key!r} holds {array.min()} … {array.max()}, not within [0, {high}]")
    for name, array in (("observations", observations), ("the environments' observations", state.get("observations"))):
        if array is None:
            continue
        if not isinstance(array, np.ndarray) or array.dtype != np.float32 or array.ndim < 1 or array.shape[0] != runs:
            raise corrupted(path, f"its {name} are no float32 array of {runs} runs")
        if not np.isfinite(array).all():
            raise corrupted(path, f"its {name} hold a value that is no finite number")
