"""Tuning a method with Optuna, on tuning seeds kept apart from the seeds its results are reported on.

:func:`run_study` tunes the parameters of one experiment of a sweep file (a method on one
environment variant; :func:`select_experiment`) over a search space
(:mod:`empathy_zoo.experiment.search_space`) by a plan (:class:`StudyPlan`)
and writes, into its output directory:

* ``study.json``: the plan (sweep file, experiment, search space, objective, tuning and reporting
  seeds, budget, sampler, pruner) and every trial: its parameters, state, value and learning curve
  (the objective at each greedy evaluation, per tuning seed), and the best trial;
* ``tuned.toml``: the best trial's settings as a sweep file of that experiment on the sweep's
  **reporting** seeds and budget (:func:`~empathy_zoo.experiment.sweep_writer.experiment_sweep`),
  labelled ``<the method's label at those settings>, tuned``: ``empathy-zoo reproduce --profile
  DIR/tuned.toml`` trains the row to report;
* ``study.journal``: Optuna's journal of the study (its storage), from which a study that was
  stopped resumes; every line of it is checked against what the study writes
  (:mod:`empathy_zoo.training.tuning_journal`) before anything is trained or written.

Each is rewritten (atomically) after every trial. Decisions, and why (the plan's names,
:class:`StudyPlan` and the functions that value a trial, are :mod:`empathy_zoo.training.study_plan`'s):

* **Objective**: the mean, over the tuning seeds, of a metric of the run's last greedy evaluation
  (ε = 0, its fixed start states): the figure the leaderboard's greedy column reports
  (:attr:`StudyPlan.over` ``"last"``). Which metric is the caller's (``tune`` defaults to the
  environment's task metric, docs/tuning.md). Where that figure saturates (Coexistence's greedy
  survival reaches its 500-step ceiling within a laptop budget at many learning rates), trials tie
  and the first of a tie is kept: ``over="curve"`` takes instead the mean over every greedy
  evaluation of the run (the area under its greedy learning curve, :func:`curve_value`), which
  ranks trials that reach the same end by how soon they got there; :func:`ties_at_best` says
  when a study's best value is tied.
* **Tuning seeds** are :data:`TUNING_SEED_BASE` and on (``10000, 10001, …``), a range no shipped
  sweep reports on; seeds that a sweep file reports on are refused (:func:`tuning_seeds`), so a
  setting is never chosen on the runs that then score it. Every trial trains the same tuning
  seeds (common random numbers: trials differ by their parameters only), in one lockstep ensemble.
* **Sampler**: Optuna's TPE, seeded; before each batch of trials (:attr:`StudyPlan.batch`, one
  unless said) a new sampler is seeded from the study's seed and the number of trials finished
  before the batch, and it sees only the trials finished before the batch (it proposes the
  batch's points one after another in a study of its own, so a point never depends on when a
  batch-mate finished). The same command gives the same study, and a stopped study resumed gives
  the study an unstopped one gives: a batch stopped mid-way keeps its trials told back, and its
  others are proposed again, the same points, and trained again. Its first
  :attr:`StudyPlan.startup_trials` trials (:data:`STARTUP_TRIALS` unless said) sample at random.
* **Batches and processes**: the trials of a batch train side by side in up to
  ``options.workers`` processes (``tune --jobs``; one trains them one after another here), and
  each is told back to the study, in trial order, as soon as it and every trial before it in the
  batch finished. Two trials of a batch at the same point train once. The pruner judges every
  trial of a batch against the trials finished before the batch, so a batch's outcome does not
  depend on the number of processes or on which trial finished first; the journal gets the same
  lines in the same order (but for time stamps and worker ids). A batch of one is the study of
  one trial at a time, as before batches existed.
* **Logging**: with ``options.log`` (``tune --log``), every trial's runs log their scalars
  under ``<out>/logs/<backend>/<run id>/`` (:mod:`empathy_zoo.training.tracking`); two trials
  at the same point are the same runs and log to the same place.
* **Pruner**: Optuna's median pruner on the learning curve: at each greedy evaluation before the
  last, the trial reports its objective and is stopped when it is worse than the median of the
  trials finished before its batch at that step (after :data:`PRUNE_STARTUP_TRIALS` finished
  trials, and from the env step :attr:`StudyPlan.prune_from` on). The report
  rides on the trainer's ``on_evaluation`` hook (:func:`~empathy_zoo.training.ensemble.train_ensemble`),
  which only reads the evaluations: a run trains the same numbers with it as without it.
* **Equal budgets**: a study runs exactly ``trials`` trials (finished, pruned or refused), each of
  ``len(seeds)`` runs of ``budget.steps`` env steps at most; a trial stopped by an interruption
  does not count and is run again when the study resumes (its runs keep no checkpoint), and so
  is a finished trial that waited on an unfinished one before it in its batch. A study resumed
  with fewer ``trials`` than it has done (or whose journal holds more) is refused before it opens
  (:func:`check_journal`): its ``study.json`` would hold more trials than its plan.
* **Refused points**: a point whose settings the method refuses (a warm-up longer than the
  budget, say) is a trial in state ``FAIL`` with the reason in ``study.json``; the ends of every
  range are checked before the study starts, so this is rare. So is a point whose runs diverged
  (their weights no longer finite numbers: a learning rate too high), with the refusal naming them.

Optuna is an optional extra (``pip install -e ".[tune]"``): :func:`import_optuna` says so
in one line where it is missing.
"""

