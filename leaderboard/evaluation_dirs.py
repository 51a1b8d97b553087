"""Evaluation files kept apart from their runs: ``empathy-zoo leaderboard DIR --evaluations EVAL_DIR``.

``empathy-zoo evaluate RESULTS --out EVAL_DIR`` writes ``EVAL_DIR/evaluations/<scenario set>/<run
id>.json``, away from the runs it evaluated. :func:`match_evaluations` reads such a directory (or
that ``evaluations`` folder itself) for a leaderboard: every file is read through the bounded
reader and checked as an evaluation file (:func:`empathy_zoo.evaluation_file.read_evaluation`),
then matched to the run it names among the runs read. The match is by run id and by the agent
file's SHA-256: the one the evaluation records must be the one the run's result file records; so
must its environment, variant, method, seed and its own partners and world (its ``trained_with``
scenario), as ``empathy-zoo evaluate`` writes them of the run
(:func:`empathy_zoo.evaluation_file.evaluation_mismatch`).
Matched, an evaluation counts as if it lay beside its run
(:func:`leaderboard.heldout_scores.load_heldout`'s ``extra``).

Refused, each with one ``ValueError`` line naming the file: an evaluation whose run is not among
the runs read, one of another agent than its run's result file records (the run was trained again),
one that records another seed, method or world than its run's, one of a run and scenario set
already evaluated beside the runs or in another ``--evaluations`` directory, and one that is not an
evaluation file of this suite. So are a directory that does not exist, holds no evaluation file, is
given twice, or is one of the results directories read (its evaluations are read beside its runs
already), each told however it is written: ``DIR/runs`` is ``DIR``, whose evaluations lie in
``DIR/evaluations`` (:func:`empathy_zoo.result_file.results_root`). Evaluation files beside the
runs keep their own rule: one that matches no run is left out with a note.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from empathy_zoo.data_files import data_files
from empathy_zoo.evaluation_file import (
    EVALUATIONS_DIR,
    check_no_stray_json,
    evaluation_files,
    evaluation_mismatch,
    evaluations_root,
    read_evaluation,
)
from empathy_zoo.evaluation_record import EvaluationResult
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.names import resolved
from empathy_zoo.result_file import results_root

__all__ = ["MatchedEvaluation", "evaluation_dir_files", "match_evaluations"]

MatchedEvaluation = tuple[RunResult, EvaluationResult, Path]
"""``(run, evaluation, path)``: a run read for the leaderboard, its evaluation and the file it was read from."""


def evaluation_dir_files(directory: str | os.PathLike[str]) -> list[Path]:
    """The evaluation files of an ``--evaluations`` directory: ``DIR/evaluations/<set>/<run id>.json``
    (what ``empathy-zoo evaluate --out DIR`` writes), or ``DIR/<set>/<run id>.json`` where ``DIR``
    is that ``evaluations`` folder itself. ``ValueError`` for a directory that does not exist or
    holds none, and for anything of those names that is no regular file."""
    root = Path(directory)
    if not root.exists():
        raise ValueError(f"--evaluations {directory} does not exist")
    if not root.is_dir():
        raise ValueError(
            f"--evaluations {directory} is not a directory (give the directory empathy-zoo evaluate --out wrote into)"
        )
    found = evaluation_files(root)
    if not found and resolved(root).name == EVALUATIONS_DIR:  # (that folder itself, or a link to it)
        check_no_stray_json(root)
        found = data_files(root, "*/*.json", "evaluation file")
    if not found:
        raise ValueError(
            f"--evaluations {directory} holds no evaluation files ({EVALUATIONS_DIR}/<scenario set>/<run id>.json): "
            "give the directory empathy-zoo evaluate --out wrote into"
        )
    return found


def _recorded_sha(run: RunResult) -> str | None:
    return None if run.agent is None else run.agent.sha256


def _beside_runs(
    results_dirs: Sequence[str | os.PathLike[str]], results: Sequence[RunResult], origins: Sequence[str] | None
) -> dict[tuple[str, str], Path]:
    """``{(run id, scenario set): path}`` of the evaluation files beside the runs that count
    (:func:`~leaderboard.heldout_scores.load_heldout`): those whose run was read from their
    directory (``origins``: each result's, as given; ``None`` for one directory) with the agent its
    result file records."""
    beside: dict[tuple[str, str], Path] = {}
    for directory in results_dirs:
        mine = results if origins is None else [r for r, o in zip(results, origins, strict=True) if o == os.fspath(directory)]
        recorded = {(run.run_id, _recorded_sha(run)) for run in mine}
        for path in evaluation_files(directory):
            evaluation = read_evaluation(path)
            if (evaluation.run_id, evaluation.agent.sha256) in recorded:
                beside[(evaluation.run_id, evaluation.scenario_set.name)] = path
    return beside


def match_evaluations(
    evaluation_dirs: Sequence[str | os.PathLike[str]],
    results: Sequence[RunResult],
    results_dirs: Sequence[str | os.PathLike[str]] = (),
    origins: Sequence[str] | None = None,
) -> list[MatchedEvaluation]:
    """Every evaluation file of ``evaluation_dirs`` (:func:`evaluation_dir_files`), read, checked and
    matched to its run among ``results`` (the runs of ``results_dirs`` as the leaderboard reads
    them; ``origins``: the directory, as given, each was read from, needed with several) by run id
    and agent hash; ``[]`` without a directory. Anything refused (see the module page) raises
    ``ValueError`` naming the file or the directory, before anything is written."""
    if not evaluation_dirs:
        return []
    read_dirs = {resolved(results_root(directory)): os.fspath(directory) for directory in results_dirs}
    read_evaluations = {resolved(evaluations_root(directory)): os.fspath(directory) for directory in results_dirs}
    seen_dirs: dict[Path, str] = {}
    for directory in evaluation_dirs:
        where = resolved(results_root(directory))  # (DIR/runs is DIR: its evaluations are DIR/evaluations)
        if where in read_dirs:
            raise ValueError(
                f"--evaluations {directory} is the results directory {read_dirs[where]}: "
                "its evaluations are read beside its runs already"
            )
        if where in read_evaluations:
            raise ValueError(
                f"--evaluations {directory} is the evaluations folder of the results directory {read_evaluations[where]}: "
                "it is read beside its runs already"
            )
        if where in seen_dirs:
            raise ValueError(f"--evaluations {directory} is given twice (as {seen_dirs[where]} too)")
        seen_dirs[where] = os.fspath(directory)
    by_id: dict[str, list[RunResult]] = {}
    for run in results:
        by_id.setdefault(run.run_id, []).append(run)
    taken = _beside_runs(results_dirs, results, origins)
    read = ", ".join(os.fspath(d) for d in results_dirs) or "the results read"
    matched: list[MatchedEvaluation] = []
    for directory in evaluation_dirs:
        for path in evaluation_dir_files(directory):
            evaluation = read_evaluation(path)
            run_id, evaluated = evaluation.run_id, evaluation.agent.sha256
            runs = by_id.get(run_id, [])
            if not runs:
                raise ValueError(f"{path}: its run {run_id} is in none of the results directories read ({read})")
            same_agent = [run for run in runs if _recorded_sha(run) == evaluated]
            if not same_agent:
                recorded = _recorded_sha(runs[0])
                if recorded is None:
                    raise ValueError(f"{path}: its run {run_id} kept no agent file, so this is not its evaluation")
                raise ValueError(
                    f"{path}: made of another agent (SHA-256 {evaluated[:12]}…) than run {run_id}'s result file "
                    f"records ({recorded[:12]}…): the run was trained again; evaluate it again"
                )
            if len(same_agent) > 1:
                raise ValueError(f"{path}: run {run_id} is read from {len(same_agent)} results directories; read it from one")
            mismatch = evaluation_mismatch(evaluation, same_agent[0])
            if mismatch is not None:
                raise ValueError(
                    f"{path}: not the evaluation of run {run_id} its result file records ({mismatch}); "
                    "move it away and evaluate the run again"
                )
            key = (run_id, evaluation.scenario_set.name)
            if key in taken:
                raise ValueError(
                    f"{path}: run {run_id} in scenario set {key[1]!r} is evaluated in {taken[key]} too; move one away"
                )
            taken[key] = path
            matched.append((same_agent[0], evaluation, path))
    return matched
