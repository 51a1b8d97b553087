"""The leaderboard's intervals and its verdict against DQN (chosen by benchmarks/interval_coverage.py):
hand-computed numbers, brute-force permutation counts, the 3-seed behaviour, and small seeded
simulations of coverage and of the false-positive rate."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from helpers_results import MAX_CYCLES, derive_run_id, hand_made_result, record, synthetic_document, synthetic_result

from empathy_zoo.experiment.records import RunResult
from leaderboard.aggregate import bootstrap_mean_ci, mean_ci, student_t_interval
from leaderboard.improvement import (
    TOO_FEW_SEEDS,
    VERDICT_MARKS,
    Improvement,
    can_decide,
    improvement_interval,
    improvement_verdict,
    improvements_over_dqn,
    permutation_test,
    probability_of_improvement,
    smallest_decidable_seeds,
)


def brute_force_p(x: list[float], y: list[float]) -> float:
    """Two-sided p by listing every split of the pooled runs (the share at least as far from 0.5)."""
    pooled = np.array(x + y)
    observed = abs(probability_of_improvement(x, y) - 0.5)
    splits = list(itertools.combinations(range(pooled.size), len(x)))
    far = 0
    for chosen in splits:
        rest = [i for i in range(pooled.size) if i not in chosen]
        far += abs(probability_of_improvement(pooled[list(chosen)], pooled[rest]) - 0.5) >= observed - 1e-12
    return far / len(splits)


def test_t_interval_of_one_two_three_is_mean_plus_minus_t_s_over_root_three() -> None:
    t = 0.95 / math.sqrt(2 * 0.975 * 0.025)  # t(0.975, 2 df) in closed form: (2p − 1) / √(2p(1 − p))
    mean, low, high = student_t_interval([1.0, 2.0, 3.0], level=0.95)  # s = 1
    assert mean == 2.0
    assert (low, high) == pytest.approx((2.0 - t / math.sqrt(3), 2.0 + t / math.sqrt(3)), rel=1e-12)
    # what the tables show for a 95 % claim: the t interval at 97.5 % nominal, t(0.9875, 2) from mpmath
    _, low, high = mean_ci([1.0, 2.0, 3.0])
    half = 6.205346816570706 / math.sqrt(3)
    assert (low, high) == pytest.approx((2.0 - half, 2.0 + half), rel=1e-12)


@pytest.mark.parametrize(
    ("x", "y"),
    [
        ([3.0, 4.0, 5.0], [0.0, 1.0, 2.0]),  # 3 v 3, complete separation: p = 2/20
        ([5.0, 6.0, 7.0, 8.0], [1.0, 2.0, 3.0, 4.0]),  # 4 v 4: p = 2/70
        ([0.0, 0.0, 1.0, 0.5, 1.0], [1.0, 1.0, 0.7, 1.0, 0.7]),  # ties across and within groups
        ([0.0, 0.0, 0.0, 0.1, 0.0], [0.0, 0.3, 0.2, 0.0, 0.0]),  # lumpy, near a boundary
        ([2.0, 2.0, 2.0], [2.0, 2.0, 2.0, 2.0]),  # every run tied
        ([1.0, 4.0, 2.0, 8.0, 3.0], [6.0, 5.0, 7.0]),  # 5 v 3
    ],
)
def test_permutation_p_matches_listing_every_split(x: list[float], y: list[float]) -> None:
    probability, p = permutation_test(x, y)
    assert probability == pytest.approx(probability_of_improvement(x, y), abs=1e-12)
    assert p == pytest.approx(brute_force_p(x, y), abs=1e-12)


def test_known_exact_p_values() -> None:
    assert permutation_test([3, 4, 5], [0, 1, 2]) == (1.0, pytest.approx(0.1))
    assert permutation_test([5, 6, 7, 8, 9], [0, 1, 2, 3, 4]) == (1.0, pytest.approx(2 / 252))
    assert permutation_test([0, 1, 2, 3, 4], [5, 6, 7, 8, 9]) == (0.0, pytest.approx(2 / 252))
    assert permutation_test([0.1, 0.0], [0.9, 1.0], higher_is_better=False)[0] == 1.0  # fewer harms are better
    assert all(math.isnan(v) for v in permutation_test([math.nan], [1.0]))


def test_the_interval_excludes_half_exactly_when_the_test_rejects() -> None:
    rng = np.random.default_rng(11)
    seen = {True: 0, False: 0}
    for n, m in ((4, 4), (5, 3), (5, 5), (6, 4), (3, 3)):
        for _ in range(150):
            x = np.round(rng.normal(rng.uniform(0, 3), 1.0, n), 1)  # rounding makes ties
            y = np.round(rng.normal(0.0, 1.0, m), 1)
            probability, low, high = improvement_interval(x, y)
            rejected = permutation_test(x, y)[1] <= 0.05
            assert 0.0 <= low <= probability <= high <= 1.0
            assert (not low <= 0.5 <= high) == rejected
            seen[rejected] += 1
    assert seen[True] > 50 and seen[False] > 50  # both sides of the rule were exercised


def test_interval_width_is_the_tests_critical_distance() -> None:
    # 5 v 5 untied: rejected iff |P − 0.5| ≥ 0.42 (U ≤ 2 or ≥ 23), accepted up to 0.38: half-width 0.40
    assert improvement_interval([5, 6, 7, 8, 9], [0, 1, 2, 3, 4]) == (1.0, pytest.approx(0.6), 1.0)
    assert improvement_interval([1.5, 2.5, 3.5, 4.5, 5.5], [2, 3, 4, 5, 6]) == (0.4, 0.0, pytest.approx(0.8))
    assert improvement_interval([2.0] * 3, [2.0] * 4) == (0.5, 0.0, 1.0)  # all tied: nothing can be rejected
    with pytest.raises(ValueError, match="strictly between 0 and 1"):
        improvement_interval([1, 2], [3, 4], confidence=0.0)


def test_three_seeds_against_three_can_never_give_a_verdict() -> None:
    assert not can_decide(3, 3) and not can_decide(4, 3) and not can_decide(1, 1)
    assert can_decide(4, 4) and can_decide(5, 3) and can_decide(5, 5) and not can_decide(0, 5)
    assert smallest_decidable_seeds() == 4
    probability, low, high = improvement_interval([300.0, 301.0, 302.0], [1.0, 2.0, 3.0])
    assert probability == 1.0 and low <= 0.5 <= high  # the most extreme 3 v 3 split stays inside
    assert improvement_verdict(low, high, 3, 3) == TOO_FEW_SEEDS and VERDICT_MARKS[TOO_FEW_SEEDS]
    assert improvement_verdict(low, high) == "no clear difference"  # the interval alone says the same


def _run(method: str, seed: int, value: float, selfishness: float = 1.0) -> RunResult:
    """A run beside four cats whose one training episode and greedy episode survived ``value`` steps
    and harmed ``value // 100`` cats (more with longer survival)."""
    train = {"episode_end_step": [MAX_CYCLES], "survival": [value], "harms": [value // 100]}
    evaluations = [{"step": MAX_CYCLES, "survival": [value], "harms": [value // 100]}]
    return hand_made_result(
        "coexistence_v0", method, seed, train, evaluations, settings={"selfishness": selfishness}, env_kwargs={"num_cats": 4}
    )


def _verdicts(method_values: list[float], dqn_values: list[float]) -> dict[str, Improvement]:
    runs = [_run("dqn", s, v) for s, v in enumerate(dqn_values)]
    runs += [_run("empathic_dqn", s, v, 0.5) for s, v in enumerate(method_values)]
    cells = improvements_over_dqn(runs, {"coexistence_v0": ["survival", "harms"]})
    return {c.metric: c for c in cells if c.phase == "eval"}


def test_the_verdict_fires_on_runs_that_clearly_differ() -> None:
    cells = _verdicts([400.0, 410.0, 420.0, 430.0, 440.0], [100.0, 110.0, 120.0, 130.0, 140.0])
    assert cells["survival"].verdict == "better" and cells["survival"].ci_low > 0.5
    assert cells["harms"].verdict == "worse" and cells["harms"].ci_high < 0.5  # more harms are worse
    assert cells["survival"].p_value == pytest.approx(2 / 252)
    assert _verdicts([400.0, 410.0, 420.0, 430.0], [100.0, 110.0, 120.0, 130.0])["survival"].verdict == "better"


def test_the_verdict_does_not_fire_on_equal_or_interleaved_runs() -> None:
    assert _verdicts([100.0] * 5, [100.0] * 5)["survival"].verdict == "no clear difference"
    cell = _verdicts([98.0, 101.0, 102.0, 105.0, 106.0], [99.0, 100.0, 103.0, 104.0, 107.0])["survival"]
    assert cell.verdict == "no clear difference" and cell.ci_low <= 0.5 <= cell.ci_high


def test_three_seeds_say_too_few_seeds_however_large_the_gap() -> None:
    cells = _verdicts([400.0, 410.0, 420.0], [100.0, 110.0, 120.0])
    assert cells["survival"].probability == 1.0 and cells["survival"].verdict == TOO_FEW_SEEDS
    assert cells["survival"].p_value == pytest.approx(0.1)


def test_simulated_coverage_of_the_mean_interval_at_five_normal_seeds() -> None:
    rng = np.random.default_rng(2026)
    data = rng.normal(3.0, 2.0, size=(5, 4000))  # 4000 cells of 5 seeds, true mean 3
    _, low, high = mean_ci(data)
    coverage = float(((low <= 3.0) & (high >= 3.0)).mean())
    assert coverage >= 0.93  # measured by the benchmark: 97.4 %
    _, low, high = bootstrap_mean_ci(data[:3, :2000], random_state=0, n_resamples=1000)  # the old interval, 3 seeds
    assert float(((low <= 3.0) & (high >= 3.0)).mean()) < 0.85  # measured: 76 %


def test_simulated_false_positive_rate_of_the_verdict_at_five_against_five() -> None:
    rng = np.random.default_rng(7)
    fired = 0
    for _ in range(600):
        x, y = rng.lognormal(0.0, 0.5, 5), rng.lognormal(0.0, 0.5, 5)  # nothing differs
        _, low, high = improvement_interval(x, y)
        fired += improvement_verdict(low, high, 5, 5) != "no clear difference"
    assert fired / 600 <= 0.05  # exact size for untied data: 8/252 = 3.2 %


def test_an_interval_stays_inside_its_metrics_range() -> None:
    from leaderboard.aggregate import mean_ci, student_t_interval, t_level

    values = np.array([[0.0, 0.9, 0.5], [0.0, 0.6, 0.45], [1.2, 1.0, 0.55]])  # harms, equality, equality
    mean, low, high = mean_ci(values, metrics=["harms", "equality", "equality"])
    raw_mean, raw_low, raw_high = student_t_interval(values, level=t_level(0.95))
    np.testing.assert_array_equal(mean, raw_mean)
    assert raw_low[0] < 0 and low[0] == 0.0 and high[0] == raw_high[0]  # no harms below 0
    assert raw_high[1] > 1 and high[1] == 1.0 and low[1] == raw_low[1]  # no equality above 1
    assert low[2] == raw_low[2] and high[2] == raw_high[2]  # inside the range: unchanged
    single = mean_ci(np.array([0.0, 0.0, 3.0]), metrics="harms")
    assert single[1] == 0.0 and single[2] > 3.0 / 3


def test_survival_stays_below_the_longest_episode() -> None:
    from leaderboard.aggregate import longest_episode, mean_ci

    _, low, high = mean_ci(np.array([500.0, 480.0, 200.0]), metrics="survival", max_cycles=500)
    assert high == 500.0 and 0.0 <= low < 200.0
    shorter = synthetic_document("sharing_v0", "dqn", 1.0, 0)
    shorter["config"]["env_kwargs"] = {"max_cycles": 40}
    runs = [synthetic_result("coexistence_v0", "dqn", 1.0, 0), record(derive_run_id(shorter))]
    assert longest_episode(runs) == 500 and longest_episode(runs[1:]) == 40  # the environment's default where unset
