"""Many ▲/▼ on one page: adjusted p-values for a family of tests, and the false marks to expect.

Each verdict against DQN is a test at 5 % (:func:`leaderboard.improvement.permutation_test`); a
page of ``m`` such cells gives up to ``0.05·m`` marks where no method differs from DQN
(:func:`expected_false_marks`). Holm's step-down adjustment (:func:`holm_adjusted`) keeps the
chance of even one false mark among the family at most the level; Benjamini–Hochberg's
(:func:`benjamini_hochberg_adjusted`) keeps the expected share of false marks among the marks
given at most the level (for independent or positively dependent tests). Pure functions over
arrays; a NaN p is no member of the family (its adjusted p is NaN, never rejected).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["FAMILY_LEVEL", "HOLM_MARK", "holm_adjusted", "benjamini_hochberg_adjusted", "rejected", "expected_false_marks"]

FAMILY_LEVEL = 0.05
"""The level of each test and of the family (family-wise for Holm, false discovery rate for BH)."""
HOLM_MARK = "◆"
"""Marks a ▲ / ▼ that survives Holm's adjustment over the page's cells."""


def _finite(p_values: Sequence[float] | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p = np.asarray(p_values, dtype=np.float64).ravel()
    members = np.flatnonzero(np.isfinite(p))
    order = members[np.argsort(p[members], kind="stable")]
    return p, order, p[order]


def holm_adjusted(p_values: Sequence[float] | np.ndarray) -> np.ndarray:
    """Holm's adjusted p, in the order given: with the ``m`` finite p sorted ascending,
    ``p̃₍ᵢ₎ = max_{j ≤ i} min(1, (m − j + 1)·p₍ⱼ₎)`` (i, j from 1), so it never decreases with p
    and tied p share one value. ``p̃ ≤ level`` rejects at family-wise ``level``."""
    p, order, ascending = _finite(p_values)
    adjusted = np.full(p.shape, np.nan)
    m = ascending.size
    if m:
        adjusted[order] = np.maximum.accumulate(np.minimum(1.0, (m - np.arange(m)) * ascending))
    return adjusted


def benjamini_hochberg_adjusted(p_values: Sequence[float] | np.ndarray) -> np.ndarray:
    """Benjamini–Hochberg's adjusted p, in the order given: with the ``m`` finite p sorted
    ascending, ``p̃₍ᵢ₎ = min_{j ≥ i} min(1, m·p₍ⱼ₎ / j)``; never above Holm's. ``p̃ ≤ level``
    rejects at false discovery rate ``level``."""
    p, order, ascending = _finite(p_values)
    adjusted = np.full(p.shape, np.nan)
    m = ascending.size
    if m:
        scaled = np.minimum(1.0, m * ascending / np.arange(1, m + 1))
        adjusted[order] = np.minimum.accumulate(scaled[::-1])[::-1]
    return adjusted


def rejected(adjusted: Sequence[float] | np.ndarray, level: float = FAMILY_LEVEL) -> np.ndarray:
    """Which adjusted p reject at ``level`` (a NaN never does)."""
    values = np.asarray(adjusted, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        return np.isfinite(values) & (values <= level + 1e-12)


def expected_false_marks(cells: int, level: float = FAMILY_LEVEL) -> float:
    """How many of ``cells`` tests at ``level`` would reject where nothing differs, at most (each
    test's size is at most ``level``): ``cells · level``."""
    return cells * level
