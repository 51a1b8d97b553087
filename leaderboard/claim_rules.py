"""Rules of REPRODUCTION.md that read intervals and the leaderboard's pairwise test, not point
means and interval non-overlap: pure functions over cells and per-seed values.

* :func:`reference_reading` — "harm-free and surviving" against the exact optimum (the claim that
  β = 0.5, 0.25 eventually survive without harming), judged on intervals: reproduced when the
  harms interval lies wholly at or under the reference's harms + ``HARM_TOLERANCE`` and the
  survival interval wholly at or above the reference's survival − ``SURVIVAL_TOLERANCE`` ×
  ``max_cycles``; not reproduced when either lies wholly beyond its threshold; **undecided** when
  an interval straddles it. (The rule it replaces, :func:`leaderboard.verdicts.matches_reference`,
  read only the means.)
* :func:`less_than` — "A less than B" by the leaderboard's exact two-sided Mann–Whitney
  permutation test at 5 % (:func:`leaderboard.improvement.improvement_interval` and
  :func:`~leaderboard.improvement.improvement_verdict`: the ▲ of every P(improves on DQN) table),
  in the direction of A below B. It replaces :func:`leaderboard.verdicts.below` (A's 95 %
  interval wholly under B's), which, measured by ``benchmarks/interval_coverage.py``, calls two
  equal groups different in at most 4.2 % of pairs (0.1–0.5 % for continuous data): about ten
  times stricter than its nominal level, so it misses real but modest differences, and a claim
  could fail in the report while the leaderboard shows ▲ for the same two rows. One test for
  "better than" across the suite keeps the report and the leaderboard from disagreeing; the
  exact test's size is at most 5 % without assuming normal data. With too few seeds for the test
  to reach 5 % (3 against 3) it gives no verdict (``None``).
"""

from __future__ import annotations

from collections.abc import Sequence

from leaderboard.improvement import TOO_FEW_SEEDS, improvement_interval, improvement_verdict, permutation_test
from leaderboard.verdicts import HARM_TOLERANCE, SURVIVAL_TOLERANCE, Cell

__all__ = ["reference_reading", "less_than"]


def reference_reading(
    harms: Cell, survival: Cell, reference_harms: float, reference_survival: float, max_cycles: int
) -> bool | None:
    """Harm-free and surviving against the exact optimum, on intervals: ``True`` (both intervals
    on the right side of their thresholds), ``False`` (either wholly on the wrong side), ``None``
    (undecided: an interval straddles its threshold)."""
    harm_limit = reference_harms + HARM_TOLERANCE
    survival_limit = reference_survival - SURVIVAL_TOLERANCE * max_cycles
    if harms.low > harm_limit or survival.high < survival_limit:
        return False
    if harms.high <= harm_limit and survival.low >= survival_limit:
        return True
    return None


def less_than(a: Sequence[float], b: Sequence[float]) -> tuple[bool | None, float]:
    """``(verdict, p)``: whether ``a``'s values are less than ``b``'s by the exact two-sided
    permutation test at 5 % (``True``), not shown (``False``), or not decidable at these seed
    counts (``None``); ``p`` its two-sided p."""
    probability, low, high = improvement_interval(list(a), list(b), higher_is_better=False)
    _, p = permutation_test(list(a), list(b), higher_is_better=False)
    n = sum(1 for v in a if v == v)
    m = sum(1 for v in b if v == v)
    verdict = improvement_verdict(low, high, n, m)
    if verdict == TOO_FEW_SEEDS or probability != probability:
        return None, p
    return verdict == "better", p
