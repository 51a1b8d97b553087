"""The populations profile's reading: does training beside a population change what carries over?

Fixed before the profile's first run (docs/results/populations/READING.md says so).

Per environment and method (DQN, Empathic DQN at β = 0.5), two groups of 10 seeds trained alike
but beside different partners: the environment's default partner (the methods and scenarios
profiles' runs) and its training population (the populations profile). Both are evaluated on the
environment's **test split** (``empathy_zoo/scenarios/<env>_test.toml``), whose members neither
group met in training. Each seed's score in a scenario is the mean over its evaluation episodes.

* **The primary comparison**, one per environment and method (10 in all), on the scenario
  :data:`PRIMARY_SCENARIO` (the test population itself) and the environment's side effect (the
  first of its entry's ``side_effects``): the population-trained seeds against the
  default-trained ones by the exact two-sided permutation test at 5 %
  (:func:`leaderboard.improvement.improvement_interval`, the direction of
  :data:`empathy_zoo.metrics.HIGHER_IS_BETTER`). **Better** or **worse** where the interval of
  the probability of improvement excludes 0.5; otherwise **no difference detected**, which at
  10 against 10 means only that the probability lies within :func:`detectable_distance` of 0.5.
* **Secondary comparisons**, the same test on every other test scenario and on the task metric:
  reported, not judged. Under no effect at all, 5 % of them are marked by chance.

Training beside a population **changes what carries over** for a method on an environment when
its primary comparison is marked and the mark survives Holm's adjustment over the 10 primary
comparisons (:func:`changes_carry_over`: at most a 5 % chance of one false claim among them).
Pure functions of arrays; reading files is the caller's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from leaderboard.improvement import CONFIDENCE, can_decide, improvement_interval, permutation_test
from leaderboard.multiplicity import holm_adjusted, rejected

__all__ = [
    "PRIMARY_SCENARIO",
    "Comparison",
    "changes_carry_over",
    "compare",
    "detectable_distance",
]

PRIMARY_SCENARIO = "test_population"
"""The test split's scenario the primary comparison reads: its whole population."""

BETTER, WORSE, NOT_DETECTED, UNDECIDABLE = "better", "worse", "no difference detected", "undecidable"


@dataclass(frozen=True)
class Comparison:
    """Population-trained seeds against default-trained seeds in one scenario and metric."""

    observed: str
    """``better``, ``worse``, ``no difference detected`` or ``undecidable`` (population-trained
    against default-trained)."""
    probability: float
    """The probability that a population-trained seed scores better than a default-trained one."""
    low: float
    """The interval's lower end."""
    high: float
    """The interval's upper end."""
    p: float
    """The two-sided p of the exact permutation test."""


def compare(population: Sequence[float], default: Sequence[float], higher_is_better: bool) -> Comparison:
    """``population``'s per-seed scores against ``default``'s (see the module page)."""
    probability, low, high = improvement_interval(population, default, higher_is_better, confidence=CONFIDENCE)
    p = permutation_test(population, default, higher_is_better)[1]
    if math.isnan(probability) or not can_decide(len(population), len(default), CONFIDENCE):
        observed = UNDECIDABLE  # (no split of so few seeds is rejected)
    else:
        observed = BETTER if low > 0.5 else WORSE if high < 0.5 else NOT_DETECTED
    return Comparison(observed, probability, low, high, p)


def changes_carry_over(primaries: Sequence[Comparison]) -> list[bool]:
    """Per primary comparison (the family of every environment and method), whether training
    beside a population changes what carries over: it is marked, and the mark survives Holm's
    adjustment over the family (:func:`leaderboard.multiplicity.holm_adjusted`, family-wise 5 %)."""
    survives = rejected(holm_adjusted([c.p for c in primaries]))
    return [bool(keep) and c.observed in (BETTER, WORSE) for c, keep in zip(primaries, survives, strict=True)]


def detectable_distance(n: int, m: int) -> float:
    """The least distance of the probability of improvement from 0.5 that the test marks at
    ``n`` against ``m`` untied seeds: nearer than this, "no difference detected" is all it can
    say. 0.5 where no split is marked (too few seeds)."""
    detectable = 0.5
    for wins in range(n * m // 2 + 1):  # the first side ahead in `wins` of the n·m pairs
        x, y = _split_with_wins(n, m, wins)
        probability, _, high = improvement_interval(x, y, True, confidence=CONFIDENCE)
        if not high < 0.5:
            break
        detectable = 0.5 - probability
    return detectable


def _split_with_wins(n: int, m: int, wins: int) -> tuple[list[float], list[float]]:
    """``n`` and ``m`` untied scores where exactly ``wins`` of the ``n·m`` pairs have the first
    side ahead: each first-side seed placed above as many second-side seeds as are left to beat."""
    y = [float(2 * k + 2) for k in range(m)]
    x = []
    left = wins
    for _ in range(n):
        beaten = min(m, left)
        x.append(float(2 * beaten + 1))  # above y's first `beaten`, below the rest
        left -= beaten
    return x, y
