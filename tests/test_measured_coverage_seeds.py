"""The seed-count rule: a profile needs the fewest measured seeds at which every metric and phase
its verdicts read is covered at least 93 %; checked on hand-made figures."""

from __future__ import annotations

import pytest

from leaderboard.measured_coverage import SEED_TARGET, MeasuredCoverage, seeds_needed


def figures(**by_key: float) -> MeasuredCoverage:
    """``harms_eval_5=0.9`` → the coverage of harms in eval at 5 seeds (no zero-width intervals)."""
    entries = {}
    for key, value in by_key.items():
        metric, phase, seeds = key.rsplit("_", 2)
        entries[(metric, phase, int(seeds))] = (value, 0.0)
    return MeasuredCoverage("hand-made", entries)


def test_the_fewest_seeds_at_which_every_read_metric_reaches_the_target():
    coverage = figures(harms_eval_3=0.95, harms_eval_5=0.96, survival_eval_3=0.80, survival_eval_5=0.94)
    assert SEED_TARGET == 0.93
    assert seeds_needed(coverage, [("harms", "eval")]) == 3
    assert seeds_needed(coverage, [("harms", "eval"), ("survival", "eval")]) == 5


def test_exactly_the_target_is_enough_and_a_count_not_measured_for_every_read_is_skipped():
    coverage = figures(harms_eval_5=0.93, survival_eval_3=0.99, survival_eval_5=0.95)
    assert seeds_needed(coverage, [("harms", "eval"), ("survival", "eval")]) == 5


def test_none_where_no_measured_count_reaches_it():
    coverage = figures(survival_eval_3=0.74, survival_eval_5=0.83, survival_eval_10=0.92)
    assert seeds_needed(coverage, [("survival", "eval")]) is None
    assert seeds_needed(coverage, [("survival", "eval")], target=0.90) == 10


def test_an_empty_reading_is_refused():
    with pytest.raises(ValueError, match="at least one"):
        seeds_needed(figures(harms_eval_3=1.0), [])


def test_a_table_with_fewer_seeds_than_its_metrics_need_says_it_is_provisional():
    from leaderboard.legends import coverage_note
    from leaderboard.measured_coverage import MeasuredCoverage

    measured = MeasuredCoverage(
        "cmd",
        {
            ("harms", "eval", 3): (0.85, 0.0),
            ("harms", "eval", 10): (0.95, 0.0),
            ("survival", "eval", 3): (0.94, 0.0),
            ("survival", "eval", 10): (0.96, 0.0),
        },
    )
    note = coverage_note(measured, "eval", ["survival", "harms", "other_return"], [3])
    assert note.endswith(
        "With fewer than 10 seeds these intervals, and the verdicts that read them, are provisional: 10 is the fewest "
        "at which every metric here was measured to be covered at least 93 % (`leaderboard.measured_coverage.seeds_needed`)."
    )
    assert "provisional" not in coverage_note(measured, "eval", ["survival", "harms"], [10])
    assert "provisional" not in coverage_note(measured, "eval", ["survival"], [3])  # (survival is covered at 3)
    assert "provisional" not in coverage_note(None, "eval", ["survival"], [3])