from __future__ import annotations

import contextlib
import errno
import importlib
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, cast

import numpy as np

from empathy_zoo._version import __version__
from empathy_zoo.atomic import check_output_dir, remove_stale_temp_files, write_json_atomic, write_text_atomic
from empathy_zoo.bounded_read import check_json_depth, parse_json, read_data
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.search_space import check_ends, point_runs
from empathy_zoo.experiment.sweep_writer import experiment_sweep
from empathy_zoo.extras import install_command
from empathy_zoo.names import (
    IMPORTANCE_MARK,
    PNG_OPENING,
    TRIALS_MARK,
    check_marked_figure,
    check_no_links,
    check_own_file,
    check_replaceable,
)
from empathy_zoo.output_lock import hold_output_dir
from empathy_zoo.training.checkpoint import DivergedError
from empathy_zoo.training.ensemble import train_ensemble
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.preflight import check_before_training
from empathy_zoo.training.runner import exit_with_parent, stop_workers
from empathy_zoo.training.study_plan import OVER_WORDS, PRUNE_STARTUP_TRIALS, StudyPlan, curve_value, trial_value
from empathy_zoo.training.tracking import log_subdirs
from empathy_zoo.training.trials_figure import IMPORTANCE_FIGURE, TRIALS_FIGURE
from empathy_zoo.training.tuning_journal import check_study_lines, stored_plan

__all__ = [
    "JOURNAL_FILE",
    "OUTPUT_FILES",
    "STUDY_FILE",
    "STUDY_SCHEMA",
    "TUNED_FILE",
    "TuningNotInstalledError",
    "check_journal",
    "import_optuna",
    "run_study",
    "study_document",
    "train_trial",
]

STUDY_FILE = "study.json"
TUNED_FILE = "tuned.toml"
JOURNAL_FILE = "study.journal"
OUTPUT_FILES = (STUDY_FILE, TUNED_FILE, JOURNAL_FILE)
"""The files a study writes (or appends to) in its output directory."""
STUDY_SCHEMA = 1
"""Version of ``study.json``'s layout."""
_REFUSED = "refused"
_CURVE = "curve"
_WALL = "wall_time_s"


class TuningNotInstalledError(ImportError, ValueError):
    """Optuna is missing (a ``ValueError`` too: the command line reports it in one line)."""


def import_optuna() -> Any:
    """The ``optuna`` module, or :class:`TuningNotInstalledError` saying which extra installs it."""
    try:
        return importlib.import_module("optuna")
    except ImportError:
        raise TuningNotInstalledError(f"tuning needs Optuna, which is not installed: {install_command('tune')}") from None


@dataclass(frozen=True)
class _Outcome:
    """What training a trial's point gave."""

    curve: list[dict[str, Any]]
    """The objective at each greedy evaluation: ``{step, value, per_seed}``, in step order."""
    wall_time_s: float
    """Seconds it trained."""
    pruned: bool
    """Whether the pruner stopped it before its last evaluation."""


