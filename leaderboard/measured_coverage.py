"""What the leaderboard's interval of a mean was measured to cover on the shipped results.

``benchmarks/interval_coverage.py --two-level`` resamples every shipped row at two levels (its
runs, then each drawn run's episodes), builds the leaderboard's t interval over the drawn runs'
means and counts how often it contains the row's mean; it writes the figures per metric, phase and
seed count to :data:`COVERAGE_FILE`, which the tables' legends quote (:class:`MeasuredCoverage`).
"""

from __future__ import annotations

import functools
import json
import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

__all__ = [
    "COVERAGE_FILE",
    "ALL_PHASES",
    "SEED_TARGET",
    "MeasuredCoverage",
    "read_measured_coverage",
    "committed_coverage",
    "seeds_needed",
]

COVERAGE_FILE = Path(__file__).resolve().parent / "interval_coverage.json"
"""The committed figures of ``python benchmarks/interval_coverage.py --two-level``."""
ALL_PHASES = "all"
"""The phase of a figure pooled over both scored phases."""
SEED_TARGET = 0.93
"""The coverage a profile's seed count must reach on every metric and phase its verdicts read."""


@dataclass(frozen=True)
class MeasuredCoverage:
    """Measured coverage of the leaderboard's interval, per ``(metric, phase, seeds)``."""

    command: str
    """The command that measured it."""
    entries: dict[tuple[str, str, int], tuple[float, float]] = field(default_factory=dict)
    """``(metric, phase, seeds) -> (coverage, share of zero-width intervals)``, both fractions."""

    def coverage(self, metric: str, phase: str, seeds: int) -> tuple[float, float] | None:
        """``(coverage, zero-width share)`` of ``metric`` in ``phase`` (or :data:`ALL_PHASES`) at
        ``seeds`` seeds; None where not measured."""
        return self.entries.get((metric, phase, seeds))


def read_measured_coverage(path: str | os.PathLike[str] = COVERAGE_FILE) -> MeasuredCoverage | None:
    """The figures of ``path`` (as written by ``benchmarks/interval_coverage.py --two-level``);
    None where there is no such file."""
    try:
        document = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    entries = {
        (str(e["metric"]), str(e["phase"]), int(e["seeds"])): (float(e["coverage"]), float(e["zero_width"]))
        for e in document["coverage"]
    }
    return MeasuredCoverage(str(document["command"]), entries)


@functools.lru_cache(maxsize=1)
def committed_coverage() -> MeasuredCoverage | None:
    """:func:`read_measured_coverage` of the committed :data:`COVERAGE_FILE` (read once)."""
    return read_measured_coverage()


def seeds_needed(coverage: MeasuredCoverage, reads: Iterable[tuple[str, str]], target: float = SEED_TARGET) -> int | None:
    """The fewest seeds, among those measured for every ``(metric, phase)`` in ``reads``, at which
    each of them is covered at least ``target`` (:data:`SEED_TARGET`); None where no measured
    count reaches it (measure more seeds). ``ValueError`` for an empty ``reads``."""
    wanted = sorted(set(reads))
    if not wanted:
        raise ValueError("seeds_needed needs at least one (metric, phase) that the verdicts read")
    counts = {seeds for (_, _, seeds) in coverage.entries}
    for seeds in sorted(counts):
        figures = [coverage.coverage(metric, phase, seeds) for metric, phase in wanted]
        if all(figure is not None for figure in figures) and all(f[0] >= target for f in figures if f is not None):
            return seeds
    return None
