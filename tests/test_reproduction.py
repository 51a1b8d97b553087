"""REPRODUCTION.md: verdicts computed from result files, both phases, both directions; only for
sweeps that contain the paper's experiments."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from empathy_zoo.atomic import write_json_atomic
from helpers_results import synthetic_result
from leaderboard.reproduction import NotThePaperSweep, assess_claims, training_window_epsilons, write_reproduction


@dataclass(frozen=True)
class FakeOutcome:
    harms: float
    survival: float


def fake_reference(selfishness: float, epsilon: float, *, gamma: float, max_cycles: int) -> FakeOutcome:
    """A reference that demands near-zero harms and long survival (more at ε = 0)."""
    return FakeOutcome(harms=0.01 + epsilon, survival=480.0 - 1000 * epsilon)


def _paper_like(harm_for_low_beta: float = 0.0, equality_at_half: float = 0.95) -> list[dict]:
    runs = []
    for seed in range(5):
        for beta, harms, survival in ((1.0, 0.9, 490), (0.75, 0.5, 480), (0.5, 0.0, 475), (0.25, harm_for_low_beta, 470)):
            runs.append(synthetic_result("coexistence_v0", "empathic_dqn", beta, seed, harms=harms, survival=survival))
        runs.append(synthetic_result("coexistence_v0", "dqn_harm_penalty", 1.0, seed, harms=0.2, survival=470))
        for beta, batteries, eq in ((1.0, 6, 0.5), (0.75, 5, 0.8), (0.5, 4.5, equality_at_half), (0.25, 3, 0.85)):
            runs.append(synthetic_result("sharing_v0", "empathic_dqn", beta, seed, batteries=batteries,
                                other_batteries=9 - batteries, equality=eq))
        runs.append(synthetic_result("sharing_v0", "dqn_equality", 1.0, seed, batteries=4.5, equality=0.97))
    return runs


def _verdicts(runs: list[dict]) -> dict[str, tuple[str, str]]:
    return {c.text: (c.verdicts["greedy"].word, c.verdicts["training"].word)
            for c in assess_claims(runs, reference=fake_reference)}


def test_claims_that_hold_are_reproduced_in_both_phases() -> None:
    claims = assess_claims(_paper_like(), reference=fake_reference)
    assert [c.papers for c in claims].count(True) == 6 and [c.papers for c in claims].count(False) == 1
    for claim in claims:
        assert (claim.verdicts["greedy"].word, claim.verdicts["training"].word) == ("reproduced", "reproduced"), claim


def test_a_claim_that_fails_is_reported_as_such(tmp_path) -> None:
    runs = _paper_like(harm_for_low_beta=1.5)  # the least selfish robot harms most
    verdicts = _verdicts(runs)
    assert verdicts["Harms to the cat fall as β falls."] == ("not reproduced", "not reproduced")
    survive = "The less selfish agents (β = 0.5, 0.25) eventually survive without harming the cat."
    assert verdicts[survive] == ("not reproduced", "not reproduced")
    assert verdicts["Equality peaks at β = 0.5."] == ("reproduced", "reproduced")
    for run in runs:
        write_json_atomic(tmp_path / "runs" / f"{run['run_id']}.json", run)
    text = write_reproduction(tmp_path, command="empathy-zoo reproduce --profile test", reference=fake_reference).read_text()
    assert "**not reproduced**" in text and "empathy-zoo reproduce --profile test" in text
    assert text.index("**The rules**") < text.index("| environment | claim | greedy | training |")
    assert "The suite's own questions" in text


def test_a_peak_needs_separation_not_just_the_highest_mean() -> None:
    # β=0.5 has the highest equality (0.852) but its interval meets β=0.25's (0.85)
    assert _verdicts(_paper_like(equality_at_half=0.852))["Equality peaks at β = 0.5."] == ("not reproduced", "not reproduced")


def test_survival_is_judged_against_the_reference_at_the_phase_epsilon() -> None:
    runs = _paper_like()
    # the final 10 % of training is steps 3600-4000, where ε falls from ≈ 0.112 to 0.01
    schedule = training_window_epsilons(next(r for r in runs if r["env"] == "coexistence_v0"))
    assert sum(schedule.values()) == 400 and min(schedule) == 0.01 and 0.11 < max(schedule) < 0.12
    # a reference that asks for more survival than the runs show fails the claim in training only
    def strict(selfishness: float, epsilon: float, *, gamma: float, max_cycles: int) -> FakeOutcome:
        return FakeOutcome(harms=0.01, survival=500.0 if epsilon > 0 else 400.0)
    claim = next(c for c in assess_claims(runs, reference=strict) if "eventually survive" in c.text)
    assert (claim.verdicts["greedy"].word, claim.verdicts["training"].word) == ("reproduced", "not reproduced")


def test_a_sweep_without_the_papers_experiments_gets_no_verdicts(tmp_path) -> None:
    runs = [r for r in _paper_like() if r["method"] != "dqn_harm_penalty"]
    with pytest.raises(NotThePaperSweep, match="coexistence_v0 dqn_harm_penalty"):
        assess_claims(runs, reference=fake_reference)
    for run in runs:
        write_json_atomic(tmp_path / "runs" / f"{run['run_id']}.json", run)
    with pytest.raises(NotThePaperSweep):
        write_reproduction(tmp_path, reference=fake_reference)
    assert not (tmp_path / "REPRODUCTION.md").exists()


def test_runs_outside_the_papers_setting_are_left_out() -> None:
    runs = _paper_like()
    # a variant with another fixed agent that would break the harm trend is not the paper's
    runs += [synthetic_result("coexistence_v0", "empathic_dqn", 0.25, s, fixed={"cat_0": "stay"}, harms=5.0) for s in range(5)]
    assert _verdicts(runs)["Harms to the cat fall as β falls."] == ("reproduced", "reproduced")