@dataclass(frozen=True)
class _Point:
    """A trial's point to train, with all it needs in a process of its own."""

    plan: StudyPlan
    out: Path
    options: RunnerOptions
    values: dict[str, Any]
    """The point: a value for each of the plan's parameters, by name."""
    earlier: list[Any]
    """The trials finished before the point's batch (Optuna ``FrozenTrial``): whom the pruner judges it against."""


class _Pruned(Exception):
    """The pruner stopped a trial (its curve so far is its outcome)."""


def train_trial(
    specs: Sequence[RunSpec],
    out_dir: Path,
    options: RunnerOptions,
    on_evaluation: Callable[[int, list[dict[str, list]]], None] | None = None,
) -> list[dict[str, Any]]:
    """Train a trial's runs ``specs`` (one ensemble) and return their result documents, without
    writing them; ``on_evaluation`` is told each greedy evaluation (and may stop the trial by
    raising). Trained as :func:`~empathy_zoo.training.runner.train_runs` trains them, but for
    checkpoints: a trial keeps none. With ``options.log``, the runs log under ``out_dir/logs``."""
    return train_ensemble(specs, out_dir, replace(options, checkpoint_interval=0), False, on_evaluation=on_evaluation)


def _counted(trial: Any, states: Any) -> bool:
    """Whether a stored trial counts toward the study's trials (finished, pruned or refused)."""
    return trial.state in (states.COMPLETE, states.PRUNED) or (trial.state == states.FAIL and _REFUSED in trial.user_attrs)


def _pruner(optuna: Any, plan: StudyPlan) -> Any:
    """The plan's pruner: Optuna's median pruner, or none."""
    if not plan.prune:
        return optuna.pruners.NopPruner()
    return optuna.pruners.MedianPruner(n_startup_trials=PRUNE_STARTUP_TRIALS, n_warmup_steps=plan.prune_from)


def _train_point(point: _Point) -> _Outcome | str:
    """Train ``point`` (here, or in a worker process): its runs on the plan's tuning seeds, the
    objective taken at each greedy evaluation and shown to the plan's pruner, which judges it
    against the trials finished before its batch (in a study in memory, as Optuna's
    ``Trial.should_prune`` does in the study itself). A point whose runs diverged
    (:class:`~empathy_zoo.training.checkpoint.DivergedError`) gives the refusal's message: its
    trial is refused with that reason, as a point the method refuses is, and the study goes on."""
    optuna = import_optuna()
    plan = point.plan
    judge = optuna.create_study(direction=plan.direction, pruner=_pruner(optuna, plan), sampler=optuna.samplers.RandomSampler(0))
    judge.add_trials(point.earlier)
    trial = judge.ask()
    specs = point_runs(plan.base, plan.params, point.values, plan.seeds)
    curve: list[dict[str, Any]] = []
    started = time.perf_counter()

    def report(step: int, per_run: list[dict[str, list]]) -> None:
        value, per_seed = trial_value(per_run, plan.metric)
        curve.append({"step": step, "value": value, "per_seed": per_seed})
        trial.report(curve_value([p["value"] for p in curve], plan.over), step)
        if step < plan.base.steps and trial.should_prune():
            raise _Pruned

    pruned = False
    try:
        train_trial(specs, point.out, point.options, report)
    except _Pruned:
        pruned = True
    except DivergedError as error:
        return str(error)
    return _Outcome(curve, round(time.perf_counter() - started, 3), pruned)


def _worker_started(parent: int) -> None:
    """In a worker process: end with the study's process (killed, not interrupted); Optuna quiet."""
    exit_with_parent(parent)
    optuna = import_optuna()
    optuna.logging.set_verbosity(optuna.logging.ERROR)


