"""Writing the per-run result file (its format and reading it: :mod:`empathy_zoo.result_file`)."""

from __future__ import annotations

import datetime as _dt
import hashlib
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import write_bytes_atomic, write_json_atomic
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.result_file import PRICE_COLUMN, SCHEMA, result_path
from empathy_zoo.training.fingerprint import run_fingerprint

__all__ = ["KEPT_AGENT", "ResultWriteError", "build_result", "stored", "write_result", "empty_columns"]

KEPT_AGENT = "_agent_file"
"""Key of a result document on its way to :func:`write_result`: the ``(suffix, bytes)`` of its
agent file (:func:`empathy_zoo.agent_file.agent_bytes`), written beside it and never stored."""


def empty_columns(priced: bool = False) -> dict[str, list]:
    """The ``train`` columns of a run with no episode yet: the end step and every metric, and,
    where ``priced`` (its reward transform prices costs when sampled), the price of its cost after
    each episode (:data:`~empathy_zoo.result_file.PRICE_COLUMN`, the Lagrangian method's λ)."""
    return {"episode_end_step": [], **{name: [] for name in METRIC_NAMES}, **({PRICE_COLUMN: []} if priced else {})}


def build_result(
    spec: Any,
    train: dict[str, list],
    evaluations: list[dict[str, Any]],
    wall_time_s: float,
    memory: dict[str, int],
    agent: tuple[str, bytes] | None = None,
    update_kernel: str | None = None,
) -> dict[str, Any]:
    """The result document of one finished run, with the fingerprint of the code that made it
    (``version``, ``commit``, ``plugin_sha256`` and the learner's ``update_kernel``, ``None`` for a
    learner without a choice: :mod:`empathy_zoo.training.fingerprint`) and the
    name and SHA-256 of its agent file, whose ``(suffix, bytes)`` it carries to :func:`write_result`
    as :data:`KEPT_AGENT` (``agent`` is ``None`` when the method keeps none)."""
    config = spec.config()
    kept = None if agent is None else {"file": spec.run_id + agent[0], "sha256": hashlib.sha256(agent[1]).hexdigest()}
    return {
        "schema": SCHEMA,
        "run_id": spec.run_id,
        "env": spec.env,
        "variant": config["variant"],
        "method": spec.method,
        "method_label": config["label"],
        "seed": spec.seed,
        "config": config,
        "steps": spec.steps,
        "train": train,
        "eval": evaluations,
        "memory_bytes": memory,
        "wall_time_s": round(float(wall_time_s), 3),
        **run_fingerprint(spec, update_kernel).fields(),
        "agent": kept,
        **({KEPT_AGENT: agent} if agent is not None else {}),
        "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
    }


def stored(result: dict[str, Any]) -> dict[str, Any]:
    """``result`` as its file stores it (without the agent file's bytes it may carry)."""
    return {key: value for key, value in result.items() if key != KEPT_AGENT}


class ResultWriteError(OSError):
    """A result file (or the agent file beside it) could not be written (a full disk, a directory
    removed); the message (:attr:`strerror`) names the file, and ``errno`` is the failed write's."""

    def __str__(self) -> str:
        return self.strerror or super().__str__()


def write_result(out_dir: Path, result: dict[str, Any]) -> Path:
    """Write ``result``'s agent file (when it carries one), then the result file itself, each
    atomically: a result file never names an agent file that is not there. A write that fails
    raises :class:`ResultWriteError` naming the file (nothing half-written is left)."""
    document = dict(result)
    agent = document.pop(KEPT_AGENT, None)
    path = result_path(out_dir, document["run_id"])
    target = path
    try:
        if agent is not None:
            suffix, data = agent
            target = path.with_name(document["run_id"] + suffix)
            write_bytes_atomic(target, data)
            target = path
        return write_json_atomic(path, document)
    except ResultWriteError:
        raise
    except OSError as error:
        raise ResultWriteError(error.errno, f"cannot write {target} ({error.strerror or error})") from error
