"""The populations profile's reading rule (leaderboard.population_transfer) on hand-made seeds."""

from __future__ import annotations

import pytest

from leaderboard.improvement import permutation_test
from leaderboard.population_transfer import (
    BETTER,
    NOT_DETECTED,
    UNDECIDABLE,
    WORSE,
    _split_with_wins,
    changes_carry_over,
    compare,
    detectable_distance,
)

FEW_HARMS = [0.0, 0.1, 0.0, 0.2, 0.0, 0.1, 0.0, 0.0, 0.1, 0.0]
MANY_HARMS = [0.9, 1.0, 0.8, 1.0, 0.7, 1.0, 0.9, 1.0, 1.0, 0.8]


@pytest.mark.parametrize(
    ("population", "default", "higher_is_better", "observed"),
    [
        (FEW_HARMS, MANY_HARMS, False, BETTER),  # fewer harms beside the test partners
        (MANY_HARMS, FEW_HARMS, False, WORSE),
        (FEW_HARMS, MANY_HARMS, True, WORSE),  # the metric's direction decides which is better
        (FEW_HARMS, FEW_HARMS, False, NOT_DETECTED),
        (FEW_HARMS[:2], MANY_HARMS[:2], False, UNDECIDABLE),  # 2 against 2 can never reach 5 %
    ],
)
def test_population_trained_seeds_against_default_trained(population, default, higher_is_better, observed) -> None:
    assert compare(population, default, higher_is_better).observed == observed


def test_a_split_has_the_wins_asked() -> None:
    for wins in (0, 17, 50, 100):
        x, y = _split_with_wins(10, 10, wins)
        assert sum(a > b for a in x for b in y) == wins
        assert not set(x) & set(y)  # no seed of one side ties one of the other


def test_the_detectable_distance_is_where_the_exact_test_starts_to_reject() -> None:
    distance = detectable_distance(10, 10)
    assert distance == pytest.approx(0.26)  # 24 of 100 pairs: p = 0.046; 25: p = 0.056
    inside = _split_with_wins(10, 10, 25)
    edge = _split_with_wins(10, 10, 24)
    assert permutation_test(*edge)[1] <= 0.05 < permutation_test(*inside)[1]
    assert compare(*edge, True).observed == WORSE and compare(*inside, True).observed == NOT_DETECTED
    assert detectable_distance(3, 3) == 0.5  # no split of 3 against 3 is marked


def test_a_claim_needs_its_mark_to_survive_holm_over_the_family() -> None:
    strong = compare(FEW_HARMS, MANY_HARMS, False)  # every pair apart: p ≈ 1e-5
    edge = compare(*_split_with_wins(10, 10, 24), True)  # marked alone (p = 0.046), not among 10
    nothing = compare(FEW_HARMS, FEW_HARMS, False)
    assert strong.observed == BETTER and edge.observed == WORSE
    assert changes_carry_over([strong, edge, *[nothing] * 8]) == [True, False, *[False] * 8]
    assert changes_carry_over([edge]) == [True]  # a family of one: its own level