class _Workers:
    """The processes that train a batch's points side by side: ``count`` at most (one trains them
    here, one after another), started at the first batch with two points to train and kept for the
    study's later batches."""

    def __init__(self, count: int, batch: int) -> None:
        self.count = min(count, batch)
        self.pool: ProcessPoolExecutor | None = None

    def train(self, points: list[tuple[list[int], _Point]]) -> Iterator[tuple[list[int], _Outcome | str]]:
        """Each ``(slots, point)`` of ``points`` trained: ``(slots, its outcome)`` as each finishes
        (in the order given, here). An interruption stops the workers; another error lets the
        running points finish."""
        if self.count == 1 or len(points) == 1:
            for slots, point in points:
                yield slots, _train_point(point)
            return
        if self.pool is None:
            context = multiprocessing.get_context("spawn")
            self.pool = ProcessPoolExecutor(self.count, mp_context=context, initializer=_worker_started, initargs=(os.getpid(),))
        futures: dict[Future[_Outcome | str], list[int]] = {}
        for slots, point in points:
            options = replace(point.options, workers=1, progress=False, threads=point.options.threads or 1)
            futures[self.pool.submit(_train_point, replace(point, options=options))] = slots
        try:
            for future in as_completed(futures):
                yield futures[future], future.result()
        except BaseException as error:
            for future in futures:
                future.cancel()
            if isinstance(error, KeyboardInterrupt):
                stop_workers(self.pool)
                self.pool = None
            raise

    def close(self) -> None:
        """Let the workers end (once what they train finished)."""
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)
            self.pool = None


def _given_sampler(optuna: Any, values: dict[str, Any]) -> Any:
    """An Optuna sampler that draws ``values`` (a point proposed already), by parameter name."""

    class Given(optuna.samplers.BaseSampler):
        def infer_relative_search_space(self, study: Any, trial: Any) -> dict[str, Any]:
            return {}

        def sample_relative(self, study: Any, trial: Any, search_space: Any) -> dict[str, Any]:
            return {}

        def sample_independent(self, study: Any, trial: Any, param_name: str, param_distribution: Any) -> Any:
            return values[param_name]

    return Given()


def _propose(optuna: Any, plan: StudyPlan, earlier: list[Any], count: int) -> list[dict[str, Any]]:
    """The first ``count`` points of the batch that starts after the finished trials ``earlier``:
    TPE seeded from the plan's seed and ``len(earlier)``, seeing ``earlier`` only (in a study in
    memory), each point drawn after the one before it."""
    seed = int(np.random.SeedSequence([plan.sampler_seed, len(earlier)]).generate_state(1)[0])
    sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=plan.startup_trials, constant_liar=False)
    proposer = optuna.create_study(direction=plan.direction, sampler=sampler)
    proposer.add_trials(earlier)
    points = []
    for _ in range(count):
        trial = proposer.ask()
        points.append({spec.name: spec.suggest(trial) for spec in plan.params})
    return points


def run_study(
    plan: StudyPlan,
    out_dir: str | Path,
    options: RunnerOptions = RunnerOptions(progress=False),
    command: str = "",
    progress: bool = True,
    on_trial: Callable[[dict[str, Any]], object] | None = None,
    on_note: Callable[[str], None] | None = None,
    also_writes: Sequence[str] = (),
) -> dict[str, Any]:
    """Run (or resume) the study ``plan`` in ``out_dir`` and return its ``study.json`` document
    (see the module documentation); ``on_trial`` gets that document after every trial (the
    command line draws its figures), ``on_note`` what is said on the way (default: stderr).
    ``options.workers`` processes train a batch's trials side by side (the study is the same for
    any number); with ``options.log`` the trials' runs log under ``out_dir/logs``.
    ``also_writes`` names the files the caller writes into ``out_dir`` too (``trials.png``): each
    is checked with the study's own files (:data:`OUTPUT_FILES`) before anything is trained or
    written: only nothing or a regular file is ever replaced or appended to, never a link (named
    with its target), a directory, a FIFO or a device (``ValueError``,
    :func:`empathy_zoo.names.check_replaceable`)."""
    optuna = import_optuna()
    note = on_note or (lambda text: print(f"empathy-zoo: {text}", file=sys.stderr, flush=True))
    out = Path(out_dir)
    check_ends(plan.base, plan.params)
    first = point_runs(plan.base, plan.params, {p.name: p.ends()[0] for p in plan.params}, plan.seeds)
    for warning in check_before_training(first, options):
        note(warning)
    for name in (*OUTPUT_FILES, *also_writes):
        _check_own_output(check_replaceable(check_no_links(out, out / name)))
    verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    try:
        with hold_output_dir(out, command or "run_study", note):
            subdirs = [out / sub for sub in log_subdirs(options.log)]
            made = [folder for sub in subdirs for folder in (*reversed(sub.parents), sub) if not folder.exists()]
            check_output_dir(out, log_subdirs(options.log))
            try:
                has_plan = check_journal(out / JOURNAL_FILE, note, plan, options.update_kernel)
            except BaseException:
                for folder in reversed(list(dict.fromkeys(made))):  # (a refused journal leaves no folder made for it)
                    with contextlib.suppress(OSError):
                        folder.rmdir()
                raise
            for stale in remove_stale_temp_files(out):
                note(f"removed {stale}, a write killed mid-way")
            try:
                return _study(optuna, plan, out, options, command, progress, on_trial, note, has_plan)
            except OSError as error:  # (a full disk): a bare system error is said naming the file, or the folder
                if error.errno is None or error.errno not in _WRITE_ERRNOS or error.strerror != os.strerror(error.errno):
                    raise  # (a message of the suite's, naming what it could not write; or no failed write)
                raise _cannot_write(Path(os.fsdecode(error.filename)) if error.filename else out, error) from None
    finally:
        optuna.logging.set_verbosity(verbosity)


