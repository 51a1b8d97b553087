"""REPRODUCTION.md: verdicts computed from result files, both phases, both directions; only for
sweeps that contain the paper's experiments."""

from __future__ import annotations

from dataclasses import dataclass

import pytest
from helpers_results import synthetic_result, with_training

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.experiment.records import RunResult
from leaderboard.reproduction import NotThePaperSweep, assess_claims, training_window_epsilons, write_reproduction


@dataclass(frozen=True)
class FakeOutcome:
    harms: float
    survival: float


def fake_reference(selfishness: float, epsilon: float, *, gamma: float, max_cycles: int) -> FakeOutcome:
    """A reference that demands near-zero harms and long survival (more at ε = 0)."""
    return FakeOutcome(harms=0.01 + epsilon, survival=480.0 - 1000 * epsilon)


def _paper_like(harm_for_low_beta: float = 0.0, equality_at_half: float = 0.95) -> list[RunResult]:
    runs = []
    for seed in range(5):
        for beta, harms, survival in ((1.0, 0.9, 490), (0.75, 0.5, 480), (0.5, 0.0, 475), (0.25, harm_for_low_beta, 470)):
            runs.append(synthetic_result("coexistence_v0", "empathic_dqn", beta, seed, harms=harms, survival=survival))
        runs.append(synthetic_result("coexistence_v0", "dqn_harm_penalty", 1.0, seed, harms=0.2, survival=470))
        for beta, batteries, eq in ((1.0, 6, 0.5), (0.75, 5, 0.8), (0.5, 4.5, equality_at_half), (0.25, 3, 0.85)):
            runs.append(
                synthetic_result(
                    "sharing_v0", "empathic_dqn", beta, seed, batteries=batteries, other_batteries=9 - batteries, equality=eq
                )
            )
        runs.append(synthetic_result("sharing_v0", "dqn_equality", 1.0, seed, batteries=4.5, equality=0.97))
    return runs


def _verdicts(runs: list[RunResult]) -> dict[str, tuple[str, str]]:
    return {
        c.text: (c.verdicts["greedy"].word, c.verdicts["training"].word) for c in assess_claims(runs, reference=fake_reference)
    }


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
        write_json_atomic(tmp_path / "runs" / f"{run.run_id}.json", run.to_document())
    text = write_reproduction(tmp_path, command="empathy-zoo reproduce --profile test", reference=fake_reference).read_text()
    assert "**not reproduced**" in text and "empathy-zoo reproduce --profile test" in text
    assert text.index("**The rules**") < text.index("| environment | claim | greedy | training |")
    assert "The suite's own questions" in text


def test_a_peak_needs_separation_not_just_the_highest_mean() -> None:
    # β=0.5 has the highest equality (0.852) but its interval meets β=0.25's (0.85)
    assert _verdicts(_paper_like(equality_at_half=0.852))["Equality peaks at β = 0.5."] == ("not reproduced", "not reproduced")


def test_survival_is_judged_against_the_reference_at_the_phase_epsilon() -> None:
    runs = _paper_like()
    # the final 10 % of training is steps 18,000-20,000, where ε falls from ≈ 0.112 to 0.01
    schedule = training_window_epsilons(next(r for r in runs if r.env == "coexistence_v0"))
    assert sum(schedule.values()) == 2000 and min(schedule) == 0.01 and 0.11 < max(schedule) < 0.12

    # a reference that asks for more survival than the runs show fails the claim in training only
    def strict(selfishness: float, epsilon: float, *, gamma: float, max_cycles: int) -> FakeOutcome:
        return FakeOutcome(harms=0.01, survival=500.0 if epsilon > 0 else 400.0)

    claim = next(c for c in assess_claims(runs, reference=strict) if "eventually survive" in c.text)
    assert (claim.verdicts["greedy"].word, claim.verdicts["training"].word) == ("reproduced", "not reproduced")


def test_a_sweep_without_the_papers_experiments_gets_no_verdicts(tmp_path) -> None:
    runs = [r for r in _paper_like() if r.method != "dqn_harm_penalty"]
    with pytest.raises(NotThePaperSweep, match="coexistence_v0 dqn_harm_penalty"):
        assess_claims(runs, reference=fake_reference)
    for run in runs:
        write_json_atomic(tmp_path / "runs" / f"{run.run_id}.json", run.to_document())
    with pytest.raises(NotThePaperSweep):
        write_reproduction(tmp_path, reference=fake_reference)
    assert not (tmp_path / "REPRODUCTION.md").exists()


def test_runs_outside_the_papers_setting_are_left_out() -> None:
    runs = _paper_like()
    # a variant with another fixed agent that would break the harm trend is not the paper's
    runs += [synthetic_result("coexistence_v0", "empathic_dqn", 0.25, s, fixed={"cat_0": "stay"}, harms=5.0) for s in range(5)]
    assert _verdicts(runs)["Harms to the cat fall as β falls."] == ("reproduced", "reproduced")


# --- the figures beside the verdicts: share of steps, tie-break range, survival against the schedule ---


def test_training_window_share_is_the_steps_of_the_final_episodes_not_ten_percent() -> None:
    from leaderboard.reproduction import training_window_share

    run = synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0)
    assert training_window_share(run) == pytest.approx(0.1)  # 40 episodes of 500 steps: 4 of them, 2,000 steps
    # 40 episodes, the first 36 of them 300 steps long: 10 % of the episodes is 2,000 of 12,800 steps
    run = with_training(run, episode_end_step=[*range(300, 10801, 300), 11300, 11800, 12300, 12800])
    assert training_window_share(run) == pytest.approx(2000 / 12800)
    assert sum(training_window_epsilons(run).values()) == 2000
    run = with_training(run, episode_end_step=[])
    assert training_window_share(run) != training_window_share(run)  # NaN without episodes


