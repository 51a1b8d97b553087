"""Checkpoints a killed run resumes from: ``torch.save`` of plain data, loaded with
``weights_only=True``; written atomically; a corrupted one raises and is never overwritten.

A checkpoint may come from anyone, so it is read as data and checked before anything of it is
used: read through the bounded reader (a regular file of at most
:data:`~empathy_zoo.limits.MAX_CHECKPOINT_BYTES`), every tensor dense, of a numeric dtype, and every
floating one of its learner finite (Adam's means of squared gradients finite or ``+inf``,
:data:`SQUARES`); :func:`save_checkpoint` writes no checkpoint that this reading refuses (runs that
diverged: :class:`DivergedError`); an ensemble's checkpoint (:func:`check_checkpoint_keys`) also has every
counter within its range and consistent with the others and with the settings of its runs (from
the list of runs beside it, when there is one): its elapsed time within a result file's
``wall_time_s`` (:data:`~empathy_zoo.limits.MAX_WALL_TIME_S`), every log entry and evaluation of its
type and within what one episode of its runs can hold (the result reader's bounds), every random
state one numpy makes, the learner's counters and copies of its networks consistent with its
networks and its updates, and the environments' state what its runs would hold
(:mod:`empathy_zoo.training.checkpoint_state`). Numbers are compared exactly: an ``int`` of any size
is never made a float. Before ``torch.load`` reads it, its zip directory is read: at most
:data:`MAX_MEMBERS` records of ``torch.save``, stored as they are, declaring no more bytes than
the file holds (:func:`~empathy_zoo.safe_data.torch_zip_problem`: nothing is decompressed); an
ensemble's holds no other key than :data:`KEYS`. Anything else is refused as corrupted, naming the
file and the field (:func:`corrupted`)."""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import torch

from empathy_zoo.atomic import write_with_atomic
from empathy_zoo.bounded_read import open_data, read_json_data
from empathy_zoo.environments import DEFAULT_ARGUMENTS
from empathy_zoo.limits import MAX_CYCLES, MAX_SEED, MAX_STEPS, MAX_WALL_TIME_S
from empathy_zoo.metrics import INTEGER_METRICS, METRIC_NAMES, METRIC_RANGES
from empathy_zoo.result_file import PRICE_COLUMN, episode_bounds
from empathy_zoo.safe_data import from_safe, to_safe, torch_zip_problem, zip_members
from empathy_zoo.training.checkpoint_state import ForgedState, bit_generator_problem, check_vector, number, rng_states, shown

__all__ = [
    "save_checkpoint",
    "load_checkpoint",
    "check_checkpoint_keys",
    "corrupted",
    "to_safe",
    "from_safe",
    "CheckpointError",
    "DIVERGED_FIX",
    "DivergedError",
    "check_writable",
    "diverged_runs",
    "RUNS_LIST_SUFFIX",
    "KEYS",
    "MAX_MEMBERS",
    "runs_list_path",
]

