"""Several results directories read into one leaderboard, their experiments kept apart.

:func:`load_results_dirs` reads every result file of each directory, each directory checked as
:func:`leaderboard.aggregate.load_results` checks one, into one list: a researcher's runs tabled
beside the suite's (``docs/results/paper``) without retraining either. Nothing is written to a
result file; what keeps experiments apart is done on the runs read (each relabelled run a new record,
:func:`dataclasses.replace`):

* **Label prefixes.** ``labels={DIR: PREFIX}`` (``--label DIR=PREFIX``) puts ``PREFIX`` and a
  space before the label of every run read from ``DIR``; a prefix is a label by the reader's rule
  (:func:`empathy_zoo.names.check_label`: one line of printable text, at most 200 characters).
* **Budgets.** Where the runs read have more than one training budget
  (:class:`leaderboard.budgets.RunBudget`), every row's label ends with its budget
  (:data:`BUDGET_SEPARATOR`, ``"DQN · 30,000 steps"``, with the evaluation interval and episodes
  where those differ between budgets), so runs of different budgets never share a row; a row is
  compared only with DQN rows of its own variant and budget
  (:func:`leaderboard.improvement.improvements_over_dqn`).
* **DQN rows** (with ``dqn_named``, as the leaderboard reads them): a DQN reference row is shown
  as ``DQN`` whatever its runs are labelled (:mod:`leaderboard.row_names`), before any prefix and
  budget; :attr:`ResultSet.renamed` says which labels were.
* **One experiment per row.** Runs of one row (variant and label) from two experiments are refused
  (:func:`leaderboard.aggregate.check_runs` over the combined runs); between two directories the
  message names both and the ``--label`` option. Runs of one experiment found in two directories
  (other seeds of the same run ids) make one row; the same run in both is refused.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.names import check_label
from empathy_zoo.result_file import read_folder
from leaderboard.aggregate import check_runs, load_result_files
from leaderboard.budgets import RunBudget, budget_of, budgets_of, shows_evaluation
from leaderboard.row_names import (
    check_reserved_label,
    dqn_row_names,
    identical_row_names,
    rename_dqn_rows,
    same_runs_row_names,
)

__all__ = ["BUDGET_SEPARATOR", "ResultsDir", "ResultSet", "load_results_dirs", "parse_label_option", "parse_label_options"]

BUDGET_SEPARATOR = " · "
"""Between a row's label and its budget, where the leaderboard holds several budgets."""


@dataclass(frozen=True)
class ResultsDir:
    """One results directory read into a leaderboard, as its header names it."""

    path: str
    """The directory as it was given."""
    prefix: str | None
    """What its labels were prefixed with (``None``: nothing)."""
    runs: int
    """Result files read from it."""
    versions: tuple[str, ...]
    """The empathy-zoo versions its result files record, sorted (empty: none records one)."""
    commits: tuple[str, ...]
    """The git commits its result files record, sorted (empty: none records one)."""
    budgets: tuple[RunBudget, ...]
    """The training budgets of its runs, ascending."""


@dataclass(frozen=True)
class ResultSet:
    """The runs of one leaderboard, with where they were read from."""

    results: list[RunResult]
    """Every run, its label prefixed and (with several budgets) ending with its budget."""
    directories: tuple[ResultsDir, ...]
    """The directories read, in the order given."""
    budgets: tuple[RunBudget, ...]
    """The training budgets of all runs, ascending."""
    origins: tuple[str, ...]
    """The directory (as given) each run of :attr:`results` was read from."""
    renamed: Mapping[tuple[str, str], str] = field(default_factory=dict)
    """``{(table env, label in the result files): shown name}`` of the DQN reference rows shown
    as DQN (:func:`leaderboard.row_names.dqn_row_names`; empty without ``dqn_named``)."""

    def row_directories(self) -> dict[tuple[str, str], tuple[str, ...]]:
        """The directories each row's runs (``(variant, label)``) were read from, in the order given."""
        order = [directory.path for directory in self.directories]
        rows: dict[tuple[str, str], set[str]] = {}
        for result, origin in zip(self.results, self.origins, strict=True):
            rows.setdefault((result.table_env, result.method_label), set()).add(origin)
        return {row: tuple(sorted(found, key=order.index)) for row, found in rows.items()}

    @property
    def budget_in_labels(self) -> bool:
        """Whether the labels end with their budget: the runs have more than one."""
        return len(self.budgets) > 1

    @property
    def budget_with_evaluation(self) -> bool:
        """Whether a budget's text names its evaluation (:func:`leaderboard.budgets.shows_evaluation`)."""
        return shows_evaluation(self.budgets)

    def budget_text(self, budget: RunBudget) -> str:
        """``budget`` as the leaderboard writes it."""
        return budget.text(self.budget_with_evaluation)


