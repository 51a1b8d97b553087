"""The leaderboard's tables and their legends, and its CSV, from computed scores.

Formatting only: every number comes from :func:`leaderboard.aggregate.score_runs`. What a cell
says (:func:`format_mean`), the rows of each table (:func:`table_rows`, :func:`improvement_sections`)
and the page's :class:`Provenance` (command, package version, commit); the long-format CSV
(:func:`csv_text`). The legends under the tables are :mod:`leaderboard.legends`'; the pages are
built of both by :mod:`leaderboard.leaderboard_page`. (:func:`markdown_text` and
:func:`markdown_table` are :mod:`leaderboard.page_markdown`'s, named here too.)
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from empathy_zoo.environments import entry_of
from empathy_zoo.markdown_escape import code_span
from empathy_zoo.metrics import METRIC_DEFINITIONS, METRIC_NAMES
from leaderboard.aggregate import (
    CONFIDENCE,
    DEFAULT_SEED,
    FINAL_FRACTION,
    MEAN_INTERVAL_NOTE,
    MIN_INTERVAL_SEEDS,
    N_RESAMPLES,
    PHASES,
    Score,
    t_level,
)
from leaderboard.budgets import RunBudget, shows_evaluation
from leaderboard.improvement import VERDICT_MARKS, Improvement
from leaderboard.legends import holm_survivors
from leaderboard.multiplicity import HOLM_MARK
from leaderboard.page_markdown import markdown_table, markdown_text
from leaderboard.sources import BUDGET_SEPARATOR, ResultsDir

__all__ = [
    "PHASE_TITLES",
    "SINGLE_SEED_MARK",
    "ZERO_WIDTH_MARK",
    "ZERO_WIDTH_NOTE",
    "CSV_COLUMNS",
    "COMPARISON_CSV_COLUMNS",
    "RowFacts",
    "Provenance",
    "format_interval",
    "format_mean",
    "NO_INTERVAL_NOTE",
    "table_rows",
    "improvement_sections",
    "names_baselines",
    "uncompared_note",
    "markdown_table",
    "markdown_text",
    "table_seeds",
    "csv_text",
]

PHASE_TITLES: dict[str, str] = {
    "eval": "Final greedy evaluation",
    "train_final10": "Training, final 10% of episodes",
}
"""Heading of each scored phase."""
SINGLE_SEED_MARK = "†"
"""Marks a method scored on a single seed, whose interval is the point itself."""
ZERO_WIDTH_MARK = "="
"""Marks a mean whose seeds all gave the same value (a zero-width interval), in place of ``[x, x]``."""
ZERO_WIDTH_NOTE = (
    f"{ZERO_WIDTH_MARK} every seed gave this value, so the t interval has zero width: the seeds show no spread, "
    "which does not mean that another seed could not differ (the measured coverage says how often that misleads)."
)
"""The legend of :data:`ZERO_WIDTH_MARK`."""
CSV_COLUMNS: tuple[str, ...] = (
    "env",
    "method_label",
    "method",
    "phase",
    "metric",
    "mean",
    "ci_low",
    "ci_high",
    "n_seeds",
    "metric_definition",
    "command",
    "version",
    "commit",
)
"""Columns of the long-format CSV, one row per (env, method, phase, metric)."""
COMPARISON_CSV_COLUMNS: tuple[str, ...] = ("steps", "eval_interval", "eval_episodes", "results_dirs")
"""Columns added after :data:`CSV_COLUMNS` in a leaderboard of several results directories or
budgets: the row's training budget and the directories its runs were read from (``;``-joined)."""


@dataclass(frozen=True)
class RowFacts:
    """What a leaderboard of several directories or budgets says of one row beyond its scores."""

    budget: RunBudget
    """The training budget of the row's runs."""
    directories: tuple[str, ...]
    """The results directories its runs were read from."""