_WRITE_ERRNOS = frozenset(getattr(errno, name) for name in ("ENOSPC", "EDQUOT", "EFBIG", "EROFS") if hasattr(errno, name))
"""The system errors only a write fails with (a full disk, a quota, a file too large, a read-only disk)."""


def _cannot_write(path: Path, error: OSError) -> OSError:
    """The ``OSError`` a study's failed write (a full disk) ends with: one line naming ``path`` (a
    file of the study, or its folder) and what to do. Every trial told is in the journal: the same
    command resumes the study."""
    return OSError(
        f"cannot write {path} ({error.strerror or error}); free space, then run the same command again "
        "to resume the study (the trials told so far are kept)"
    )


def check_journal(
    path: Path, note: Callable[[str], None], plan: StudyPlan | None = None, update_kernel: str = RunnerOptions.update_kernel
) -> bool:
    """Check the study's journal ``path`` (when there is one) before Optuna reads it, through the
    bounded reader (a regular file of at most :data:`~empathy_zoo.limits.MAX_JOURNAL_BYTES`); any
    line that is no JSON object (or nests deeper than :data:`~empathy_zoo.limits.MAX_JSON_DEPTH`)
    but a last one a kill cut short (no line break at its end) is refused with a ``ValueError``
    naming the file and the line. Given the ``plan`` of the study that opens it (trained with
    ``update_kernel``), every line's every field is then checked against what that study writes
    (:func:`~empathy_zoo.training.tuning_journal.check_study_lines`: a study of another plan, or a
    forged line, is refused). Only once all of it passed is the cut last line dropped from the
    file, said through ``note``. Returns whether the journal holds the plan already."""
    if not path.exists() and not path.is_symlink():
        return False
    check_replaceable(path)  # (Optuna appends to it: never through a link, never to a FIFO or a device)
    data = read_data(path, "tuning journal")
    lines = data.split(b"\n")
    torn = lines.pop()  # (b"" when the journal ends with a line break, as every complete write does)
    entries: list[tuple[int, dict[str, Any]]] = []
    for number, line in enumerate(lines, start=1):
        where = f"tuning journal {path}, line {number}"
        check_json_depth(line, where)
        try:
            entry = parse_json(line)
        except (ValueError, RecursionError) as error:
            raise ValueError(
                f"{where} is no JSON ({str(error)[:200]}): the journal is damaged; move it away to start the study again"
            ) from None
        if not isinstance(entry, dict):
            raise ValueError(f"{where} is no JSON object: the journal is damaged; move it away to start the study again")
        entries.append((number, entry))
    if plan is not None:
        check_study_lines(entries, path, plan, update_kernel)
    if torn:
        with open(path, "r+b") as handle:
            handle.truncate(len(data) - len(torn))
        note(f"dropped the last line of {path}: a write killed mid-way cut it short ({len(torn):,} bytes)")
    return any(entry.get("op_code") == 2 for _, entry in entries)