def parse_label_option(text: str) -> tuple[str, str]:
    """``"DIR=PREFIX"`` (a ``--label`` option) as ``(DIR, PREFIX)``, split at the last ``=`` (a
    directory's name may hold one, a prefix none); ``ValueError`` if it is not that."""
    directory, equals, prefix = text.rpartition("=")
    if not equals or not directory or not prefix.strip():
        raise ValueError(f"--label takes DIR=PREFIX (a results directory and the prefix of its labels), got {text[:200]!r}")
    return directory, check_label(prefix.strip(), f"--label {directory[:200]}=: the prefix")


def parse_label_options(options: Sequence[str] | None) -> dict[str | os.PathLike[str], str]:
    """``{directory: prefix}`` of the ``--label DIR=PREFIX`` options (:func:`parse_label_option`);
    a directory given twice is refused."""
    labels: dict[str | os.PathLike[str], str] = {}
    for option in options or ():
        directory, prefix = parse_label_option(option)
        if directory in labels:
            raise ValueError(f"--label {directory}= is given twice ({labels[directory]!r} and {prefix!r})")
        labels[directory] = prefix
    return labels


def _prefixes(given: Sequence[str], dirs: Sequence[Path], labels: Mapping[str | os.PathLike[str], str]) -> list[str | None]:
    prefixes: list[str | None] = [None] * len(given)
    named: dict[Path, str | os.PathLike[str]] = {}
    for directory, prefix in labels.items():
        where = read_folder(directory)
        if where in named:  # (DIR and DIR/runs are one directory: a second prefix would drop the first)
            raise ValueError(
                f"--label {directory}={prefix}: {directory} is the directory {named[where]} is, which has a prefix "
                f"already ({labels[named[where]]!r}); give one --label per directory"
            )
        named[where] = directory
        if where not in dirs:
            read = ", ".join(given)
            split = (
                f" (the option is split at its last '=': a prefix holds none, so {directory} is read as the directory)"
                if "=" in os.fspath(directory)
                else ""
            )
            raise ValueError(
                f"--label {directory}={prefix}: {directory} is not one of the results directories read ({read}){split}"
            )
        if not isinstance(prefix, str) or not prefix.strip():
            raise ValueError(f"--label {directory}: the prefix must be a non-empty one-line text, got {prefix!r}")
        prefixes[dirs.index(where)] = check_label(prefix.strip(), f"--label {directory}=: the prefix")
    return prefixes


def _versions(runs: Sequence[RunResult]) -> tuple[str, ...]:
    return tuple(sorted({run.version for run in runs if run.version}))


def _commits(runs: Sequence[RunResult]) -> tuple[str, ...]:
    return tuple(sorted({run.commit for run in runs if run.commit}))