@dataclass(frozen=True)
class Provenance:
    """Where a leaderboard came from, and how its intervals were computed."""

    command: str
    """The command that produced the leaderboard."""
    version: str
    """Version of the empathy-zoo package."""
    commit: str | None
    """Short git commit, or None when unknown."""
    n_resamples: int = N_RESAMPLES
    confidence: float = CONFIDENCE
    random_state: int = DEFAULT_SEED
    final_fraction: float = FINAL_FRACTION
    directories: tuple[ResultsDir, ...] = ()
    """The results directories read, where the leaderboard names them: one of several directories
    or budgets, or with prefixed labels (empty: one directory, as it is)."""
    budgets: tuple[RunBudget, ...] = ()
    """The training budgets of every run, ascending (named with :attr:`directories`)."""

    def commit_text(self) -> str:
        return self.commit if self.commit else "unknown"

    def method_text(self) -> str:
        """One paragraph explaining what a cell means."""
        measured = f" {MEAN_INTERVAL_NOTE}" if self.confidence == CONFIDENCE else ""
        nominal = t_level(self.confidence)
        return (
            f"Each cell is the mean over seeds [an interval over seeds: the two-sided Student-t interval "
            f"mean ± t·s/√n at {100 * nominal:.1f} % nominal (t the {nominal + (1 - nominal) / 2:.4g} quantile with "
            f"n − 1 degrees of freedom), computed at that level so that it covers the mean in at least "
            f"{100 * self.confidence:.0f} % of cases on skewed data; the coverage measured on the shipped results "
            f"is given under each table].{measured} "
            f"'{PHASE_TITLES['eval']}': mean over the episodes of each run's last greedy evaluation. "
            f"'{PHASE_TITLES['train_final10']}': mean over the last {self.final_fraction:.0%} of each run's "
            "training episodes (at least one)."
        )

    def comparison(self) -> bool:
        """Whether this leaderboard names its directories and budgets (:attr:`directories`)."""
        return bool(self.directories)

    def source_lines(self) -> tuple[str, list[str], str]:
        """``(heading, [one line per directory], budget sentence)``, in Markdown (code spans in backticks)."""
        with_evaluation = shows_evaluation(self.budgets)
        lines = []
        for directory in self.directories:
            prefix = f", labels prefixed {code_span(directory.prefix)}" if directory.prefix else ""
            budgets = "; ".join(budget.text(with_evaluation) for budget in directory.budgets)
            versions = ", ".join(markdown_text(version) for version in directory.versions) or "not recorded"
            commits = ", ".join(code_span(commit) for commit in directory.commits) or "not recorded"
            where = code_span(str(directory.path))
            lines.append(f"{where}{prefix}: {directory.runs} runs, {budgets}; empathy-zoo {versions}, commit {commits}")
        evaluation = " (`eval 10,000 × 10`: a greedy evaluation of 10 episodes every 10,000 steps)"
        if len(self.budgets) > 1:
            budget = (
                f"The runs have {len(self.budgets)} training budgets: each row's label ends with its budget "
                f"(`{BUDGET_SEPARATOR.strip()} {self.budgets[0].text(with_evaluation)}`), rows of different budgets are "
                "never merged, and P(improves on DQN) compares a row only with the DQN rows of its variant and budget"
                f"{evaluation if with_evaluation else ''}."
            )
        elif self.budgets:
            budget = f"Every run has the same training budget: {self.budgets[0].text(True)}{evaluation}."
        else:
            budget = ""
        heading = (
            f"Read from {len(self.directories)} results director{'y' if len(self.directories) == 1 else 'ies'} "
            "(with the versions and commits their result files record):"
        )
        return heading, lines, budget


NO_INTERVAL_NOTE = (
    f"(n=1: no interval), (n=2: no interval): a mean over fewer than {MIN_INTERVAL_SEEDS} seeds is printed without "
    "its interval, which would not mean anything: with one seed there is no spread to measure, and with two the "
    "Student-t interval has one degree of freedom (t = 25.5 at 97.5 %), so it spans about ±18 standard deviations, "
    f"mostly the metric's whole range; {MIN_INTERVAL_SEEDS} seeds is the least at which its coverage was measured "
    "(94–98 % on simulated continuous data; on the shipped results, under each table)."
)
"""The legend of a cell with too few seeds for an interval (:func:`format_mean`)."""


