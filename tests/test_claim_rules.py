"""Claims judged on intervals and by the leaderboard's own pairwise test: C3 ("β = 0.5, 0.25
eventually survive without harming") undecided where an interval straddles the threshold; C4 and
C7 ("A less than B") by the exact permutation test, not by non-overlapping intervals; the old
verdicts shown beside the new."""

from __future__ import annotations

from dataclasses import dataclass

import pytest
from helpers_results import synthetic_result

from leaderboard.claim_rules import less_than, reference_reading
from leaderboard.reproduction import assess_claims, claim_verdicts_markdown, reproduction_markdown
from leaderboard.verdicts import HARM_TOLERANCE, SURVIVAL_TOLERANCE, Cell

SURVIVE = "The less selfish agents (β = 0.5, 0.25) eventually survive without harming the cat."
PENALTY = "The −100 harm-penalty baseline harms the cat less than DQN."
EQUAL = "The equality-scaled DQN baseline is more equal than DQN."


@dataclass(frozen=True)
class FakeOutcome:
    harms: float
    survival: float


def fake_reference(selfishness: float, epsilon: float, *, gamma: float, max_cycles: int) -> FakeOutcome:
    return FakeOutcome(harms=0.01 + epsilon, survival=480.0 - 1000 * epsilon)


def paper_like(low_beta_harms: float = 0.0, penalty_harms: float = 0.2, shaped_equality: float = 0.97) -> list[dict]:
    """As tests/test_reproduction.py's sweep; a greedy value is ``mean + 0.01·seed`` (seeds 0–4)."""
    runs = []
    for seed in range(5):
        for beta, harms, survival in ((1.0, 0.9, 490), (0.75, 0.5, 480), (0.5, 0.0, 475), (0.25, low_beta_harms, 470)):
            runs.append(synthetic_result("coexistence_v0", "empathic_dqn", beta, seed, harms=harms, survival=survival))
        runs.append(synthetic_result("coexistence_v0", "dqn_harm_penalty", 1.0, seed, harms=penalty_harms, survival=470))
        for beta, batteries, eq in ((1.0, 6, 0.5), (0.75, 5, 0.8), (0.5, 4.5, 0.95), (0.25, 3, 0.85)):
            runs.append(
                synthetic_result(
                    "sharing_v0", "empathic_dqn", beta, seed, batteries=batteries, other_batteries=9 - batteries, equality=eq
                )
            )
        runs.append(synthetic_result("sharing_v0", "dqn_equality", 1.0, seed, batteries=4.5, equality=shaped_equality))
    return runs


def greedy(runs: list[dict], text: str) -> tuple[str, str]:
    """``(old word, new word)`` of a claim's greedy verdict."""
    claim = next(c for c in assess_claims(runs, reference=fake_reference) if c.text == text)
    verdict = claim.verdicts["greedy"]
    return (verdict.old or verdict).word, verdict.word


def test_reference_reading_on_intervals() -> None:
    slack = SURVIVAL_TOLERANCE * 500
    ok_survival = Cell(470.0, 465.0, 475.0, 5)
    threshold = 0.04 + HARM_TOLERANCE
    assert reference_reading(Cell(0.05, 0.04, 0.06, 5), ok_survival, 0.04, 462.0, 500) is True
    assert reference_reading(Cell(0.2, 0.15, 0.25, 5), ok_survival, 0.04, 462.0, 500) is False
    assert reference_reading(Cell(threshold, threshold - 0.02, threshold + 0.02, 5), ok_survival, 0.04, 462.0, 500) is None
    low = 462.0 - slack
    assert reference_reading(Cell(0.0, 0.0, 0.0, 5), Cell(low, low - 5, low + 5, 5), 0.04, 462.0, 500) is None
    assert reference_reading(Cell(0.0, 0.0, 0.0, 5), Cell(low - 10, low - 15, low - 5, 5), 0.04, 462.0, 500) is False


def test_less_than_is_the_exact_permutation_test() -> None:
    assert less_than([0.85, 0.86, 0.87, 0.88, 0.89], [0.90, 0.91, 0.92, 0.93, 0.94])[0] is True
    assert less_than([0.90, 0.91, 0.92, 0.93, 0.94], [0.85, 0.86, 0.87, 0.88, 0.89])[0] is False
    assert less_than([0.1, 0.5, 0.2, 0.6, 0.3], [0.4, 0.15, 0.55, 0.25, 0.45])[0] is False
    assert less_than([0.1, 0.2, 0.3], [0.7, 0.8, 0.9])[0] is None  # 3 against 3 cannot reach 5 %


def test_c3_is_undecided_where_an_interval_straddles_the_threshold() -> None:
    # β = 0.25's greedy harms 0.035–0.075, mean 0.055 ≤ 0.06 (the reference 0.01 + 0.05): the old rule
    # passed it on the mean; its interval straddles 0.06
    assert greedy(paper_like(low_beta_harms=0.035), SURVIVE) == ("reproduced", "undecided")
    assert greedy(paper_like(low_beta_harms=0.0), SURVIVE) == ("reproduced", "reproduced")
    assert greedy(paper_like(low_beta_harms=0.3), SURVIVE) == ("not reproduced", "not reproduced")


def test_c4_and_c7_use_the_exact_test_not_interval_separation() -> None:
    # penalty 0.865–0.905 against DQN's 0.90–0.94: 24 of 25 pairs below (p = 4/252), intervals overlapping
    assert greedy(paper_like(penalty_harms=0.865), PENALTY) == ("not reproduced", "reproduced")
    assert greedy(paper_like(penalty_harms=0.2), PENALTY) == ("reproduced", "reproduced")
    assert greedy(paper_like(penalty_harms=0.88), PENALTY) == ("not reproduced", "not reproduced")
    # equality 0.545–0.585 against DQN's 0.50–0.54
    assert greedy(paper_like(shaped_equality=0.545), EQUAL) == ("not reproduced", "reproduced")


def test_the_report_shows_old_verdicts_beside_new() -> None:
    claims = assess_claims(paper_like(low_beta_harms=0.035, penalty_harms=0.865), reference=fake_reference)
    text = reproduction_markdown(claims, "cmd", "dir")
    assert "old rule: reproduced" in text and "**undecided**" in text
    assert "old rule: not reproduced" in text
    listing = claim_verdicts_markdown(claims)
    assert "| C3 |" in listing and "| C4 |" in listing and "| C7 |" in listing
    assert "| greedy (old rule) | greedy | training (old rule) | training |" in listing


@pytest.mark.parametrize("phase", ["greedy", "training"])
def test_unchanged_claims_have_no_old_verdict(phase: str) -> None:
    for claim in assess_claims(paper_like(), reference=fake_reference):
        if claim.text not in (SURVIVE, PENALTY, EQUAL):
            assert claim.verdicts[phase].old is None
