"""Writing the per-run result file (its format and reading it: :mod:`empathy_zoo.result_file`)."""

from __future__ import annotations

import datetime as _dt
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.result_file import SCHEMA, result_path
from empathy_zoo.training.fingerprint import run_fingerprint

__all__ = ["build_result", "write_result", "empty_columns"]


def empty_columns() -> dict[str, list]:
    return {"episode_end_step": [], **{name: [] for name in METRIC_NAMES}}


def build_result(
    spec: Any, train: dict[str, list], evaluations: list[dict[str, Any]], wall_time_s: float, memory: dict[str, int]
) -> dict[str, Any]:
    """The result document of one finished run, with the fingerprint of the code that made it
    (``version``, ``commit``, ``plugin_sha256``: :mod:`empathy_zoo.training.fingerprint`)."""
    config = spec.config()
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
        **run_fingerprint(spec).fields(),
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }


def write_result(out_dir: Path, result: dict[str, Any]) -> Path:
    return write_json_atomic(result_path(out_dir, result["run_id"]), result)