def format_interval(mean: float, low: float, high: float, digits: int = 2) -> str:
    """``"mean [low, high]"`` with ``digits`` decimals; ``"n/a"`` when the mean is NaN."""
    if math.isnan(mean):
        return "n/a"
    return f"{mean:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"


def format_mean(mean: float, low: float, high: float, n_seeds: int, digits: int = 2, mark_equal: bool = False) -> str:
    """A mean over ``n_seeds`` seeds with its interval (:func:`format_interval`), or, below
    :data:`~leaderboard.aggregate.MIN_INTERVAL_SEEDS` seeds, without it: ``"0.50 (n=2: no interval)"``;
    with ``mark_equal``, a zero-width interval (every seed equal) is :data:`ZERO_WIDTH_MARK`: ``"0.50 ="``."""
    if math.isnan(mean):
        return "n/a"
    if n_seeds < MIN_INTERVAL_SEEDS:
        return f"{mean:.{digits}f} (n={n_seeds}: no interval)"
    if mark_equal and low == high:
        return f"{mean:.{digits}f} {ZERO_WIDTH_MARK}"
    return format_interval(mean, low, high, digits)


def table_metrics(env: str, base_env: str | None = None) -> tuple[str, ...]:
    """The metrics that mean something in ``env``'s tables, in order: its entry's
    :attr:`~empathy_zoo.environments.Environment.table_metrics`, else its environment's
    (``base_env``), else none."""
    entry = entry_of(env, base_env)
    return () if entry is None else entry.table_metrics


def env_metrics(env: str, base_env: Mapping[str, str] | None, metrics: Sequence[str]) -> Sequence[str]:
    """The columns of ``env``'s tables: its :func:`table_metrics` when the caller asked for every
    metric (the default), else exactly ``metrics``."""
    if tuple(metrics) != METRIC_NAMES:
        return metrics
    return table_metrics(env, (base_env or {}).get(env)) or metrics


def table_rows(
    scores: Sequence[Score], env: str, phase: str, metrics: Sequence[str] = METRIC_NAMES, digits: int = 2
) -> tuple[list[str], list[list[str]]]:
    """Header and rows of one table: rows are methods (in the order of ``scores``), columns metrics."""
    cells: dict[str, dict[str, Score]] = {}
    for score in scores:
        if score.env == env and score.phase == phase:
            cells.setdefault(score.method_label, {})[score.metric] = score
    header = ["Method", "Seeds", *metrics]
    rows = []
    for label, by_metric in cells.items():
        n_seeds = max(score.n_seeds for score in by_metric.values())
        seeds = f"{n_seeds}{SINGLE_SEED_MARK}" if n_seeds == 1 else str(n_seeds)
        row = [label, seeds]
        for metric in metrics:
            cell = by_metric.get(metric)
            row.append(
                "n/a"
                if cell is None
                else format_mean(cell.mean, cell.ci_low, cell.ci_high, cell.n_seeds, digits, mark_equal=True)
            )
        rows.append(row)
    return header, rows


def improvement_sections(
    cells: Sequence[Improvement], env: str, digits: int = 2, against: bool = False
) -> list[tuple[str, list[str], list[list[str]]]]:
    """``[(phase, header, rows)]`` of ``env``'s probability-of-improvement tables: a row per method
    (and DQN row compared with), a column per metric, each cell ``P [interval] · IQM value``; with
    ``against``, a column ``Against`` names the DQN row and its seeds. ``cells`` are the page's: a
    mark that survives Holm over them (:func:`holm_survivors`) is followed by :data:`HOLM_MARK`."""
    holm = dict(zip(map(id, cells), holm_survivors(cells), strict=True))
    sections = []
    for phase in PHASES:
        mine = [c for c in cells if c.env == env and c.phase == phase]
        metrics = list(dict.fromkeys(c.metric for c in mine))
        rows: dict[tuple[str, str], list[str]] = {}
        first = 3 if against else 2
        for cell in mine:
            named = [f"{cell.baseline_label} ({cell.n_baseline_seeds} seeds)"] if against else []
            row = rows.setdefault(
                (cell.method_label, cell.baseline_label),
                [cell.method_label, *named, str(cell.n_seeds)] + [""] * len(metrics),
            )
            mark = VERDICT_MARKS[cell.verdict] + (HOLM_MARK if holm[id(cell)] else "")
            row[first + metrics.index(cell.metric)] = (
                f"{mark}{' ' if mark else ''}{format_interval(cell.probability, cell.ci_low, cell.ci_high, digits)}"
                f" · IQM {cell.iqm:.{digits}f}"
            )
        if rows:
            sections.append((phase, ["Method", *(["Against"] if against else []), "Seeds", *metrics], list(rows.values())))
    return sections