class _HeldWithDirectory:
    """The lock on the journal Optuna takes to append to it, held already: the one process that
    writes the journal (trials train in worker processes, which never write it) holds the output
    directory (:func:`~empathy_zoo.output_lock.hold_output_dir`) the while. Optuna's own lock
    file, ``study.journal.lock``, is never made: a file of that name (the user's) is left alone,
    where Optuna's lock waits 30 seconds on it and deletes it. (Optuna only calls these two
    methods of it; its base class is private to Optuna.)"""

    def acquire(self) -> bool:
        """Taken (the directory is held)."""
        return True

    def release(self) -> None:
        """Nothing to give back (the directory is released by its holder)."""


def _open_study(optuna: Any, plan: StudyPlan, out: Path, update_kernel: str, has_plan: bool) -> Any:
    """The study stored in ``out`` (created when there is none), whose journal :func:`check_journal`
    checked against ``plan`` (``has_plan``: it holds the plan already; else the plan is stored)."""
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend

    journal = out / JOURNAL_FILE

    class _NamedJournal(JournalFileBackend):
        """Optuna's journal file, whose failed append (a full disk) is an ``OSError`` naming it."""

        def append_logs(self, logs: list[dict[str, Any]]) -> None:
            try:
                super().append_logs(logs)
            except OSError as error:
                raise _cannot_write(journal, error) from None

    storage = JournalStorage(_NamedJournal(str(journal), lock_obj=cast(Any, _HeldWithDirectory())))
    study = optuna.create_study(
        storage=storage, study_name="tune", direction=plan.direction, pruner=_pruner(optuna, plan), load_if_exists=True
    )
    if not has_plan:
        study.set_user_attr("plan", stored_plan(plan, update_kernel))
    return study


def _study(
    optuna: Any,
    plan: StudyPlan,
    out: Path,
    options: RunnerOptions,
    command: str,
    progress: bool,
    on_trial: Callable[[dict[str, Any]], object] | None,
    note: Callable[[str], None],
    has_plan: bool,
) -> dict[str, Any]:
    from empathy_zoo.training.progress import progress_bar

    study = _open_study(optuna, plan, out, options.update_kernel, has_plan)
    states = optuna.trial.TrialState
    counted = [t for t in study.trials if _counted(t, states)]
    interrupted = [t.number for t in study.trials if not _counted(t, states)]
    if counted or interrupted:
        note(
            f"resuming the study in {out}: {len(counted)} of {plan.trials} trial(s) done"
            + (f"; trial(s) {interrupted} were interrupted and do not count" if interrupted else "")
        )
    bar = progress_bar(
        options.progress_style,
        total=plan.trials,
        initial=min(len(counted), plan.trials),
        desc=f"tune {plan.base.method}",
        unit="trial",
        disable=not progress,
    )

    def told() -> None:
        document = _write_outputs(study, plan, out, command, optuna, options)
        if on_trial is not None:
            on_trial(document)
        best = document["best"]
        bar.set_postfix_str(f"best {plan.metric} {best['value']:.4g} (trial {best['number']})" if best else "no trial finished")
        bar.update(1)

    workers = _Workers(options.workers, plan.batch)
    try:
        while len(counted) < plan.trials:
            start = len(counted) - len(counted) % plan.batch
            earlier = counted[:start]
            points = _propose(optuna, plan, earlier, min(plan.batch, plan.trials - start))
            for trial, values in zip(counted[start:], points, strict=False):  # (the batch's trials told so far)
                if dict(trial.params) != values:
                    raise ValueError(
                        f"{out / JOURNAL_FILE}: trial {trial.number} is not the point its batch proposes ({values}): "
                        "the journal is damaged or not this study's; move it away to start the study again"
                    )
            _run_batch(optuna, study, plan, out, options, points[len(counted) - start :], earlier, workers, told)
            counted = [t for t in study.trials if _counted(t, states)]
    finally:
        workers.close()
        bar.close()
    return _write_outputs(study, plan, out, command, optuna, options)