FORMAT = 1
KEYS = ("format", "run_ids", "step", "elapsed", "learner", "vector", "obs", "logs", "evaluations", "rewards")
"""The keys an ensemble's checkpoint holds (:func:`check_checkpoint_keys` refuses any other)."""
MAX_MEMBERS = 1 << 18
"""Most members of a checkpoint's zip: ``torch.save`` writes a few records and one per tensor (an
ensemble's checkpoint holds a few dozen per learner, or per run of SB3's)."""
RUNS_LIST_SUFFIX = ".runs.json"
"""Suffix of the file beside a checkpoint that lists its runs' specs (:mod:`empathy_zoo.training.resume`)."""
TENSOR_DTYPES = frozenset(
    {
        torch.bool,
        torch.uint8,
        torch.uint16,
        torch.uint32,
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
ADAM_MOMENTS = ("exp_avg", "exp_avg_sq")
"""The lists of Adam's moments in a learner's optimiser state, each of the shapes of its networks."""
LOG_COLUMNS = ("episode_end_step", *METRIC_NAMES)
"""The columns of a run's training log in an ensemble's checkpoint (and :data:`PRICE_COLUMN`, the
price of its cost after each episode, for a run whose reward transform prices costs when sampled)."""


SAVED_KERNELS = ("numba", "torch")
"""The update kernels a learner's checkpoint may name (``learner.update_kernel``)."""

MESSAGE_CHARS = 300
"""Most characters of what was wrong that a refused checkpoint's message quotes."""


class CheckpointError(ValueError):
    """A checkpoint exists but cannot be used."""


class DivergedError(ValueError):
    """Runs diverged (a learner's weights or memories hold numbers that are no finite ones): nothing
    of them is written, neither a checkpoint (:func:`save_checkpoint`) nor a result; the message
    names the runs and what to do (:data:`DIVERGED_FIX`)."""


SQUARES = "the checkpoint['learner']['optimizer']['exp_avg_sq']"
"""Where a learner's checkpoint keeps Adam's means of squared gradients: a square that overflowed
float32 (a gradient past ≈ 1.8e19) is ``+inf`` there, a state Adam trains on from (its step for
that weight is 0 from then on, the weight finite), so a checkpoint holds it and is read back with it."""
NOT_FINITE = "holds a value that is no finite number"
"""What a checkpoint's tensor holds where its learner diverged (how its reader says it)."""
DIVERGED_FIX = "lower the learning rate (or change the settings that let it diverge) and train again"
"""What a refusal of diverged runs tells to do."""


def diverged_runs(run_ids: Any) -> str:
    """``run A`` or ``runs A, B``: the runs of ``run_ids`` (a list of run ids) as a refusal names
    them (``these runs`` where it is no list of strings)."""
    if not isinstance(run_ids, list) or not run_ids or not all(isinstance(run, str) for run in run_ids):
        return "these runs"
    return f"run {run_ids[0]}" if len(run_ids) == 1 else f"runs {', '.join(run_ids)}"


def save_checkpoint(path: Path, payload: dict[str, Any]) -> None:
    """Write ``payload`` to ``path`` atomically, streamed into the temporary file (no copy of the
    checkpoint is held in memory: an ensemble's replay memories are ≈ 1 GB in the paper profile).

    A payload :func:`load_checkpoint` would refuse is not written, and any earlier checkpoint at
    ``path`` is kept: a learner's tensor that holds a number that is no finite one raises
    :class:`DivergedError` naming the runs (``payload["run_ids"]``) and the tensor; another tensor
    it refuses, ``ValueError``. A write that fails (a full disk) raises ``OSError`` with its
    ``errno``, naming the checkpoint and saying whether an earlier one is kept (torch reports a
    failed write as a ``RuntimeError`` of its zip writer, the ``OSError`` in its context)."""
    check_writable(path, payload)
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


def check_writable(path: Path, payload: Mapping[str, Any]) -> None:
    """Refuse a checkpoint ``payload`` for ``path`` that :func:`load_checkpoint` would refuse (see
    :func:`save_checkpoint`, which calls it first), saying that any earlier checkpoint at ``path`` is
    kept; nothing is written."""
    problem = _payload_problem(payload)
    if problem:
        kept = f"the checkpoint {path} of an earlier step is kept" if path.exists() else "no checkpoint was written"
        if problem.endswith(NOT_FINITE):
            raise DivergedError(f"{diverged_runs(payload.get('run_ids'))} diverged: {problem}; {DIVERGED_FIX}; {kept}")
        raise ValueError(f"checkpoint {path} not written: {problem} (a checkpoint's reader refuses it); {kept}")


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
    with handle:
        try:
            size = os.fstat(handle.fileno()).st_size
            problem = torch_zip_problem(zip_members(handle, size, MAX_MEMBERS), size)
        except (ValueError, OSError) as error:
            problem = str(error)
        if problem:
            raise corrupted(path, problem)
        try:
            payload = torch.load(handle, map_location="cpu", weights_only=True)
        except Exception as error:  # torch raises many kinds for a damaged file
            raise corrupted(path, error) from error
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise CheckpointError(f"checkpoint {path} has an unknown format; delete or move it to restart")
    problem = _payload_problem(payload)
    if problem:
        raise corrupted(path, problem)
    return payload


def _payload_problem(payload: Mapping[str, Any]) -> str:
    """What is wrong with the first tensor of a checkpoint's ``payload`` that is wrong, and where
    (``""``: nothing): what :func:`load_checkpoint` refuses, and so what :func:`save_checkpoint`
    never writes."""
    for where, tensor in _tensors(payload, "the checkpoint"):
        problem = _tensor_problem(
            tensor, finite=where.startswith("the checkpoint['learner']"), overflow=where.startswith(SQUARES)
        )
        if problem:
            return f"{where} {problem}"
    return ""


def _tensors(value: Any, where: str) -> Iterator[tuple[str, torch.Tensor]]:
    """Every tensor in ``value`` (dicts and lists, any depth), with where it is."""
    if isinstance(value, torch.Tensor):
        yield where, value
    elif isinstance(value, dict):
        for key, item in value.items():
            yield from _tensors(item, f"{where}[{shown(key)}]")
    elif isinstance(value, (list, tuple)):
        for index, item in enumerate(value):
            yield from _tensors(item, f"{where}[{index}]")


def _tensor_problem(tensor: torch.Tensor, finite: bool, overflow: bool = False) -> str:
    """What is wrong with a tensor of a checkpoint (``""``: nothing); a floating one must be finite
    where ``finite`` (a learner's weights and memories), or, where ``overflow`` (Adam's mean of
    squared gradients, :data:`SQUARES`), finite or ``+inf``."""
    if tensor.layout != torch.strided or tensor.is_quantized:
        return f"is a {tensor.layout} tensor, not a dense one"
    if tensor.dtype not in TENSOR_DTYPES:
        return f"has dtype {tensor.dtype}"
    if finite and tensor.is_floating_point():
        bad = (
            bool(torch.isnan(tensor).any() or (tensor == -math.inf).any()) if overflow else not bool(torch.isfinite(tensor).all())
        )
        if bad:
            return NOT_FINITE
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
    its type and no other key (but ``format``; an ensemble's, those of :data:`KEYS`), and, for an
    ensemble's checkpoint (``run_ids``, ``step``, ``elapsed``, ``learner``, ``vector``, ``logs``,
    ``evaluations``), every value within its range and consistent with the
    settings of its runs (see the module page); else the :func:`corrupted` error naming what is
    missing or wrong."""
    missing = [key for key in keys if key not in payload]
    if missing:
        raise corrupted(path, f"it holds no {', '.join(map(repr, missing))}")
    wrong = [key for key, kind in keys.items() if isinstance(payload[key], bool) or not isinstance(payload[key], kind)]
    if wrong:
        raise corrupted(path, ", ".join(f"{shown(key)} is a {type(payload[key]).__name__}" for key in wrong))
    ensemble = {"run_ids", "step", "elapsed", "learner", "vector", "logs", "evaluations"} <= set(keys)
    known = {"format", *keys, *(KEYS if ensemble else ())}
    unknown = sorted(shown(key) for key in payload if key not in known)
    if unknown:
        raise corrupted(
            path, f"it holds a key {unknown[0]}, which no such checkpoint has (its keys are {', '.join(sorted(known))})"
        )
    if ensemble:
        _check_ensemble(path, payload)
    return payload


def _runs_settings(path: Path, run_ids: list[str]) -> dict[str, Any] | None:
    """The settings of checkpoint ``path``'s runs that bound what it may hold, from the list of
    runs beside it: ``steps``, ``eval_interval``, ``eval_episodes``, ``max_cycles``, ``cells``, the
    most each metric can be in an episode (``bounds``, the result reader's own), the environment
    and its arguments (``env``, ``env_kwargs``) and each run's ``seed``; ``None`` when there is
    no list, or it cannot tell them (the list is checked where it is read)."""
    try:
        records = read_json_data(runs_list_path(path), "list of runs")["runs"]
        shared, seeds = [], []
        for record in records:
            kwargs = {**DEFAULT_ARGUMENTS[record["env"]], **record["env_kwargs"]}
            shared.append(
                {
                    "steps": record["steps"],
                    "eval_interval": record["eval_interval"],
                    "eval_episodes": record["eval_episodes"],
                    "max_cycles": kwargs["max_cycles"],
                    "cells": kwargs["size"] ** 2,
                    "env": record["env"],
                    "env_kwargs": dict(record["env_kwargs"]),
                }
            )
            seeds.append(record["seed"])
        if len(records) != len(run_ids) or any(
            record.get("run_id", run_id) != run_id for record, run_id in zip(records, run_ids, strict=True)
        ):
            return None
        first = shared[0]
        if any(one != first for one in shared) or not all(number(seed, 0, MAX_SEED, whole=True) for seed in seeds):
            return None
        if not all(
            number(first[key], 1, whole=True) for key in ("steps", "eval_interval", "eval_episodes", "max_cycles", "cells")
        ):
            return None
        return {**first, "seeds": seeds, "bounds": episode_bounds(first["env"], first["env_kwargs"])}
    except (ValueError, OSError, KeyError, TypeError, IndexError, AttributeError):
        return None


def _check_ensemble(path: Path, payload: Mapping[str, Any]) -> None:
    """An ensemble's checkpoint (see the module page), else the :func:`corrupted` error."""
    ids = payload["run_ids"]
    if not ids or not all(isinstance(run_id, str) for run_id in ids):
        raise corrupted(path, "its run ids are no list of names")
    runs = _runs_settings(path, ids)
    step, steps = payload["step"], (runs["steps"] if runs else MAX_STEPS)
    if not 1 <= step <= steps:
        raise corrupted(path, f"its step {shown(step)} is not in [1, {steps:,}] (the runs' steps)")
    if not number(payload["elapsed"], 0, MAX_WALL_TIME_S):
        raise corrupted(
            path, f"elapsed is {shown(payload['elapsed'])}, no number of seconds in [0, {MAX_WALL_TIME_S:,}] (ten years)"
        )
    if not len(payload["logs"]) == len(payload["evaluations"]) == len(ids):
        counts = len(payload["logs"]), len(payload["evaluations"])
        raise corrupted(path, f"it holds the logs of {counts[0]} runs and the evaluations of {counts[1]}, not {len(ids)}")
    bounds = runs["bounds"] if runs else {"survival": MAX_CYCLES}
    for run, log in enumerate(payload["logs"]):
        _check_log(path, f"logs[{run}]", log, step, bounds)
    expected = _evaluation_steps(runs, step)
    for run, evaluations in enumerate(payload["evaluations"]):
        _check_evaluations(
            path, f"evaluations[{run}]", evaluations, step, expected, runs["eval_episodes"] if runs else None, bounds
        )
    for where, state in rng_states(payload, ""):
        problem = bit_generator_problem(state)
        if problem:
            raise corrupted(path, f"{where} {problem}")
    _check_learner(path, payload["learner"], step, len(ids))
    learner_seeds = payload["learner"].get("seeds")
    seeds = runs["seeds"] if runs else learner_seeds if isinstance(learner_seeds, list) else None
    try:
        check_vector(payload["vector"], payload.get("obs"), len(ids), runs, seeds)
    except ForgedState as error:
        raise corrupted(path, str(error)) from None


def _value_problem(value: Any, metric: str, high: float | None, whole: bool) -> bool:
    """Whether ``value`` is no value ``metric`` takes in an episode (an ``int`` where ``whole``),
    at most ``high`` (the run's own bound; ``None``: the metric's range)."""
    low, top = METRIC_RANGES[metric]
    return not number(value, low, top if high is None else high, whole)


def _check_log(path: Path, where: str, log: Any, step: int, bounds: Mapping[str, float | None]) -> None:
    columns = sorted(log) if isinstance(log, dict) else None
    if columns not in (sorted(LOG_COLUMNS), sorted((*LOG_COLUMNS, PRICE_COLUMN))) or not all(
        isinstance(c, list) for c in log.values()
    ):
        raise corrupted(path, f"{where} is no table of the columns {', '.join(LOG_COLUMNS)} (and {PRICE_COLUMN})")
    if len({len(column) for column in log.values()}) != 1:
        raise corrupted(path, f"{where} has columns of different lengths")
    ends = log["episode_end_step"]
    for i, end in enumerate(ends):
        if not number(end, (ends[i - 1] if i else 0) + 1, step, whole=True):
            raise corrupted(path, f"{where}['episode_end_step'][{i}] is {shown(end)}, no step after the one before and <= {step}")
    for metric in METRIC_NAMES:
        for i, value in enumerate(log[metric]):
            if _value_problem(value, metric, bounds.get(metric), metric in INTEGER_METRICS):
                raise corrupted(path, f"{where}[{metric!r}][{i}] is {shown(value)}, no {metric} of an episode")
    for i, survival in enumerate(log["survival"]):
        if survival > ends[i] - (ends[i - 1] if i else 0):
            raise corrupted(path, f"{where}['survival'][{i}] is {shown(survival)}, more than its episode's steps")
    for i, price in enumerate(log.get(PRICE_COLUMN, [])):
        if not number(price, 0):
            raise corrupted(path, f"{where}[{PRICE_COLUMN!r}][{i}] is {shown(price)}, no finite price >= 0")


def _evaluation_steps(runs: Mapping[str, Any] | None, step: int) -> list[int] | None:
    """The steps a run was evaluated at up to ``step`` (every ``eval_interval``, and the last)."""
    if runs is None:
        return None
    expected = list(range(runs["eval_interval"], step + 1, runs["eval_interval"]))
    return [*expected, step] if step == runs["steps"] and expected[-1:] != [step] else expected


def _check_evaluations(
    path: Path,
    where: str,
    evaluations: Any,
    step: int,
    expected: list[int] | None,
    episodes: int | None,
    bounds: Mapping[str, float | None],
) -> None:
    if not isinstance(evaluations, list):
        raise corrupted(path, f"{where} is no list of evaluations")
    for i, entry in enumerate(evaluations):
        if not isinstance(entry, dict) or sorted(entry) != sorted(("step", *METRIC_NAMES)):
            raise corrupted(path, f"{where}[{i}] is no table of step and {', '.join(METRIC_NAMES)}")
        at = entry["step"]
        before = evaluations[i - 1]["step"] if i else 0
        if not number(at, before + 1, step, whole=True):
            raise corrupted(path, f"{where}[{i}]['step'] is {shown(at)}, no step after {before} and <= {step}")
        for metric in METRIC_NAMES:
            values = entry[metric]
            count = episodes if episodes is not None else len(evaluations[0][metric])
            if not isinstance(values, list) or len(values) != count:
                raise corrupted(path, f"{where}[{i}][{metric!r}] is no list of {count} values")
            if any(_value_problem(value, metric, bounds.get(metric), False) for value in values):
                raise corrupted(path, f"{where}[{i}][{metric!r}] holds a value that is no {metric} of an episode")
    if expected is not None and [entry["step"] for entry in evaluations] != expected:
        raise corrupted(path, f"{where} holds evaluations at other steps than every eval_interval up to step {step}")


def _check_learner(path: Path, state: Mapping[str, Any], step: int, runs: int) -> None:
    """Empathic DQN's counters (and those of a learner keeping the same names) within their range
    and consistent with ``step`` and with each other: its updates as many as its optimiser's steps,
    its networks' copies (target, Adam's moments) of its networks' shapes, its replay memory's size
    and position those of one transition a step, its buffers of its runs and size."""
    env_steps, grad_steps = state.get("env_steps"), state.get("grad_steps")
    kernel = state.get("update_kernel")
    if kernel is not None and kernel not in SAVED_KERNELS:
        raise corrupted(path, f"learner.update_kernel is {shown(kernel)}, not one of {', '.join(SAVED_KERNELS)}")
    if "env_steps" in state and not number(env_steps, step, step, whole=True):
        raise corrupted(
            path, f"learner.env_steps is {shown(env_steps)}: its learner has taken other steps than its ensemble's {step}"
        )
    if "grad_steps" in state and not number(grad_steps, 0, step, whole=True):
        raise corrupted(path, f"learner.grad_steps is {shown(grad_steps)}, not in [0, {step}] (its updates in {step} steps)")
    _check_networks(path, state, runs)
    replay = state.get("replay")
    if isinstance(replay, dict) and {"size", "position"} <= set(replay):
        size, position = replay["size"], replay["position"]
        if not number(size, 1, step, whole=True) or not number(position, 0, size, whole=True):
            both = f"size {shown(size)} and position {shown(position)}"
            raise corrupted(path, f"learner.replay: {both} are not 0 <= position <= size <= step {step}")
        if "env_steps" in state and not (position == step % size if size < step else position in (0, size)):
            raise corrupted(path, f"learner.replay.position is {position}, not where {step} steps leave a memory of {size}")
        for key, buffer in replay.items():
            if isinstance(buffer, torch.Tensor) and (buffer.dim() < 2 or buffer.shape[:2] != (runs, size)):
                raise corrupted(path, f"learner.replay.{key} has shape {tuple(buffer.shape)}, not ({runs}, {size}, ...)")


def _check_networks(path: Path, state: Mapping[str, Any], runs: int) -> None:
    """A learner's copies of its networks of their shapes: the target networks those of its runs'
    (the first ``runs`` of ``online``), Adam's moments those of every network; and Adam's step
    count of each network its number of updates (``grad_steps``)."""
    online, optimizer = state.get("online"), state.get("optimizer")
    if not isinstance(online, list) or not online or not all(isinstance(p, torch.Tensor) and p.dim() for p in online):
        return
    optimizer = optimizer if isinstance(optimizer, dict) else {}
    every = [tuple(p.shape) for p in online]
    for name, copies, shapes in (
        ("target", state.get("target"), [(min(runs, shape[0]), *shape[1:]) for shape in every]),
        *((f"optimizer.{key}", optimizer.get(key), every) for key in ADAM_MOMENTS),
    ):
        if copies is None:
            continue  # (the learner's own load says what it misses)
        if not isinstance(copies, list) or len(copies) != len(shapes) or not all(isinstance(c, torch.Tensor) for c in copies):
            raise corrupted(path, f"learner.{name} is no list of {len(shapes)} tensors (one per network parameter)")
        for i, (copy, shape) in enumerate(zip(copies, shapes, strict=True)):
            if tuple(copy.shape) != shape:
                raise corrupted(path, f"learner.{name}[{i}] has shape {tuple(copy.shape)}, not {shape} (its networks')")
            if copy.dtype != torch.float32:
                raise corrupted(path, f"learner.{name}[{i}] has dtype {copy.dtype}, not torch.float32 (its networks')")
            if name == "optimizer.exp_avg_sq" and bool((copy < 0).any()):
                raise corrupted(path, f"learner.{name}[{i}] holds a negative value (Adam's mean of squared gradients)")
    for i, parameter in enumerate(online):
        if parameter.dtype != torch.float32:
            raise corrupted(path, f"learner.online[{i}] has dtype {parameter.dtype}, not torch.float32 (the suite's precision)")
    counts, updates = optimizer.get("steps"), state.get("grad_steps")
    if counts is None:
        return
    if not isinstance(counts, torch.Tensor) or tuple(counts.shape) != (every[0][0],):
        raise corrupted(path, f"learner.optimizer.steps is no tensor of ({every[0][0]},) step counts (one per network)")
    if isinstance(updates, int) and not bool(torch.all(counts.double() == float(updates))):
        raise corrupted(path, f"learner.optimizer.steps holds {counts.tolist()[:4]}, not its {updates} updates (grad_steps)")
