"""What the leaderboard calls its DQN reference rows: "DQN", whatever their result files label them.

A row is a DQN reference when every one of its runs is, as its result file's description says
(``config.description.dqn_reference``: :func:`leaderboard.run_facts.is_dqn_reference`): plain DQN
on the environment's reward, the row every P(improves on DQN) compares the others with. Empathic
DQN at β = 1 is one, and its runs are labelled ``"Empathic DQN (β=1)"`` in their result files
(the label is part of a run's identity, and never rewritten in a file); the leaderboard shows such
a row as **DQN** in its tables, figures and legends, and says which labels it renamed
(:func:`renaming_note`).

Where one variant has several DQN reference rows (a ``dqn`` run and an ``empathic_dqn`` β = 1 run,
say), each keeps apart: a row labelled ``DQN`` stays ``DQN``, another is shown as ``"DQN, as
<its label>"`` (``"DQN, as Empathic DQN (β=1)"``). A name another row of the variant already has
is never given: where one would be, that variant's rows keep their labels.
"""

from __future__ import annotations

import unicodedata
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from empathy_zoo.experiment.records import RunResult
from leaderboard.label_skeleton import skeleton
from leaderboard.run_facts import is_dqn_reference

__all__ = [
    "DQN_NAME",
    "check_reserved_label",
    "reserved_label_reason",
    "IDENTICAL_MARK",
    "dqn_row_names",
    "identical_row_names",
    "SAME_RUNS_MARK",
    "same_runs_row_names",
    "rename_dqn_rows",
    "dqn_rows_of",
    "renaming_note",
]

DQN_NAME = "DQN"
"""What a DQN reference row is called."""


def _ends_in_a_mark(label: str) -> bool:
    """Whether ``label`` (a :func:`~leaderboard.label_skeleton.skeleton`) ends as a mark the
    leaderboard appends does: a mathematical symbol (``≡``, ``=``, ``≣``, …), then ``dqn`` or
    ``dqn's runs``."""
    for tail in (skeleton(DQN_NAME), skeleton(SAME_RUNS_MARK.split("=", 1)[1])):
        if label.endswith(tail) and len(label) > len(tail) and unicodedata.category(label[-len(tail) - 1]) == "Sm":
            return True
    return False


def reserved_label_reason(label: str, dqn_reference: bool) -> str | None:
    """Why ``label`` cannot name a row of runs (``dqn_reference``: whether they are the DQN
    reference), or ``None``: it reads as a name the leaderboard gives (:func:`check_reserved_label`)."""
    shape = skeleton(label)
    if _ends_in_a_mark(shape):
        return "ends as a mark the leaderboard gives a row it finds to train as DQN (“≡ DQN”, “= DQN's runs”)"
    if (shape == skeleton(DQN_NAME) or shape.startswith(skeleton(f"{DQN_NAME}, as"))) and not dqn_reference:
        return f"reads as {DQN_NAME!r}, the leaderboard's name of the DQN reference, and this run is none"
    return None


def check_reserved_label(run: RunResult, path: Path) -> None:
    """Refuse (``ValueError`` naming the file) a run whose label reads as a name the leaderboard
    gives (:func:`~leaderboard.label_skeleton.skeleton`: lookalike letters, case, marks and
    spaces aside): ``DQN`` or ``DQN, as …`` on a run that is no DQN reference, or a label ending
    as a mark the leaderboard appends does (:data:`IDENTICAL_MARK`, :data:`SAME_RUNS_MARK`). The
    page would name the wrong row as the reference, or mark a row it did not mark."""
    why = reserved_label_reason(run.method_label, is_dqn_reference(run))
    if why is None:
        return
    raise ValueError(
        f"result file {path}: its label {run.method_label!r} {why} (config.description.dqn_reference); "
        "prefix the directory's labels (--label DIR=PREFIX) to table it"
    )


def _qualified(label: str) -> str:
    return label if label == DQN_NAME else f"{DQN_NAME}, as {label}"


def dqn_row_names(results: Iterable[RunResult]) -> dict[tuple[str, str], str]:
    """``{(table env, label): shown name}`` of every DQN reference row of ``results`` (labels as
    their result files have them) whose shown name differs from its label (see the module page)."""
    rows: dict[tuple[str, str], bool] = {}
    for run in results:
        key = (run.table_env, run.method_label)
        rows[key] = rows.get(key, True) and is_dqn_reference(run)
    names: dict[tuple[str, str], str] = {}
    for env in sorted({env for env, _ in rows}):
        references = sorted(label for (e, label), reference in rows.items() if e == env and reference)
        others = {label for (e, label), reference in rows.items() if e == env and not reference}
        if not references:
            continue
        shown = {label: DQN_NAME if len(references) == 1 else _qualified(label) for label in references}
        if len(set(shown.values())) < len(shown) or set(shown.values()) & others:
            continue  # (a name another row has: this variant's rows keep their labels)
        names.update({(env, label): name for label, name in shown.items() if name != label})
    return names


IDENTICAL_MARK = " ≡ DQN"
"""Appended to the name of a row whose method trains as DQN by construction on its environment."""