def names_baselines(provenance: Provenance, cells: Sequence[Improvement]) -> bool:
    """Whether the probability-of-improvement tables name each row's DQN row (column ``Against``):
    in a leaderboard of several directories or budgets, or where a row is compared with more than one."""
    compared: dict[tuple[str, str], set[str]] = {}
    for cell in cells:
        compared.setdefault((cell.env, cell.method_label), set()).add(cell.baseline_label)
    return provenance.comparison() or any(len(baselines) > 1 for baselines in compared.values())


def uncompared_note(uncompared: Sequence[tuple[str, str]], env: str | None, markdown: bool = False) -> str:
    """The sentence naming ``env``'s rows that no DQN row of their variant, world and budget is compared
    with (their labels :func:`markdown_text` with ``markdown``)."""
    labels = [markdown_text(label) if markdown else label for row_env, label in uncompared if row_env == env]
    if not labels:
        return ""
    return "Not compared with DQN (no DQN row of their variant, world and budget): " + ", ".join(labels) + "."


def table_seeds(scores: Sequence[Score], env: str, phase: str) -> list[int]:
    """The seed counts of ``env``'s rows in ``phase`` that show an interval, ascending."""
    rows: dict[str, int] = {}
    for score in scores:
        if score.env == env and score.phase == phase:
            rows[score.method_label] = max(rows.get(score.method_label, 0), score.n_seeds)
    return sorted({n for n in rows.values() if n >= MIN_INTERVAL_SEEDS})


FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")
"""First characters that make a spreadsheet read a cell as a formula."""


def csv_text_cell(value: str) -> str:
    """``value`` as a CSV text cell a spreadsheet shows as text: one starting a formula
    (:data:`FORMULA_STARTS`, e.g. a label ``=HYPERLINK(...)`` from a result file) gets a leading ``'``."""
    return f"'{value}" if value.startswith(FORMULA_STARTS) else value


def _csv_number(value: float) -> str:
    return repr(float(value)) if math.isfinite(value) else ""


def csv_text(scores: Sequence[Score], provenance: Provenance, rows: Mapping[tuple[str, str], RowFacts] | None = None) -> str:
    """Long-format CSV (:data:`CSV_COLUMNS`), one row per score; NaN is an empty cell, a text cell
    that would start a formula is quoted (:func:`csv_text_cell`). With
    ``rows`` (the facts of every ``(env, method_label)``), :data:`COMPARISON_CSV_COLUMNS` follow."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(CSV_COLUMNS + (COMPARISON_CSV_COLUMNS if rows is not None else ()))
    for s in scores:
        facts = [] if rows is None else _facts_cells(rows[(s.env, s.method_label)])
        writer.writerow(
            [
                s.env,
                csv_text_cell(s.method_label),
                csv_text_cell(s.method),
                s.phase,
                s.metric,
                _csv_number(s.mean),
                _csv_number(s.ci_low),
                _csv_number(s.ci_high),
                s.n_seeds,
                METRIC_DEFINITIONS.get(s.metric, ""),
                csv_text_cell(provenance.command),
                provenance.version,
                provenance.commit or "",
                *facts,
            ]
        )
    return buffer.getvalue()


def _facts_cells(facts: RowFacts) -> list[Any]:
    budget = facts.budget
    return [budget.steps, budget.eval_interval or "", budget.eval_episodes or "", csv_text_cell(";".join(facts.directories))]
