"""The per-run result file (schema 1): what a run did, episode by episode, written atomically."""

from __future__ import annotations

import datetime as _dt
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import read_json, write_json_atomic
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.names import check_path_name
from empathy_zoo.provenance import git_commit, package_version
from empathy_zoo.training.result_schema import SCHEMA, check_result

__all__ = [
    "SCHEMA", "RUNS_DIR", "result_path", "build_result", "write_result", "read_result", "experiment_of",
    "check_one_experiment_per_label",
]

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


def experiment_of(run_id: str) -> str:
    """The run id without its seed: the runs of one experiment (all but the seed equal) share it."""
    return run_id.rsplit("__s", 1)[0]


def check_one_experiment_per_label(runs: Iterable[tuple[str, str, str, str]]) -> None:
    """Raise ``ValueError`` when two of ``runs`` (``(table env, label, run id, where it is)``) share
    a table row, i.e. an env and a label, but come from different experiments: the leaderboard
    groups runs by env and label, so it would mix them (or count one seed twice)."""
    seen: dict[tuple[str, str], tuple[str, str, str]] = {}
    for env, label, run_id, where in runs:
        first = seen.setdefault((env, label), (experiment_of(run_id), run_id, where))
        if first[0] != experiment_of(run_id):
            raise ValueError(
                f"{where} and {first[2]} have the same label {label!r} on {env} but come from two experiments "
                f"(run ids {run_id} and {first[1]}: other settings); the tables could not tell them apart: give one "
                "its own label (train --label, or label in its sweep entry) or move one away"
            )
