"""The legends under the leaderboard's tables: the coverage their intervals were measured to have,
what P(improves on DQN) means, and how many of a page's ▲ / ▼ survive adjustment as a family.

Each is a sentence of Markdown (commands in backticks) built from what the tables show; the page
builders (:mod:`leaderboard.leaderboard_page`, :mod:`leaderboard.versus_dqn`) place them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

from leaderboard.improvement import TOO_FEW_SEEDS, VERDICT_MARKS, VERDICT_NOTE, Improvement, can_decide, smallest_decidable_seeds
from leaderboard.measured_coverage import SEED_TARGET, MeasuredCoverage, committed_coverage, seeds_needed
from leaderboard.multiplicity import (
    FAMILY_LEVEL,
    HOLM_MARK,
    benjamini_hochberg_adjusted,
    expected_false_marks,
    holm_adjusted,
    rejected,
)

__all__ = [
    "TWO_LEVEL_COMMAND",
    "IMPROVEMENT_NOTE",
    "holm_survivors",
    "multiplicity_note",
    "coverage_note",
    "resolve_coverage",
]

TWO_LEVEL_COMMAND = "python benchmarks/interval_coverage.py --two-level"
"""The command that measures the coverage the legends print (:mod:`leaderboard.measured_coverage`)."""
IMPROVEMENT_NOTE = (
    "P(improves on DQN): the probability that a run of the method does better than a run of DQN in that "
    "metric (fewer harms is better; 0.5 is a tie), over every pair of runs. ▲ / ▼: better / worse than DQN "
    "by the exact two-sided Mann–Whitney permutation test at 5 % (every split of the runs counted, midranks "
    "for ties); [interval]: the one that inverts that test (P ± the test's critical distance from 0.5), so "
    f"▲ / ▼ stand exactly where it lies wholly above / below 0.5. {VERDICT_MARKS[TOO_FEW_SEEDS]}: "
    f"{TOO_FEW_SEEDS} — with n runs against m where 2 / C(n + m, n) > 5 % (3 against 3: p = 0.1), even every "
    "run of one side beating every run of the other is not rare enough, so no ▲ or ▼ can be given and the "
    f"interval always contains 0.5; {smallest_decidable_seeds()} against {smallest_decidable_seeds()} (or 5 "
    f"against 3) is the least that can give one. {VERDICT_NOTE} "
    "IQM: the method's interquartile mean over seeds (its mean below 4 seeds)."
)


def _family(cells: Sequence[Improvement]) -> list[int]:
    """The indices of ``cells`` that can give a ▲ or ▼ (seed counts that can reach 5 %, a finite p):
    the family of tests a page's marks come from."""
    return [i for i, cell in enumerate(cells) if can_decide(cell.n_seeds, cell.n_baseline_seeds) and math.isfinite(cell.p_value)]


def holm_survivors(cells: Sequence[Improvement], level: float = FAMILY_LEVEL) -> list[bool]:
    """Per cell of ``cells`` (a page's), whether its ▲ / ▼ survives Holm's adjustment
    (:func:`leaderboard.multiplicity.holm_adjusted`) over the cells that can give one, at family-wise ``level``."""
    family = _family(cells)
    adjusted = holm_adjusted([cells[i].p_value for i in family])
    survives = [False] * len(cells)
    for i, keep in zip(family, rejected(adjusted, level), strict=True):
        survives[i] = bool(keep) and cells[i].verdict in ("better", "worse")
    return survives


def _number(value: float) -> str:
    return f"{value:.2g}" if value < 10 else f"{value:.0f}"


