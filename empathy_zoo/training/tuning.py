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
* **Sampler**: Optuna's TPE, seeded; before each trial a new sampler is seeded from the study's
  seed and the number of trials finished, and it sees only finished trials, so the same command
  gives the same study, and a stopped study resumed gives the study an unstopped one gives.
  Its first :attr:`StudyPlan.startup_trials` trials (:data:`STARTUP_TRIALS` unless said)
  sample at random.
* **Pruner**: Optuna's median pruner on the learning curve: at each greedy evaluation before the
  last, the trial reports its objective and is stopped when it is worse than the median of the
  finished trials at that step (after :data:`PRUNE_STARTUP_TRIALS` finished trials, and from
  the env step :attr:`StudyPlan.prune_from` on). The report
  rides on the trainer's ``on_evaluation`` hook (:func:`~empathy_zoo.training.ensemble.train_ensemble`),
  which only reads the evaluations: a run trains the same numbers with it as without it.
* **Equal budgets**: a study runs exactly ``trials`` trials (finished, pruned or refused), each of
  ``len(seeds)`` runs of ``budget.steps`` env steps at most; a trial stopped by an interruption
  does not count and is run again when the study resumes (its runs keep no checkpoint).
* **Refused points**: a point whose settings the method refuses (a warm-up longer than the
  budget, say) is a trial in state ``FAIL`` with the reason in ``study.json``; the ends of every
  range are checked before the study starts, so this is rare.

Optuna is an optional extra (``pip install -e ".[tune]"``): :func:`import_optuna` says so
in one line where it is missing.
"""

from __future__ import annotations

import importlib
import json
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from empathy_zoo._version import __version__
from empathy_zoo.atomic import check_output_dir, remove_stale_temp_files, write_json_atomic, write_text_atomic
from empathy_zoo.bounded_read import check_json_depth, read_data
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.search_space import check_ends, point_runs
from empathy_zoo.experiment.sweep_writer import experiment_sweep
from empathy_zoo.extras import install_command
from empathy_zoo.names import check_no_links, check_replaceable
from empathy_zoo.output_lock import hold_output_dir
from empathy_zoo.training.ensemble import train_ensemble
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.preflight import check_before_training
from empathy_zoo.training.study_plan import OVER_WORDS, PRUNE_STARTUP_TRIALS, StudyPlan, curve_value, trial_value
from empathy_zoo.training.tuning_journal import check_study_lines, stored_plan

__all__ = [
    "JOURNAL_FILE",
    "OUTPUT_FILES",
    "STUDY_FILE",
    "STUDY_SCHEMA",
    "TRIALS_DIR",
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
TRIALS_DIR = "trials"
"""Where a trial's ensemble would keep a checkpoint (it keeps none: an interrupted trial is rerun)."""
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


class _Refused(Exception):
    """A trial's point the method refuses (its reason is the trial's ``refused`` attribute)."""


def train_trial(
    specs: Sequence[RunSpec],
    out_dir: Path,
    options: RunnerOptions,
    on_evaluation: Callable[[int, list[dict[str, list]]], None] | None = None,
) -> list[dict[str, Any]]:
    """Train a trial's runs ``specs`` (one ensemble) and return their result documents, without
    writing them; ``on_evaluation`` is told each greedy evaluation (and may stop the trial by
    raising). Trained as :func:`~empathy_zoo.training.runner.train_runs` trains them, but for
    checkpoints: a trial keeps none."""
    return train_ensemble(specs, out_dir, replace(options, checkpoint_interval=0), False, on_evaluation=on_evaluation)


def _counted(trial: Any, states: Any) -> bool:
    """Whether a stored trial counts toward the study's trials (finished, pruned or refused)."""
    return trial.state in (states.COMPLETE, states.PRUNED) or (trial.state == states.FAIL and _REFUSED in trial.user_attrs)