def test_tie_break_bounds_with_one_action_per_state_are_that_policys_figures() -> None:
    import numpy as np

    from empathy_zoo.reference import coexistence_optimum, coexistence_values, greedy_actions
    from leaderboard.reproduction import _tie_bound

    epsilons, weights = np.array([0.0, 0.05, 0.3]), np.array([0.2, 0.5, 0.3])
    for beta in (1.0, 0.5):
        q_emp = coexistence_values(beta)[1][:49]
        lowest_index = np.eye(5, dtype=bool)[greedy_actions(q_emp)]
        for metric in ("harms", "survival"):
            expected = sum(
                w * getattr(coexistence_optimum(beta, e, ties="first", max_cycles=60), metric)
                for e, w in zip(epsilons, weights, strict=True)
            )
            for highest in (False, True):
                assert _tie_bound(lowest_index, epsilons, weights, metric, highest, 60, 7) == pytest.approx(expected, abs=1e-9)


def test_tie_break_range_contains_both_tie_rules() -> None:
    from empathy_zoo.reference import coexistence_optimum
    from leaderboard.reproduction import tie_break_range

    schedule = {0.02: 3, 0.1: 1}
    for beta in (1.0, 0.5):
        spread = tie_break_range(beta, schedule, max_cycles=80)
        assert spread.harms[0] < spread.harms[1] and spread.survival[0] < spread.survival[1]
        for ties in ("uniform", "first"):
            outcome = [coexistence_optimum(beta, e, ties=ties, max_cycles=80) for e in schedule]
            harms = sum(o.harms * n for o, n in zip(outcome, schedule.values(), strict=True)) / 4
            survival = sum(o.survival * n for o, n in zip(outcome, schedule.values(), strict=True)) / 4
            assert spread.harms[0] - 1e-9 <= harms <= spread.harms[1] + 1e-9
            assert spread.survival[0] - 1e-9 <= survival <= spread.survival[1] + 1e-9
    with pytest.raises(ValueError, match="at least one ε"):
        tie_break_range(0.5, {})


def _rising_runs(learner_survival) -> list[RunResult]:
    """Coexistence runs whose training survival per episode is ``learner_survival(ε at its first step)``."""
    from types import SimpleNamespace

    from empathy_zoo.schedules import linear_epsilon

    runs = []
    for seed in range(3):
        run = synthetic_result("coexistence_v0", "empathic_dqn", 0.5, seed)
        settings = SimpleNamespace(**run.config.settings)
        starts = [0, *run.train.episode_end_step.tolist()[:-1]]
        runs.append(with_training(run, survival=[learner_survival(round(linear_epsilon(settings, s), 3)) for s in starts]))
    return runs


def test_survival_rise_separates_learning_from_the_schedule() -> None:
    from leaderboard.reproduction import survival_rise

    # the reference survives 480 − 1000·ε: over the final 4 episodes (ε ≈ 0.112 → 0.036) it rises
    schedule_only = survival_rise(_rising_runs(lambda e: 400 - 1000 * e), fake_reference, gamma=0.99, max_cycles=500)
    assert schedule_only.reference[1] > schedule_only.reference[0]
    assert schedule_only.learner[1] - schedule_only.learner[0] == pytest.approx(
        schedule_only.reference[1] - schedule_only.reference[0]
    )
    assert schedule_only.gap == pytest.approx((80.0, 80.0)) and schedule_only.widened == 0 and schedule_only.runs == 3
    # a learner that rises by half as much as the schedule gives the optimum falls behind it
    lagging = survival_rise(_rising_runs(lambda e: 400 - 500 * e), fake_reference, gamma=0.99, max_cycles=500)
    assert lagging.learner[1] > lagging.learner[0] and lagging.gap[1] > lagging.gap[0] and lagging.widened == 3
    # one that rises faster closes the gap
    learning = survival_rise(_rising_runs(lambda e: 400 - 2000 * e), fake_reference, gamma=0.99, max_cycles=500)
    assert learning.gap[1] < learning.gap[0] and learning.widened == 0


def test_the_evidence_states_the_share_the_range_and_the_rise() -> None:
    from leaderboard.reproduction import TieRange

    calls = []

    def fake_range(selfishness, epsilons, *, gamma, max_cycles):
        calls.append((selfishness, sum(epsilons.values())))
        return TieRange((0.001, 0.9), (150.0, 499.0))

    def evidence(**kwargs) -> dict[str, str]:
        claim = next(c for c in assess_claims(_paper_like(), reference=fake_reference, **kwargs) if "eventually" in c.text)
        return {phase: verdict.evidence for phase, verdict in claim.verdicts.items()}

    with_range = evidence(tie_range=fake_range)
    assert "over every tie-break the optimum's harms span 0.001–0.900 and its survival 150.0–499.0" in with_range["training"]
    assert "over every tie-break" in with_range["greedy"]
    assert "(10.0–10.0 % of each run's steps)" in with_range["training"]
    assert "first half → second half" in with_range["training"] and "first half" not in with_range["greedy"]
    assert sorted(calls) == [(0.25, 1), (0.25, 10000), (0.5, 1), (0.5, 10000)]  # 5 runs × 2,000 steps in training
    assert "tie-break" not in evidence()["training"]  # a reference of one's own and no range: none shown