def multiplicity_note(
    cells: Sequence[Improvement], level: float = FAMILY_LEVEL, where: str = "this page's P(improves on DQN) tables hold"
) -> str:
    """The sentence on a page's ▲ / ▼ as a family (``where`` names the tables, ending in a verb):
    how many false marks its cells would give where no method differed from DQN, and how many
    marks survive Holm (:data:`HOLM_MARK`) and Benjamini–Hochberg over them."""
    family = _family(cells)
    marked = [i for i in family if cells[i].verdict in ("better", "worse")]
    holm = holm_survivors(cells, level)
    bh = rejected(benjamini_hochberg_adjusted([cells[i].p_value for i in family]), level)
    by_bh = sum(1 for i, keep in zip(family, bh, strict=True) if keep and i in marked)
    percent = f"{100 * level:.0f} %"
    smallest = min((2.0 / math.comb(cells[i].n_seeds + cells[i].n_baseline_seeds, cells[i].n_seeds) for i in family), default=0.0)
    out_of_reach = (
        f" No cell can: the smallest p these seed counts can give, {smallest:.2g}, is above {percent} / {len(family)}."
        if family and smallest * len(family) > level + 1e-12
        else ""
    )
    if not family:
        return f"No cell of {where.rsplit(' ', 1)[0]} can give a ▲ or ▼ (too few seeds), so none can be a false mark."
    return (
        f"Many cells, many chances: {where} {len(family)} cells that can give a "
        f"▲ or ▼, so ≈ {_number(expected_false_marks(len(family), level))} false marks expected among {len(family)} "
        f"cells at {percent} if no method differed from DQN at all (each test's size is at most {percent}). "
        f"{HOLM_MARK}: the mark survives Holm's adjustment of the p-values over those {len(family)} cells (family-wise "
        f"{percent}: the chance of even one false {HOLM_MARK} is at most {percent}); {sum(holm)} of the {len(marked)} "
        f"marks do ({by_bh} survive Benjamini–Hochberg at a false discovery rate of {percent}).{out_of_reach}"
    )


def coverage_note(measured: MeasuredCoverage | None, phase: str, metrics: Sequence[str], seeds: Sequence[int]) -> str:
    """The legend of one table (Markdown, the command in backticks): per seed count of its rows, the
    coverage of its interval measured per metric (:class:`leaderboard.measured_coverage.MeasuredCoverage`),
    "not measured" where there is none."""
    if not seeds:
        return ""
    parts = []
    for n in seeds:
        found = {metric: measured.coverage(metric, phase, n) if measured is not None else None for metric in metrics}
        figures = []
        for metric, figure in found.items():
            if figure is not None:
                coverage, flat = figure
                zero = f" ({100 * flat:.0f} % zero-width)" if flat >= 0.005 else ""
                figures.append(f"{metric} {100 * coverage:.1f} %{zero}")
        missing = [metric for metric, figure in found.items() if figure is None]
        if not figures:
            parts.append(f"at {n} seeds: not measured")
            continue
        rest = f"; {', '.join(missing)} not measured" if missing else ""
        parts.append(f"at {n} seeds: {', '.join(figures)}{rest}")
    command = measured.command if measured is not None else TWO_LEVEL_COMMAND
    return (
        f"Coverage of these intervals (nominal 97.5 %, for a claimed 95 %) measured by `{command}` (each shipped "
        f"row's runs resampled, then each drawn run's episodes): {'; '.join(parts)}."
        + _provisional(measured, phase, metrics, seeds)
    )


def _provisional(measured: MeasuredCoverage | None, phase: str, metrics: Sequence[str], seeds: Sequence[int]) -> str:
    """A sentence saying the table's intervals and verdicts are provisional where a row has fewer
    seeds than :func:`~leaderboard.measured_coverage.seeds_needed` asks for its measured metrics
    (``""`` otherwise, or where nothing is measured)."""
    if measured is None:
        return ""
    measured_reads = {(metric, kind) for (metric, kind, _) in measured.entries}
    reads = [(metric, phase) for metric in metrics if (metric, phase) in measured_reads]
    needed = seeds_needed(measured, reads, SEED_TARGET) if reads else None
    if needed is None or min(seeds) >= needed:
        return ""
    return (
        f" With fewer than {needed} seeds these intervals, and the verdicts that read them, are provisional: "
        f"{needed} is the fewest at which every metric here was measured to be covered at least "
        f"{100 * SEED_TARGET:.0f} % (`leaderboard.measured_coverage.seeds_needed`)."
    )


def resolve_coverage(coverage: MeasuredCoverage | Literal["committed"] | None) -> MeasuredCoverage | None:
    """The measured coverage a page quotes: the committed figures for ``"committed"``, else ``coverage``."""
    return committed_coverage() if coverage == "committed" else coverage  # type: ignore[return-value]