def run_study(
    plan: StudyPlan,
    out_dir: str | Path,
    options: RunnerOptions = RunnerOptions(progress=False),
    command: str = "",
    progress: bool = True,
    on_trial: Callable[[dict[str, Any]], None] | None = None,
    on_note: Callable[[str], None] | None = None,
    also_writes: Sequence[str] = (),
) -> dict[str, Any]:
    """Run (or resume) the study ``plan`` in ``out_dir`` and return its ``study.json`` document
    (see the module documentation); ``on_trial`` gets that document after every trial (the
    command line draws its figure), ``on_note`` what is said on the way (default: stderr).
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
        check_replaceable(check_no_links(out, out / name))
    check_output_dir(out, (TRIALS_DIR,))
    verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    try:
        with hold_output_dir(out, command or "run_study", note):
            has_plan = check_journal(out / JOURNAL_FILE, note, plan, options.update_kernel)
            for stale in remove_stale_temp_files(out):
                note(f"removed {stale}, a write killed mid-way")
            return _study(optuna, plan, out, options, command, progress, on_trial, note, has_plan)
    finally:
        optuna.logging.set_verbosity(verbosity)


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
            entry = json.loads(line)
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


def _open_study(optuna: Any, plan: StudyPlan, out: Path, update_kernel: str, has_plan: bool) -> Any:
    """The study stored in ``out`` (created when there is none), whose journal :func:`check_journal`
    checked against ``plan`` (``has_plan``: it holds the plan already; else the plan is stored)."""
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend

    storage = JournalStorage(JournalFileBackend(str(out / JOURNAL_FILE)))
    pruner = (
        optuna.pruners.MedianPruner(n_startup_trials=PRUNE_STARTUP_TRIALS, n_warmup_steps=plan.prune_from)
        if plan.prune
        else optuna.pruners.NopPruner()
    )
    study = optuna.create_study(storage=storage, study_name="tune", direction=plan.direction, pruner=pruner, load_if_exists=True)
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
    on_trial: Callable[[dict[str, Any]], None] | None,
    note: Callable[[str], None],
    has_plan: bool,
) -> dict[str, Any]:
    from empathy_zoo.training.progress import progress_bar

    study = _open_study(optuna, plan, out, options.update_kernel, has_plan)
    states = optuna.trial.TrialState
    done = sum(_counted(t, states) for t in study.trials)
    interrupted = [t.number for t in study.trials if not _counted(t, states)]
    if done or interrupted:
        note(
            f"resuming the study in {out}: {done} of {plan.trials} trial(s) done"
            + (f"; trial(s) {interrupted} were interrupted and do not count" if interrupted else "")
        )
    bar = progress_bar(
        options.progress_style,
        total=plan.trials,
        initial=min(done, plan.trials),
        desc=f"tune {plan.base.method}",
        unit="trial",
        disable=not progress,
    )
    try:
        while done < plan.trials:
            seed = int(np.random.SeedSequence([plan.sampler_seed, done]).generate_state(1)[0])
            study.sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=plan.startup_trials, constant_liar=False)
            study.optimize(_objective(optuna, plan, out, options), n_trials=1, catch=(_Refused,))
            done = sum(_counted(t, states) for t in study.trials)
            document = _write_outputs(study, plan, out, command, optuna, options)
            if on_trial is not None:
                on_trial(document)
            best = document["best"]
            bar.set_postfix_str(
                f"best {plan.metric} {best['value']:.4g} (trial {best['number']})" if best else "no trial finished"
            )
            bar.update(1)
    finally:
        bar.close()
    return _write_outputs(study, plan, out, command, optuna, options)


def _objective(optuna: Any, plan: StudyPlan, out: Path, options: RunnerOptions) -> Callable[[Any], float]:
    def objective(trial: Any) -> float:
        values = {spec.name: spec.suggest(trial) for spec in plan.params}
        try:
            specs = point_runs(plan.base, plan.params, values, plan.seeds)
            check_before_training(specs, options)
        except ValueError as error:
            trial.set_user_attr(_REFUSED, str(error))
            raise _Refused(str(error)) from None
        curve: list[dict[str, Any]] = []
        started = time.perf_counter()

        def report(step: int, per_run: list[dict[str, list]]) -> None:
            value, per_seed = trial_value(per_run, plan.metric)
            curve.append({"step": step, "value": value, "per_seed": per_seed})
            trial.set_user_attr(_CURVE, curve)
            value = curve_value([point["value"] for point in curve], plan.over)
            trial.report(value, step)
            if step < plan.base.steps and trial.should_prune():
                trial.set_user_attr(_WALL, round(time.perf_counter() - started, 3))
                raise optuna.TrialPruned(f"pruned at step {step}: {plan.metric} {value:.4g}")

        train_trial(specs, out / TRIALS_DIR, options, report)
        trial.set_user_attr(_WALL, round(time.perf_counter() - started, 3))
        return curve_value([point["value"] for point in curve], plan.over)

    return objective


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


def _write_outputs(study: Any, plan: StudyPlan, out: Path, command: str, optuna: Any, options: RunnerOptions) -> dict[str, Any]:
    """Write ``study.json`` and, once a trial finished, ``tuned.toml``; return the document."""
    document = study_document(study, plan, command, optuna, options.update_kernel)
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
