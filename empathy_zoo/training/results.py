"""The per-run result file (schema 1): what a run did, episode by episode, written atomically."""

from __future__ import annotations

import datetime as _dt
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import read_json, write_json_atomic
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.names import check_path_name
from empathy_zoo.provenance import git_commit, package_version
from empathy_zoo.training.result_schema import SCHEMA, check_result

__all__ = ["SCHEMA", "result_path", "build_result", "write_result", "read_result"]

RUNS_DIR = "runs"


def result_path(out_dir: Path, run_id: str) -> Path:
    """Where the result file of ``run_id`` lives (a ``run_id`` that is no file name raises ``ValueError``)."""
    return Path(out_dir) / RUNS_DIR / f"{check_path_name(run_id, 'run id')}.json"


def empty_columns() -> dict[str, list]:
    return {"episode_end_step": [], **{name: [] for name in METRIC_NAMES}}


def build_result(
    spec: Any, train: dict[str, list], evaluations: list[dict[str, Any]], wall_time_s: float, memory: dict[str, int]
) -> dict[str, Any]:
    """The result document of one finished run."""
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
        "version": package_version(),
        "commit": git_commit(),
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }


def write_result(out_dir: Path, result: dict[str, Any]) -> Path:
    return write_json_atomic(result_path(out_dir, result["run_id"]), result)


def read_result(path: Path) -> dict[str, Any]:
    """Read a result file; a corrupted or malformed one raises ``ValueError`` naming it (and the field)."""
    return check_result(read_json(path), path)