def load_results_dirs(
    results_dirs: Sequence[str | os.PathLike[str]],
    labels: Mapping[str | os.PathLike[str], str] | None = None,
    *,
    dqn_named: bool = False,
) -> ResultSet:
    """Every run of every directory of ``results_dirs`` (each as
    :func:`leaderboard.aggregate.load_results` reads it), labels prefixed by ``labels``
    (``{directory: prefix}``) and, where the runs have several budgets, ending with their budget;
    with ``dqn_named``, a DQN reference row's label is first its shown name (``DQN``:
    :mod:`leaderboard.row_names`).

    ``ValueError`` for no directory, a directory given twice, a ``labels`` key that is not one of
    them, a directory :func:`~leaderboard.aggregate.load_results` refuses, and runs of two
    experiments in one row or one run read twice (:func:`leaderboard.aggregate.check_runs`); when
    those come from two directories, the message names both and the ``--label`` option.
    """
    given = [os.fspath(directory) for directory in results_dirs]
    dirs = [Path(directory) for directory in given]
    if not dirs:
        raise ValueError("no results directory to read")
    resolved_dirs = [read_folder(directory) for directory in dirs]  # (DIR and DIR/runs are one directory)
    for i, directory in enumerate(resolved_dirs):
        if directory in resolved_dirs[:i]:
            raise ValueError(f"results directory {given[i]} is given twice (as {given[resolved_dirs.index(directory)]} too)")
    prefixes = _prefixes(given, resolved_dirs, labels or {})
    files = [(i, path, result) for i, directory in enumerate(dirs) for path, result in load_result_files(directory)]
    budgets = budgets_of(result for _, _, result in files)
    with_evaluation = shows_evaluation(budgets)

    def label(i: int, result: RunResult, core: str) -> str:
        """``core`` (a run's label, or its shown name) with the directory's prefix and the run's budget."""
        prefixed = core if prefixes[i] is None else f"{prefixes[i]} {core}"
        shown = prefixed + (BUDGET_SEPARATOR + budget_of(result).text(with_evaluation) if len(budgets) > 1 else "")
        # (a prefix and a label of at most 200 characters each can make one longer than a label may be)
        return check_label(shown, f"--label {given[i]}: the label of run {result.run_id} with its prefix")

    if dqn_named:  # (a label that reads as a name the page gives, where no prefix sets it apart)
        for i, path, result in files:
            if prefixes[i] is None:
                check_reserved_label(result, path)
    read = [(i, path, replace(result, method_label=label(i, result, result.method_label))) for i, path, result in files]
    try:  # (on the labels of the result files: a clash names what a user finds in them)
        check_runs([(path, result) for _, path, result in read])
    except ValueError as error:
        first, second = _clashing_dirs(read)
        if first == second:
            raise
        raise ValueError(
            f"{error}. They come from two results directories, {given[first]} and {given[second]}: to table both "
            f"without editing a result file, prefix one directory's labels (--label {given[second]}=PREFIX; "
            "Python: labels={directory: prefix})"
        ) from None
    renamed = (
        {
            **identical_row_names(result for _, _, result in files),
            **same_runs_row_names(result for _, _, result in files),
            **dqn_row_names(result for _, _, result in files),
        }
        if dqn_named
        else {}
    )
    if renamed:
        shown = rename_dqn_rows([result for _, _, result in files], renamed)
        read = [
            (i, path, replace(result, method_label=label(i, result, named.method_label)))
            for (i, path, result), named in zip(read, shown, strict=True)
        ]
    directories = tuple(
        ResultsDir(
            path=directory,
            prefix=prefixes[i],
            runs=len(mine),
            versions=_versions(mine),
            commits=_commits(mine),
            budgets=budgets_of(mine),
        )
        for i, directory in enumerate(given)
        for mine in [[result for j, _, result in read if j == i]]
    )
    return ResultSet([result for _, _, result in read], directories, budgets, tuple(given[i] for i, _, _ in read), renamed)


def _clashing_dirs(read: Sequence[tuple[int, Path, RunResult]]) -> tuple[int, int]:
    """The directories of the first two runs that share a row but not an experiment, or are
    the same run (each directory passed these checks on its own)."""
    rows: dict[tuple[str, str], tuple[str, int]] = {}
    runs: dict[tuple[str, str, int], int] = {}
    for i, _, result in read:
        row = (result.table_env, result.method_label)
        experiment, first = rows.setdefault(row, (result.experiment, i))
        if experiment != result.experiment:
            return first, i
    for i, _, result in read:
        first = runs.setdefault((result.table_env, result.method_label, result.seed), i)
        if first != i:
            return first, i
    return 0, 0
