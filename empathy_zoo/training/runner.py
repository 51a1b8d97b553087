"""The runner: trains a sweep's runs, ensemble by ensemble, here or on Ray.

``train_runs(specs, out_dir)`` groups the runs into ensembles (same env, method family and
shared settings), skips the runs whose result file exists (once it was made by this code),
resumes an ensemble from its checkpoint, and writes one result file per run, atomically, when it
finishes. A run's numbers
depend only on its own spec: its seed drives its networks, exploration, replay sampling and
environments, so it gives the same result alone or beside other runs.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager, suppress
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import PROBE_BYTES, check_output_dir, remove_stale_temp_files
from empathy_zoo.data_files import data_files
from empathy_zoo.evaluation_file import check_not_read_folder
from empathy_zoo.experiment.model import RunSpec, group_specs
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.names import check_no_links, check_replaceable
from empathy_zoo.output_lock import command_line, hold_output_dir
from empathy_zoo.result_file import AGENT_SUFFIXES, RUNS_DIR, check_one_experiment_per_label, result_path
from empathy_zoo.training.checkpoint import RUNS_LIST_SUFFIX, runs_list_path
from empathy_zoo.training.ensemble import train_ensemble
from empathy_zoo.training.fingerprint import code_changes, listing
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.preflight import check_before_training, largest_checkpoint_bytes
from empathy_zoo.training.progress import QueueDrain, QueueReporter, SweepProgress
from empathy_zoo.training.ray_backend import check_ray_address, import_ray, train_with_ray
from empathy_zoo.training.resume import CHECKPOINT_DIR, EnsemblePlan, checkpoint_path, survey_ensembles
from empathy_zoo.training.set_aside import SUPERSEDED_SUFFIX, set_aside, settle_superseded
from empathy_zoo.training.tracking import check_log_places, log_subdirs

__all__ = [
    "NOT_CHECKED_WITHOUT_WRITING",
    "RunnerOptions",
    "Stopped",
    "TrainingPlan",
    "check_file_places",
    "check_runs",
    "read_finished",
    "stopped_by_signals",
    "train_runs",
    "CHECKPOINT_DIR",
    "SUPERSEDED_SUFFIX",
    "STOP_SIGNALS",
    "exit_with_parent",
    "stop_workers",
]

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
"""The signals that stop a sweep while it trains, even in a process started with them ignored
(a job started with ``&`` by a script ignores SIGINT)."""
WORKER_STOP_S = 10.0
"""Seconds a worker process is given to end once terminated, before it is killed."""


class Stopped(KeyboardInterrupt):
    """A signal of :data:`STOP_SIGNALS` stopped the sweep (a ``KeyboardInterrupt``, so whatever
    cleans up after Ctrl-C cleans up after it too); :attr:`signum` is the signal."""

    def __init__(self, signum: int) -> None:
        super().__init__(f"stopped by {signal.Signals(signum).name}")
        self.signum = signum
        """The signal received."""


def train_runs(
    specs: Sequence[RunSpec],
    out_dir: str | Path,
    options: RunnerOptions = RunnerOptions(),
    on_result: Callable[[dict[str, Any]], None] | None = None,
    on_note: Callable[[str], None] | None = None,
    finished: dict[Path, RunResult] | None = None,
) -> list[Path]:
    """Train every run not finished yet; returns the result files of all ``specs``.

    ``out_dir`` is checked first (created, written to): one that cannot hold the results raises
    ``ValueError`` before any training starts. Checkpointed ensembles resume as they were
    (:mod:`empathy_zoo.training.resume`); what is resumed, restarted or removed, and the temporary
    files of writes killed mid-way that are removed, is said through ``on_note`` (default: printed
    to stderr). ``on_result`` gets every result of ``specs`` written here. ``finished`` is what
    :func:`read_finished` gave for ``out_dir`` when the caller has read it already (it is read
    here otherwise).

    A finished run is reused only when its result file was made by this code: this empathy-zoo
    version and, for a ``package.module:NAME`` method or fixed policy, the same source of that
    module (:mod:`empathy_zoo.training.fingerprint`). The recorded commit does not count: most
    commits do not touch a given method, so a new one alone does not make results stale. When
    some finished runs were made by other code, ``ValueError`` lists them and what changed, before
    anything is written, unless ``options.rerun_changed``: then they are retrained, their result
    files set aside as ``<run id>.json.superseded-<pid>-<mark>`` meanwhile
    (:mod:`empathy_zoo.training.set_aside`), each removed once its run's new
    result is written and put back if it is not (an error, Ctrl-C). A process killed outright
    leaves it set aside: that run is retrained by the next call that asks for it. Finished runs
    whose code cannot be told (files written before plug-in hashes were recorded, modules without
    a source file) are reused with a note, or retrained with ``rerun_changed``.

    While runs train, SIGINT or SIGTERM to this process (in its main thread) raises
    :class:`Stopped`, a ``KeyboardInterrupt``, even where the process was started with SIGINT
    ignored: worker processes are stopped, every result and checkpoint already written is kept, and
    the same call resumes from them."""
    note = on_note or _print_note
    out_dir = Path(out_dir)
    plan = check_runs(specs, out_dir, options, note, finished)
    redo, warnings, subdirs, room = plan.redo, plan.warnings, plan.subdirs, plan.room
    with hold_output_dir(out_dir, command_line(), note):
        made = list(
            dict.fromkeys(f for sub in subdirs for f in (*reversed((out_dir / sub).parents), out_dir / sub) if not f.exists())
        )
        check_output_dir(out_dir, subdirs, largest_file=room)  # (inside the lock: nothing made before it)
        try:
            ensembles = survey_ensembles(plan.todo, out_dir, options.max_parallel_runs, every_run=specs)  # (reads only)
            for warning in warnings:  # (said once everything before training has passed)
                note(warning)
            stale = [path for sub in ("", RUNS_DIR, CHECKPOINT_DIR) for path in remove_stale_temp_files(out_dir / sub)]
            if stale:
                note(f"removed {len(stale)} temporary file(s) of writes killed mid-way (e.g. {stale[0]})")
            settle_superseded(out_dir / RUNS_DIR)
            with set_aside(out_dir, redo), stopped_by_signals():
                _train_todo(ensembles, out_dir, options, on_result, note)
        except BaseException:
            for folder in reversed(made):  # (a call that stopped leaves no empty folder it made; one holding a file stays)
                with suppress(OSError):
                    folder.rmdir()
            raise
    return [result_path(out_dir, s.run_id) for s in specs]


@dataclass(frozen=True)
class TrainingPlan:
    """What :func:`check_runs` found: what :func:`train_runs` does once it holds the output directory."""

    redo: set[str]
    """The finished runs to retrain (made by other code, ``rerun_changed``)."""
    todo: list[RunSpec]
    """The runs to train: those without a result file, and ``redo``."""
    warnings: list[str]
    """What to say once every check has passed (:func:`~empathy_zoo.training.preflight.check_before_training`)."""
    subdirs: tuple[str, ...]
    """The folders of the output directory written to (results, checkpoints, logs)."""
    room: int
    """The bytes the largest file written there takes (a checkpoint's estimate, or a result's)."""


NOT_CHECKED_WITHOUT_WRITING = (
    "a probe file written to each output folder (only its permissions and free space were asked)",
    "the output directory's lock (another process training there)",
)
"""What :func:`train_runs` checks once it holds the output directory and :func:`check_runs` (with
:func:`empathy_zoo.atomic.check_output_places`) cannot without writing: a dry run says so."""


def check_runs(
    specs: Sequence[RunSpec],
    out_dir: Path,
    options: RunnerOptions,
    note: Callable[[str], None] | None = None,
    finished: Mapping[Path, RunResult] | None = None,
) -> TrainingPlan:
    """Every check :func:`train_runs` makes before it takes the output directory's lock, in its
    order, writing nothing: the same ``ValueError`` (one line naming the run, file or option). Runs
    listed twice and the options; the result files of ``out_dir`` read and checked (``finished``
    when the caller has read them); one label one experiment among those files and ``specs``
    (:func:`~empathy_zoo.result_file.check_one_experiment_per_label`); finished runs made by other
    code (said through ``note``, refused without ``options.rerun_changed``); the runs to train
    (:func:`~empathy_zoo.training.preflight.check_before_training`: budgets, evaluation size,
    checkpointable fixed policies, the learner's memory, each built from settings with one
    environment and nothing allocated); the places their logs, result, agent and checkpoint files
    go; and the room the largest file needs. ``note`` defaults to printing to stderr.
    ``reproduce --dry-run`` asks it too."""
    note = note or _print_note
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
    if options.backend == "ray" and not import_ray().is_initialized():
        check_ray_address(options.address)  # (missing Ray, or no cluster there, is said before anything is written)
    check_not_read_folder(out_dir, f"the output directory {out_dir}", runs_by_name=False)  # (its files would stop being read)
    if finished is None:
        finished = read_finished(out_dir)
    check_one_experiment_per_label(
        [
            *((result.table_env, result.method_label, result.run_id, str(path)) for path, result in finished.items()),
            *((s.variant.label, s.display_label(), s.run_id, f"run {s.run_id}") for s in specs),
        ]
    )
    redo = _runs_to_redo(specs, out_dir, finished, options, note)
    todo = [s for s in specs if result_path(out_dir, s.run_id) not in finished or s.run_id in redo]
    warnings = check_before_training(todo, options)
    local_checkpoints = options.backend == "local" and options.checkpoint_interval > 0
    room = max(PROBE_BYTES, largest_checkpoint_bytes(todo, options)) if local_checkpoints and todo else PROBE_BYTES
    check_log_places(out_dir, options.log, [s.run_id for s in todo])  # (no link where a run logs)
    check_file_places(out_dir, todo, options.max_parallel_runs if local_checkpoints else None)
    subdirs = (RUNS_DIR, *((CHECKPOINT_DIR,) if local_checkpoints else ()), *log_subdirs(options.log))
    return TrainingPlan(redo, todo, warnings, subdirs, room)


def check_file_places(out_dir: Path, todo: Sequence[RunSpec], max_parallel_runs: int | None) -> None:
    """Refuse (``ValueError`` naming it) every place a run of ``todo`` writes a file in ``out_dir``
    that holds anything but nothing or a regular file, or lies through a link
    (:func:`empathy_zoo.names.check_replaceable`, :func:`~empathy_zoo.names.check_no_links`): its
    result file, its agent file (either suffix) and, with local checkpoints (``max_parallel_runs``
    given, the most runs of an ensemble), each checkpoint and list of runs in ``checkpoints/`` and
    those of the fresh ensembles ``todo`` groups into. Asked before any directory is made and any
    run trains, so a refusal leaves the output directory as it was (and trains nothing)."""
    places = []
    for spec in todo:
        result = result_path(out_dir, spec.run_id)
        places += [result, *(result.with_name(spec.run_id + suffix) for suffix in AGENT_SUFFIXES)]
    if max_parallel_runs is not None:
        directory = out_dir / CHECKPOINT_DIR
        data_files(directory, "*.pt", "checkpoint")  # (each there a regular file, as plan_ensembles asks)
        data_files(directory, f"*{RUNS_LIST_SUFFIX}", "list of runs")
        for chunk in group_specs(todo, max_parallel_runs):
            checkpoint = checkpoint_path(out_dir, chunk)
            places += [checkpoint, runs_list_path(checkpoint)]
    for place in places:
        check_replaceable(check_no_links(out_dir, place))


def _runs_to_redo(
    specs: Sequence[RunSpec],
    out_dir: Path,
    finished: Mapping[Path, RunResult],
    options: RunnerOptions,
    note: Callable[[str], None],
) -> set[str]:
    """The finished runs of ``specs`` to retrain because other code made them
    (``options.rerun_changed``); without it, ``ValueError`` when there are any (see :func:`train_runs`)."""
    rerun_changed = options.rerun_changed
    changed, unknown = code_changes(
        specs,
        {s.run_id: finished[path] for s in specs if (path := result_path(out_dir, s.run_id)) in finished},
        options.update_kernel,
        options.device,
    )
    if changed and not rerun_changed:
        count = len({run_id for run_ids in changed.values() for run_id in run_ids})
        raise ValueError(
            f"{count} finished run(s) in {out_dir / RUNS_DIR} were made by other code than this, so their results "
            f"are not what these runs give now: {listing(changed)}; to go on, write to a new output directory (--out), "
            "delete those result files, or retrain them over their files (rerun_changed=True, --rerun-changed)"
        )
    if unknown and not rerun_changed:
        note(
            f"reusing finished runs whose code cannot be checked: {listing(unknown)}; "
            "rerun_changed=True (--rerun-changed) retrains them"
        )
    if not rerun_changed or not (changed or unknown):
        return set()
    note(
        f"retraining finished runs made by other code, or by code that cannot be checked: "
        f"{listing({**changed, **unknown})}; their result files are replaced when the new ones are written"
    )
    return {run_id for groups in (changed, unknown) for run_ids in groups.values() for run_id in run_ids}


def _train_todo(
    ensembles: EnsemblePlan,
    out_dir: Path,
    options: RunnerOptions,
    on_result: Callable[[dict[str, Any]], None] | None,
    note: Callable[[str], None],
) -> None:
    """Train the runs to do of ``ensembles`` (``train_runs`` checked everything, the checkpoints
    too), once the changes to ``checkpoints/`` it plans are made and said."""
    chunks = ensembles.apply(note)
    wanted = {s.run_id for s in ensembles.todo}
    if on_result is not None:  # (a resumed ensemble may finish runs not asked for here)
        given, on_result = on_result, lambda result: given(result) if result["run_id"] in wanted else None
    progress = SweepProgress(
        [(len(chunk), chunk[0].steps) for chunk in chunks], enabled=options.progress, style=options.progress_style
    )
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


def _counting(on_result: Callable[[dict[str, Any]], None] | None, progress: SweepProgress) -> Callable[[dict[str, Any]], None]:
    def counted(result: dict[str, Any]) -> None:
        progress.sweep.update(result["steps"])
        if on_result is not None:
            on_result(result)

    return counted


def _print_note(text: str) -> None:
    print(f"empathy-zoo: {text}", file=sys.stderr, flush=True)


def read_finished(out_dir: str | Path) -> dict[Path, RunResult]:
    """Every result file in ``out_dir``, read (and checked: a damaged one raises, naming it), by path."""
    runs_dir = Path(out_dir) / RUNS_DIR
    paths = sorted(runs_dir.glob("*.json")) if runs_dir.is_dir() else []
    return {path: read_result(path) for path in paths if not path.name.startswith(".")}


def exit_with_parent(parent: int) -> None:
    """In a worker: end this process if the sweep's process goes away (killed, not interrupted),
    so no orphan keeps training and writing checkpoints beside a restarted sweep."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(2.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="exit-with-parent").start()