def _run_batch(
    optuna: Any,
    study: Any,
    plan: StudyPlan,
    out: Path,
    options: RunnerOptions,
    points: list[dict[str, Any]],
    earlier: list[Any],
    workers: _Workers,
    told: Callable[[], None],
) -> None:
    """Ask ``study`` for a trial at each of ``points`` (the batch's points not told yet), train
    them with ``workers``, and tell each back in trial order as soon as it and those before it are
    done (then ``told()``); a trial not told when training stops (an interruption, an error) is
    told failed, as Optuna's ``optimize`` tells it."""
    states = optuna.trial.TrialState
    trials = []
    for values in points:
        study.sampler = _given_sampler(optuna, values)
        trial = study.ask()
        for spec in plan.params:
            spec.suggest(trial)
        trials.append(trial)
    done: dict[int, _Outcome | str] = {}
    to_train: dict[tuple[str, ...], list[int]] = {}
    for slot, values in enumerate(points):
        try:
            specs = point_runs(plan.base, plan.params, values, plan.seeds)
            check_before_training(specs, options)
        except ValueError as error:
            done[slot] = str(error)
            continue
        to_train.setdefault(tuple(spec.run_id for spec in specs), []).append(slot)  # (one point, trained once)
    next_slot = 0

    def tell_ready() -> None:
        nonlocal next_slot
        while next_slot < len(trials) and next_slot in done:
            _tell(optuna, study, plan, trials[next_slot], done[next_slot])
            next_slot += 1
            told()

    try:
        tell_ready()
        jobs = [(slots, _Point(plan, out, options, points[slots[0]], earlier)) for slots in to_train.values()]
        for slots, outcome in workers.train(jobs):
            for slot in slots:
                done[slot] = outcome
            tell_ready()
    except BaseException:
        for trial in trials[next_slot:]:
            study.tell(trial, state=states.FAIL)
        raise


def _tell(optuna: Any, study: Any, plan: StudyPlan, trial: Any, outcome: _Outcome | str) -> None:
    """Tell ``study`` the ``outcome`` of ``trial``: the method's reason for refusing its point (a
    string), or what training gave, written as a trial that trains in the study writes it (each
    evaluation on its curve, then its value so far, then its wall time)."""
    states = optuna.trial.TrialState
    if isinstance(outcome, str):
        trial.set_user_attr(_REFUSED, outcome)
        study.tell(trial, state=states.FAIL)
        return
    curve: list[dict[str, Any]] = []
    for point in outcome.curve:
        curve.append(point)
        trial.set_user_attr(_CURVE, list(curve))
        trial.report(curve_value([p["value"] for p in curve], plan.over), point["step"])
    trial.set_user_attr(_WALL, outcome.wall_time_s)
    if outcome.pruned:
        study.tell(trial, state=states.PRUNED)
    else:
        study.tell(trial, curve_value([p["value"] for p in curve], plan.over))


def study_document(study: Any, plan: StudyPlan, command: str, optuna: Any, update_kernel: str) -> dict[str, Any]:
    """``study.json``'s document of ``study``, whose trials trained with ``update_kernel``."""
    states = optuna.trial.TrialState
    trials = []
    for trial in study.trials:
        curve = trial.user_attrs.get(_CURVE, [])
        state = trial.state.name if _counted(trial, states) else "INTERRUPTED"
        trials.append(
            {
                "number": trial.number,
                "state": "REFUSED" if _REFUSED in trial.user_attrs else state,
                "params": dict(trial.params),
                "value": trial.value if trial.state == states.COMPLETE else None,
                "last_value": curve_value([point["value"] for point in curve], plan.over) if curve else None,
                "steps_trained": curve[-1]["step"] if curve else 0,
                "curve": curve,
                **({"refused": trial.user_attrs[_REFUSED]} if _REFUSED in trial.user_attrs else {}),
                _WALL: trial.user_attrs.get(_WALL),
            }
        )
    complete = [t for t in study.trials if t.state == states.COMPLETE]
    best = study.best_trial if complete else None
    counted = [t for t in trials if t["state"] != "INTERRUPTED"]
    return {
        "schema": STUDY_SCHEMA,
        "version": __version__,
        "optuna": optuna.__version__,
        "command": command,
        "plan": plan.record(),
        "update_kernel": update_kernel,
        "trials_done": len(counted),
        "env_steps_trained": sum(t["steps_trained"] for t in counted) * len(plan.seeds),
        "best": None if best is None else {"number": best.number, "value": best.value, "params": dict(best.params)},
        "tuned_sweep_file": TUNED_FILE if best is not None else None,
        "trials": trials,
    }