def identical_row_names(results: Iterable[RunResult]) -> dict[tuple[str, str], str]:
    """``{(table env, label): label ≡ DQN}`` of every row of ``results`` whose method says it trains
    as DQN by construction on the run's environment (``Method.identical_to``: Be Considerate in
    Sharing, the harm penalty in Sharing, …); a method the registry does not hold is not marked."""
    from baselines.registry import METHODS  # (what a method is by construction is the registry's fact)

    names: dict[tuple[str, str], str] = {}
    for run in results:
        method = METHODS.get(run.method)
        other = method.identical_to.get(run.env) if method is not None else None
        label = run.method_label
        if other is not None and other[0] == "dqn" and not label.endswith(IDENTICAL_MARK):
            names[run.table_env, label] = label + IDENTICAL_MARK
    return names


SAME_RUNS_MARK = " = DQN's runs"
"""Appended to the name of a row whose every run equals the DQN run of its seed, though its method
does not train as DQN by construction there."""
OWN_COLUMNS = frozenset({"lambda"})
"""Training columns a method records beside the shared metrics (the Lagrangian's λ): left out of
the comparison with DQN."""


def _same_columns(run: RunResult, other: RunResult) -> bool:
    """The two runs' training columns (but :data:`OWN_COLUMNS`) and evaluations are equal, value for value."""
    mine = {key: value for key, value in run.train.columns().items() if key not in OWN_COLUMNS}
    theirs = {key: value for key, value in other.train.columns().items() if key not in OWN_COLUMNS}
    return mine.keys() == theirs.keys() and all(np.array_equal(mine[key], theirs[key]) for key in mine) and run.eval == other.eval


def same_runs_row_names(results: Iterable[RunResult]) -> dict[tuple[str, str], str]:
    """``{(table env, label): label = DQN's runs}`` of every row of ``results`` that is no DQN
    reference and whose every run has the training and evaluation columns of the DQN reference run
    of its table, seed and budget, where such a run exists for each: a method that trained as DQN
    in fact (Be Considerate where no episode paid its bonus). Rows marked by construction
    (:func:`identical_row_names`) are left to that mark."""
    runs = list(results)
    by_construction = identical_row_names(runs)
    dqn: dict[tuple[str, int, int], RunResult] = {}
    for run in runs:
        if is_dqn_reference(run):
            dqn.setdefault((run.table_env, run.seed, run.steps), run)
    rows: dict[tuple[str, str], bool] = {}
    for run in runs:
        key = (run.table_env, run.method_label)
        if is_dqn_reference(run) or key in by_construction:
            continue
        reference = dqn.get((key[0], run.seed, run.steps))
        rows[key] = rows.get(key, True) and reference is not None and _same_columns(run, reference)
    return {key: key[1] + SAME_RUNS_MARK for key, same in rows.items() if same}


def rename_dqn_rows(results: Sequence[RunResult], names: Mapping[tuple[str, str], str]) -> list[RunResult]:
    """``results`` with the label of every run of a renamed row (``names``, from
    :func:`dqn_row_names`) replaced by its shown name (a new record: :func:`dataclasses.replace`);
    the others as they are (nothing is written)."""
    renamed = []
    for run in results:
        name = names.get((run.table_env, run.method_label))
        renamed.append(run if name is None else replace(run, method_label=name))
    return renamed


def dqn_rows_of(results: Iterable[RunResult]) -> set[tuple[str, str]]:
    """``{(table env, label)}`` of the rows of ``results`` whose every run is a DQN reference."""
    rows: dict[tuple[str, str], bool] = {}
    for run in results:
        key = (run.table_env, run.method_label)
        rows[key] = rows.get(key, True) and is_dqn_reference(run)
    return {key for key, reference in rows.items() if reference}


def renaming_note(names: Mapping[tuple[str, str], str], has_reference: bool = True, escape: Callable[[str], str] = str) -> str:
    """The sentence that says which rows are the DQN reference and, of the rows shown as DQN, how
    their result files label them (each label through ``escape``: Markdown's, say); ``""`` where
    the leaderboard has no DQN reference row."""
    if not has_reference and not names:
        return ""
    text = (
        "Rows named DQN are the DQN reference, the rows P(improves on DQN) compares every other row with: runs "
        "their result files describe as plain DQN on the environment's reward (config.description.dqn_reference)."
    )
    marks = (IDENTICAL_MARK, SAME_RUNS_MARK)
    pairs = list(dict.fromkeys((label, name) for (_, label), name in sorted(names.items()) if not name.endswith(marks)))
    if any(name.endswith(IDENTICAL_MARK) for name in names.values()):
        text += (
            f" Rows marked{IDENTICAL_MARK} train as DQN by construction on their environment: their runs equal DQN's "
            "seed for seed (`empathy-zoo methods` says why)."
        )
    if any(name.endswith(SAME_RUNS_MARK) for name in names.values()):
        text += (
            f" Rows marked{SAME_RUNS_MARK} are not DQN by construction, but their runs equal DQN's seed for seed "
            "in every training and evaluation column: on these runs the method trained as DQN."
        )
    if pairs:
        shown = "; ".join(f"{escape(name)} is labelled “{escape(label)}”" for label, name in pairs)
        text += f" In their result files (and run ids) these rows keep their own labels: {shown}."
    return text
