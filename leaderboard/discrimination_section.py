"""The leaderboard's "Discrimination" section: which task of these runs tells which two methods apart.

For every task of the runs (an environment's own variant) that has a shipped exact separation
table (``docs/results/separation/<task>.json``, :data:`leaderboard.separation_reading.TABLES`),
and every pair of methods with trained rows on at least one such task, a row: per task, what the
exact optima say of the pair (:mod:`baselines.discrimination`, at ε = 0.01, a method with β at
β = 0.5) and, after ``;``, what the runs say (:mod:`leaderboard.trained_discrimination`: final
greedy harms, seed against seed, the leaderboard's test at 5 %, unadjusted). A leaderboard whose
runs are on no such task, or of fewer than two of the tables' methods, has no such section.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.markdown_escape import markdown_text
from leaderboard.page import Paragraph, Section, Table

__all__ = ["EPSILON", "SECTION_TITLE", "discrimination_section"]

SECTION_TITLE = "Discrimination: which task tells which methods apart"
EPSILON = 0.01
"""The ε of the exact pairs read (the discrimination page's)."""


def _column(task: str, table: Mapping[str, Any]) -> str:
    """A task's column heading; a table of another variant than the default (Sharing's, smaller so
    that it can be enumerated) says which."""
    arguments = table.get("arguments") or []
    shown = ", ".join(f"{pair[0]}={pair[1]}" for pair in arguments if isinstance(pair, list) and len(pair) == 2)
    return f"{task} (exact: {shown})" if shown else task


def discrimination_section(results: Sequence[RunResult], tables_dir: Path | None = None) -> Section | None:
    """The section for ``results`` (see the module page), reading the tables of ``tables_dir``
    (default: the shipped ones); ``None`` where it would hold no pair."""
    from baselines.discrimination import TableIndex
    from baselines.separation_file import read_separation_table
    from leaderboard.separation_reading import TABLES, can_harm
    from leaderboard.trained_discrimination import method_harms, trained_cells

    folder = TABLES if tables_dir is None else tables_dir
    envs = sorted({run.env for run in results if (run.variant or run.env) == run.env})
    tables = {env: read_separation_table(folder / f"{env}.json") for env in envs if os.path.lexists(folder / f"{env}.json")}
    if not tables:
        return None
    indexes = {task: TableIndex.of(table, task) for task, table in tables.items()}
    selfish = {str(row["method"]): row.get("selfishness") is not None for table in tables.values() for row in table["rows"]}
    harms, shared = method_harms(results, selfish)
    ran = {key for key in harms if key[0] in tables}
    methods = list(dict.fromkeys(m for index in indexes.values() for m in index.rows if any((t, m) in ran for t in tables)))
    tasks = list(tables)
    trained = trained_cells(tasks, methods, harms, {task: can_harm(task) for task in tasks})
    rows = []
    for i, first in enumerate(methods):
        for second in methods[i + 1 :]:
            if not any((task, first) in ran and (task, second) in ran for task in tasks):
                continue
            cells = []
            for task in tasks:
                text = indexes[task].cell(first, second, EPSILON).text()
                part = trained.get((task, first, second))
                cells.append(text if part is None else f"{text}; {part.text()}")
            rows.append([f"{first} / {second}", *cells])  # (method names: the tables' and the runs')
    if not rows:
        return None
    intro = (
        f"Each pair of methods with trained rows here, on each task with an exact separation table (docs/separation.md). "
        f"Before `;`: the exact optima (ε = {EPSILON:g}, β = 0.5; `separated (N states, Δharms x)`: their policies differ in N "
        "reachable states, x = harms of the first − the second). After `;`: these runs, final greedy harms seed against "
        f"seed, the permutation test at 5 %, unadjusted (cells tested: {len(trained)}; where runs do not differ, about one in "
        "twenty reads separated by chance); P = the probability that a seed of the first harms fewer than one of the second. "
        "A column whose exact table is of a smaller variant names it. "
        "The whole matrix: `empathy-zoo analyse discrimination --results DIR`."
    )
    if shared:
        intro += " Not read, as two of their rows share a seed on one task: " + ", ".join(markdown_text(m) for m in shared) + "."
    header = ["Pair", *(_column(task, tables[task]) for task in tasks)]
    return Section(SECTION_TITLE, [Paragraph(intro, note=True), Table(header, rows, left_columns=len(header))])
