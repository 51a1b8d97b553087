"""The runner: trains a sweep's runs, ensemble by ensemble, here or on Ray.

``train_runs(specs, out_dir)`` groups the runs into ensembles (same env, method family and
shared settings), skips the runs whose result file exists, resumes an ensemble from its
checkpoint, and writes one result file per run, atomically, when it finishes. A run's numbers
depend only on its own spec: its seed drives its networks, exploration, replay sampling and
environments, so it gives the same result alone or beside other runs.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import check_output_dir, remove_stale_temp_files
from empathy_zoo.training.ensemble import train_ensemble
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.ray_backend import check_ray_address, import_ray, train_with_ray
from empathy_zoo.training.progress import QueueDrain, QueueReporter, SweepProgress
from empathy_zoo.result_file import RUNS_DIR, check_one_experiment_per_label, read_result, result_path
from empathy_zoo.training.resume import CHECKPOINT_DIR, plan_ensembles
from empathy_zoo.training.spec import RunSpec

__all__ = ["RunnerOptions", "train_runs", "CHECKPOINT_DIR"]


def train_runs(
    specs: Sequence[RunSpec], out_dir: str | Path, options: RunnerOptions = RunnerOptions(),
    on_result: Callable[[dict[str, Any]], None] | None = None, on_note: Callable[[str], None] | None = None,
) -> list[Path]:
    """Train every run not finished yet; returns the result files of all ``specs``.

    ``out_dir`` is checked first (created, written to): one that cannot hold the results raises
    ``ValueError`` before any training starts. Checkpointed ensembles resume as they were
    (:mod:`empathy_zoo.training.resume`); what is resumed, restarted or removed, and the temporary
    files of writes killed mid-way that are removed, is said through ``on_note`` (default: printed
    to stderr). ``on_result`` gets every result of ``specs`` written here."""
    note = on_note or _print_note
    out_dir = Path(out_dir)
    ids = [s.run_id for s in specs]
    duplicates = sorted({i for i in ids if ids.count(i) > 1})
    if duplicates:
        raise ValueError(f"the same run is listed twice: {duplicates}")
    if options.workers < 1:
        raise ValueError(f"workers must be positive, got {options.workers}")
    if options.max_parallel_runs < 1:
        raise ValueError(f"max_parallel_runs must be positive, got {options.max_parallel_runs}")
    if options.backend not in ("local", "ray"):
        raise ValueError(f"unknown backend {options.backend!r}; choose 'local' or 'ray'")
    if options.backend == "ray":
        if not import_ray().is_initialized():  # (missing Ray, or no cluster there, is said before anything is written)
            check_ray_address(options.address)
    check_one_experiment_per_label(
        [*_finished_runs(out_dir), *((s.variant or s.env, s.display_label(), s.run_id, f"run {s.run_id}") for s in specs)]
    )
    local_checkpoints = options.backend == "local" and options.checkpoint_interval > 0
    check_output_dir(out_dir, (RUNS_DIR, *((CHECKPOINT_DIR,) if local_checkpoints else ())))
    stale = [path for sub in ("", RUNS_DIR, CHECKPOINT_DIR) for path in remove_stale_temp_files(out_dir / sub)]
    if stale:
        note(f"removed {len(stale)} temporary file(s) of writes killed mid-way (e.g. {stale[0]})")
    todo = [s for s in specs if not result_path(out_dir, s.run_id).exists()]
    chunks = plan_ensembles(todo, out_dir, options.max_parallel_runs, note)
    wanted = {s.run_id for s in todo}
    if on_result is not None:  # (a resumed ensemble may finish runs not asked for here)
        given, on_result = on_result, lambda result: given(result) if result["run_id"] in wanted else None
    progress = SweepProgress([(len(chunk), chunk[0].steps) for chunk in chunks], enabled=options.progress)
    try:
        if options.backend == "ray":  # (the tasks report nothing: the sweep bar counts finished runs' steps)
            train_with_ray(chunks, out_dir, options, _counting(on_result, progress))
        elif options.workers == 1 or len(chunks) <= 1:
            for index, chunk in enumerate(chunks):
                for result in train_ensemble(chunk, out_dir, options, report=progress.update, ensemble=index):
                    if on_result is not None:
                        on_result(result)
        else:
            _train_in_processes(chunks, out_dir, options, on_result, progress)
    finally:
        progress.close()
    return [result_path(out_dir, s.run_id) for s in specs]


def _counting(
    on_result: Callable[[dict[str, Any]], None] | None, progress: SweepProgress
) -> Callable[[dict[str, Any]], None]:
    def counted(result: dict[str, Any]) -> None:
        progress.sweep.update(result["steps"])
        if on_result is not None:
            on_result(result)

    return counted


def _print_note(text: str) -> None:
    print(f"empathy-zoo: {text}", file=sys.stderr, flush=True)


def _finished_runs(out_dir: Path) -> list[tuple[str, str, str, str]]:
    """``(table env, label, run id, path)`` of every result file in ``out_dir`` (each one checked)."""
    runs = []
    for path in sorted((out_dir / RUNS_DIR).glob("*.json")) if (out_dir / RUNS_DIR).is_dir() else []:
        if not path.name.startswith("."):
            result = read_result(path)
            runs.append((result.get("variant") or result["env"], result["method_label"], result["run_id"], str(path)))
    return runs


def _exit_with_parent(parent: int) -> None:
    """In a worker: end this process if the sweep's process goes away (killed, not interrupted),
    so no orphan keeps training and writing checkpoints beside a restarted sweep."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(2.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="exit-with-parent").start()


def _train_in_processes(
    chunks: list[list[RunSpec]], out_dir: Path, options: RunnerOptions,
    on_result: Callable[[dict[str, Any]], None] | None, progress: SweepProgress,
) -> None:
    """Spread ensembles over ``options.workers`` processes (one torch thread each by default);
    their progress comes back through a queue and is drawn here."""
    context = multiprocessing.get_context("spawn")
    workers = min(options.workers, len(chunks))
    manager = context.Manager() if options.progress else None
    drain = QueueDrain(manager.Queue(), progress) if manager is not None else None
    reporter = QueueReporter(drain.source) if drain is not None else None
    try:
        with ProcessPoolExecutor(workers, mp_context=context, initializer=_exit_with_parent,
                                 initargs=(os.getpid(),)) as pool:
            futures = [
                pool.submit(train_ensemble, chunk, out_dir, replace(options, workers=1, threads=options.threads or 1),
                            True, reporter, i)
                for i, chunk in enumerate(chunks)
            ]
            try:
                for future in as_completed(futures):
                    for result in future.result():
                        if on_result is not None:
                            on_result(result)
            except BaseException:
                for future in futures:
                    future.cancel()
                raise
    finally:
        if drain is not None:
            drain.stop()
            manager.shutdown()


