"""The verdict rules on synthetic cells: a case that passes each rule, one that fails it, and
one on its boundary."""

from __future__ import annotations

import math

import pytest

from leaderboard.verdicts import HARM_TOLERANCE, SURVIVAL_TOLERANCE, Cell, below, cell_of, falls, matches_reference, peaks


def c(mean: float, half_width: float = 0.05) -> Cell:
    return Cell(mean, mean - half_width, mean + half_width, 5)


def test_below_needs_separated_intervals() -> None:
    assert below(c(0.0), c(1.0))
    assert not below(c(1.0), c(0.0))
    assert not below(Cell(0.5, 0.4, 0.6, 5), Cell(0.7, 0.6, 0.8, 5))  # boundary: touching is not separated
    assert below(Cell(0.5, 0.4, 0.6, 5), Cell(0.7, 0.6000001, 0.8, 5))


def test_falls_passes_a_clean_trend_and_ties_near_zero() -> None:
    assert falls([c(0.9), c(0.5), c(0.2), c(0.0)])
    assert falls([c(0.9), c(0.5), c(0.0, 0.0), c(0.0, 0.0)])  # a tie at zero is allowed
    assert falls([c(0.9), c(0.95), c(0.3), c(0.1)])  # a rise within the intervals is a tie


def test_falls_fails_a_significant_rise_or_unseparated_ends() -> None:
    assert not falls([c(0.9), c(0.2), c(0.6), c(0.0)])  # 0.2 -> 0.6 rises significantly
    assert not falls([c(0.9, 0.5), c(0.5), c(0.3), c(0.2, 0.3)])  # the ends overlap
    assert not falls([c(0.0), c(0.3), c(0.6), c(0.9)])


def test_falls_boundary_ends_touching() -> None:
    assert not falls([Cell(1.0, 0.5, 1.5, 5), Cell(0.2, -0.3, 0.5, 5)])
    assert falls([Cell(1.0, 0.5, 1.5, 5), Cell(0.2, -0.3, 0.4999, 5)])
    with pytest.raises(ValueError, match="two cells"):
        falls([c(1.0)])


def test_peaks_needs_both_neighbours_below() -> None:
    assert peaks(c(0.7), c(0.95), c(0.6))
    assert not peaks(c(0.7, 0.2), c(0.95), c(0.6))  # highest mean, but overlapping the left neighbour
    assert not peaks(c(0.95), c(0.7), c(0.6))
    assert not peaks(Cell(0.8, 0.75, 0.85, 5), Cell(0.9, 0.85, 0.95, 5), c(0.1))  # boundary: touching


def test_reference_tolerance_and_its_boundary() -> None:
    max_cycles = 500
    slack = SURVIVAL_TOLERANCE * max_cycles
    ref_harms, ref_survival = 0.04, 462.0
    assert matches_reference(c(0.04), c(462.0), ref_harms, ref_survival, max_cycles)  # the optimum itself
    assert matches_reference(c(0.04 + HARM_TOLERANCE), c(ref_survival - slack), ref_harms, ref_survival, max_cycles)
    assert not matches_reference(c(0.04 + HARM_TOLERANCE + 1e-6), c(462.0), ref_harms, ref_survival, max_cycles)
    assert not matches_reference(c(0.0), c(ref_survival - slack - 1e-6), ref_harms, ref_survival, max_cycles)


def test_cell_of_is_the_mean_with_the_leaderboards_t_interval() -> None:
    cell = cell_of([1.0, 2.0, 3.0, 4.0, 5.0])
    half = 3.4954059325164416 * math.sqrt(2.5) / math.sqrt(5)  # t(0.9875, 4) (mpmath), s² = 2.5
    assert cell.mean == 3.0 and cell.n == 5
    assert (cell.low, cell.high) == pytest.approx((3.0 - half, 3.0 + half), rel=1e-12)
    assert cell_of([2.0]) == Cell(2.0, 2.0, 2.0, 1)
    assert not cell_of([float("nan")] * 3).finite