@contextmanager
def stopped_by_signals() -> Iterator[None]:
    """While the block runs (in the main thread), the first SIGINT or SIGTERM raises
    :class:`Stopped` there, whatever the process inherited for them; a second one while the sweep
    stops is ignored. The handlers before are put back afterwards. Inside a block of its own (a
    command that trains, then writes its reports, all of it stoppable) it changes nothing."""
    if threading.current_thread() is not threading.main_thread() or all(
        getattr(signal.getsignal(number), "stops_sweep", False) for number in STOP_SIGNALS
    ):
        yield
        return
    fired: list[int] = []

    def stop(signum: int, frame: Any) -> None:
        if not fired:
            fired.append(signum)
            raise Stopped(signum)

    stop.stops_sweep = True  # type: ignore[attr-defined]

    previous = {number: signal.signal(number, stop) for number in STOP_SIGNALS}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def stop_workers(pool: ProcessPoolExecutor) -> None:
    """End the worker processes of ``pool`` now (the sweep stops): each is terminated, then killed
    after :data:`WORKER_STOP_S` seconds, and waited for. What they finished is written (each result
    file and checkpoint atomically), so the same command resumes from there."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join(WORKER_STOP_S)
        if process.is_alive():
            process.kill()
            process.join()


def _train_in_processes(
    chunks: list[list[RunSpec]],
    out_dir: Path,
    options: RunnerOptions,
    on_result: Callable[[dict[str, Any]], None] | None,
    progress: SweepProgress,
) -> None:
    """Spread ensembles over ``options.workers`` processes (one torch thread each by default);
    their progress comes back through a queue and is drawn here. When an ensemble fails, those not
    started are cancelled and the running ones finish; when this process is interrupted (Ctrl-C,
    SIGINT or SIGTERM: :class:`Stopped`), the workers are stopped too (:func:`stop_workers`)."""
    context = multiprocessing.get_context("spawn")
    workers = min(options.workers, len(chunks))
    manager = context.Manager() if options.progress else None
    drain = QueueDrain(manager.Queue(), progress) if manager is not None else None
    reporter = QueueReporter(drain.source) if drain is not None else None
    try:
        with ProcessPoolExecutor(workers, mp_context=context, initializer=exit_with_parent, initargs=(os.getpid(),)) as pool:
            futures = [
                pool.submit(
                    train_ensemble, chunk, out_dir, replace(options, workers=1, threads=options.threads or 1), True, reporter, i
                )
                for i, chunk in enumerate(chunks)
            ]
            try:
                for future in as_completed(futures):
                    for result in future.result():
                        if on_result is not None:
                            on_result(result)
            except BaseException as error:
                for future in futures:
                    future.cancel()
                if isinstance(error, KeyboardInterrupt):  # (another error lets the running ensembles finish)
                    stop_workers(pool)
                raise
    finally:
        if drain is not None:
            drain.stop()
        if manager is not None:
            manager.shutdown()
