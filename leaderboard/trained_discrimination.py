"""# The discrimination matrix with trained runs: which pairs the runs themselves tell apart

Adds to each cell of the exact discrimination matrix (:mod:`baselines.discrimination`) what
trained runs say of the same pair on the same task. The rule was fixed before the scenarios
profile's runs were read (docs/results/scenarios/READING.md, addendum "the matrix's trained
cells").

**The rule.** For a task whose robot can harm, and two methods that both have trained runs of
the task's own variant (a method with a β at β = 0.5, as the exact matrix reads it), trained in
the world the task's table models (every environment argument, ``max_cycles`` included, and
partner: :func:`leaderboard.separation_reading.in_table_world`; a run of another world is named in
the page's notes, never read against the table): each seed's
score is its mean harms per episode over the final greedy evaluation
(:func:`leaderboard.separation_reading.final_harms`). The two methods' seeds are compared by the
leaderboard's own test (:func:`leaderboard.improvement.improvement_interval` and
:func:`~leaderboard.improvement.improvement_verdict`: the exact two-sided permutation test at
5 %, fewer harms better).

* The interval excludes 0.5: **separated in trained runs**, with the probability that a seed of
  the first harms fewer than one of the second.
* It contains 0.5: **no difference detected**. At 10 seeds a side the test marks only
  probabilities of at most 0.24 or at least 0.76.
* The seed counts cannot reach the level: **undecidable**.
* Either method without runs of the task, or a task whose robot cannot harm (its harms are 0 by
  construction): no trained cell.

Each cell is a test at 5 %, unadjusted, as the leaderboard's marks are: among pairs whose runs do
not differ, about one cell in twenty is marked by chance. The page counts the cells tested.

    empathy-zoo analyse discrimination --results DIR [--results DIR ...]   # -> the page with trained cells

Everything but :func:`main` is a pure function of tables and per-seed arrays.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from baselines.discrimination import TableIndex
from baselines.discrimination import main as discrimination_main
from empathy_zoo.experiment.records import RunResult
from leaderboard.improvement import TOO_FEW_SEEDS, improvement_interval, improvement_verdict

__all__ = [
    "NO_DIFFERENCE",
    "SEPARATED",
    "UNDECIDABLE",
    "TrainedCell",
    "cells_of_results",
    "method_harms",
    "trained_cell",
    "trained_cells",
    "main",
]

SEPARATED, NO_DIFFERENCE, UNDECIDABLE = "separated in trained runs", "no difference detected", "undecidable"


@dataclass(frozen=True)
class TrainedCell:
    """What trained runs say of one pair of methods on one task."""

    kind: str
    """:data:`SEPARATED`, :data:`NO_DIFFERENCE` or :data:`UNDECIDABLE`."""
    probability: float
    """P(a seed of the first method harms fewer than one of the second), ties halved."""
    seeds: tuple[int, int]
    """Seeds read of the first and the second method."""

    @property
    def separated(self) -> bool:
        """Whether the runs separate the pair."""
        return self.kind == SEPARATED

    def text(self) -> str:
        """The cell's trained part, as the matrix shows it."""
        if self.kind == UNDECIDABLE:
            return f"trained: undecidable ({self.seeds[0]} vs {self.seeds[1]} seeds)"
        return f"trained: {'separated' if self.separated else 'no difference detected'}, P {self.probability:.2f}"


def trained_cell(first: Sequence[float], second: Sequence[float]) -> TrainedCell:
    """The rule (see the module page) on the per-seed harms of two methods' runs."""
    probability, low, high = improvement_interval(first, second, higher_is_better=False)
    verdict = improvement_verdict(low, high, len(first), len(second))
    seeds = (len(first), len(second))
    if verdict == TOO_FEW_SEEDS or math.isnan(probability):
        return TrainedCell(UNDECIDABLE, probability, seeds)
    return TrainedCell(NO_DIFFERENCE if verdict == "no clear difference" else SEPARATED, probability, seeds)


Harms = dict[tuple[str, str], list[float]]
"""Per-seed harms by ``(task, method)``."""