_OPENINGS = {STUDY_FILE: b'{\n "schema": ', JOURNAL_FILE: b'{"op_code":', ".png": PNG_OPENING}
"""What every file of each name (a figure: of each suffix) that a study writes begins with."""
_FIGURE_MARKS = {TRIALS_FIGURE: TRIALS_MARK, IMPORTANCE_FIGURE: IMPORTANCE_MARK}
"""The mark every figure of each name a study's command writes holds (:func:`~empathy_zoo.names.check_marked_figure`)."""
TUNED_MARK = b"(study.json beside this file)"
"""What the first line of every ``tuned.toml`` holds (its comment names the study it comes from)."""


def _check_own_output(path: Path) -> None:
    """Refuse (``ValueError`` naming it) a regular file at ``path`` that is not what a study writes
    there (:data:`_OPENINGS`, :data:`TUNED_MARK`): a user's notes, a sweep file, another file named
    so is never replaced. A figure (:data:`_FIGURE_MARKS`) must hold its mark unless a study lies
    beside it (a figure an older version wrote, unmarked, beside its study is replaced). An empty
    file holds nothing to lose (:func:`~empathy_zoo.names.check_own_file`)."""
    if not path.is_file() or path.stat().st_size == 0:
        return
    if path.name == TUNED_FILE:
        with open(path, "rb") as handle:
            first = handle.readline(4096)
        if TUNED_MARK not in first:
            raise ValueError(
                f"{path} exists and is no tuned sweep file a study wrote (its first line names the study.json beside it): "
                "the suite replaces only its own; move the file away or give another --out"
            )
        return
    mark = _FIGURE_MARKS.get(path.name)
    if mark is not None and not _study_beside(path):  # (beside a study: an older version's unmarked figure is its own)
        check_marked_figure(path, path.stem, PNG_OPENING, mark)
        return
    opening = _OPENINGS.get(path.name) or _OPENINGS.get(path.suffix)
    if opening is not None:
        check_own_file(path, f"{path.name} of a study", opening)


def _study_beside(path: Path) -> bool:
    """Whether a study's own ``study.json`` (non-empty, beginning as every one does) lies beside ``path``."""
    study = path.parent / STUDY_FILE
    try:
        if not study.is_file() or study.is_symlink():
            return False
        with open(study, "rb") as handle:
            return handle.read(len(_OPENINGS[STUDY_FILE])) == _OPENINGS[STUDY_FILE]
    except OSError:
        return False


def _write_outputs(study: Any, plan: StudyPlan, out: Path, command: str, optuna: Any, options: RunnerOptions) -> dict[str, Any]:
    """Write ``study.json`` and, once a trial finished, ``tuned.toml``; return the document."""
    document = study_document(study, plan, command, optuna, options.update_kernel)
    if document["trials_done"] > plan.trials:  # (checked before the study opened: its reader refuses such a study)
        raise ValueError(
            f"{out / JOURNAL_FILE} holds {document['trials_done']} trial(s) done, more than --trials {plan.trials}: "
            f"resume it with --trials {document['trials_done']} or more"
        )
    best = document["best"]
    if best is not None:
        tuned = point_runs(plan.base, plan.params, best["params"], plan.reporting_seeds[:1])[0]
        tuned = replace(tuned, budget=plan.reporting_budget)
        label = f"{tuned.display_label()}, tuned"
        comment = (
            f"{label}: the best of {document['trials_done']} trial(s) of `empathy-zoo tune` (study.json beside this file),\n"
            f"tuned on seeds {list(plan.seeds)} at {plan.base.steps:,} env steps per run, objective: {plan.metric} "
            f"({plan.direction}) {OVER_WORDS[plan.over]};\n"
            f"reported on the sweep's seeds and budget (from {plan.source}):\n"
            f"  empathy-zoo reproduce --profile {out / TUNED_FILE}"
            + (f" --update-kernel {options.update_kernel}" if options.update_kernel != RunnerOptions.update_kernel else "")
            + "\n"
            f"tuned: {', '.join(f'{name} = {value!r}' for name, value in best['params'].items())}"
        )
        text = experiment_sweep(tuned, plan.reporting_seeds, label=label, comment=comment, name=f"{plan.base.method}_tuned")
        write_text_atomic(out / TUNED_FILE, text)
    write_json_atomic(out / STUDY_FILE, document)
    return document