def method_harms(
    results: Sequence[RunResult], selfish: Mapping[str, bool], tables: Mapping[str, Mapping[str, Any]] | None = None
) -> tuple[Harms, list[str]]:
    """``({(task, method): per-seed harms}, methods not read)``: each method's runs read by
    :func:`leaderboard.separation_reading.final_harms` (a method with β at β = 0.5; a run only in
    the world its task's table of ``tables`` models, the default world without them), a run its
    result file describes as standard DQN read as ``dqn`` (the paper's profile trains DQN as Empathic
    DQN at β = 1). A method two of whose rows share a seed on one task (a tuned row beside an
    untuned one) is not read, and listed."""
    from leaderboard.improvement import is_dqn
    from leaderboard.separation_reading import final_harms

    by_method: dict[str, list[RunResult]] = {}
    for run in results:
        method = "dqn" if is_dqn(run) else run.method
        by_method.setdefault(method, []).append(run if method == run.method else dataclasses.replace(run, method=method))
    harms: Harms = {}
    shared = []
    for method, runs in by_method.items():
        try:
            harms.update(final_harms(runs, selfish, tables))
        except ValueError:
            shared.append(method)
    return harms, shared


def trained_cells(
    tasks: Sequence[str], methods: Sequence[str], harms: Mapping[tuple[str, str], Sequence[float]], can_harm: Mapping[str, bool]
) -> dict[tuple[str, str, str], TrainedCell]:
    """``{(task, first, second): cell}`` for every pair of ``methods`` (in their order) on every
    task of ``tasks`` whose robot can harm and where both have runs (``harms``: per-seed harms by
    ``(task, method)``)."""
    cells = {}
    for task in tasks:
        if not can_harm.get(task, False):
            continue
        for i, first in enumerate(methods):
            for second in methods[i + 1 :]:
                a, b = harms.get((task, first), ()), harms.get((task, second), ())
                if a and b:
                    cells[task, first, second] = trained_cell(a, b)
    return cells


def cells_of_results(
    tables: Mapping[str, Mapping[str, Any]], results_dirs: Sequence[Path]
) -> tuple[dict[tuple[str, str, str], TrainedCell], list[str]]:
    """The trained cells of the result files of ``results_dirs`` for the matrix of ``tables``
    (every method of the tables, in their order; a task whose robot can harm), and a note per
    reason some runs were not read (:func:`leaderboard.separation_reading.not_read_notes`) and per
    method whose runs of a task fall in no cell. Runs that make no cell at all are refused."""
    from empathy_zoo.training.heldout import results_of
    from leaderboard.improvement import is_dqn
    from leaderboard.separation_reading import can_harm, not_read_notes, selfish_methods

    results = [result for directory in results_dirs for _, result in results_of(directory)]
    indexes = [TableIndex.of(table, task) for task, table in tables.items()]
    methods = list(dict.fromkeys(method for index in indexes for method in index.rows))
    selfish = selfish_methods(tables)
    harms, shared = method_harms(results, selfish, tables)
    if shared:
        raise ValueError(f"two rows of {', '.join(shared)} share a seed on one task; give one results directory per row")
    tasks = list(tables)
    as_read = [dataclasses.replace(run, method="dqn") if is_dqn(run) else run for run in results]  # (as method_harms reads them)
    notes = not_read_notes(as_read, selfish, tasks, methods, tables)
    cells = trained_cells(tasks, methods, harms, {task: can_harm(task) for task in tasks})
    if not cells:  # (every cell "0 of 0" would read as "separates nothing")
        read = ", ".join(sorted({f"{method} on {task}" for task, method in harms if task in tables})) or "none"
        unread = "".join(f"; {note}" for note in notes)  # (why the others were not: a run of another world named)
        raise ValueError(
            f"the runs of --results {' '.join(map(str, results_dirs))} make no cell: no two methods of the tables have runs "
            f"of one task whose robot can harm (runs read: {read}{unread}); give runs of DQN and a method on one task"
        )
    in_cells = {(task, method) for task, first, second in cells for method in (first, second)}
    for (task, method), values in sorted(harms.items()):
        if (task, method) not in in_cells and method in methods and can_harm(task):
            notes.append(f"{len(values)} runs of {method} on {task}: in no cell (no other method of the tables has runs there)")
    return cells, notes


def main(argv: Sequence[str] | None = None) -> int:
    """``empathy-zoo analyse discrimination [DIR] [--epsilon E] [--results RESULTS ...] [--out FILE]``."""
    return discrimination_main(argv, cells_of_results, prog="empathy-zoo analyse discrimination")


if __name__ == "__main__":
    raise SystemExit(main())
