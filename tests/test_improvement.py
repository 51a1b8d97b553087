"""Probability of improvement over DQN and the interquartile mean, on hand-made numbers, and their
tables in the leaderboard."""

from __future__ import annotations

import json
import math

import pytest
from helpers_results import MAX_CYCLES, derive_run_id, hand_made_result

from empathy_zoo.experiment.records import RunResult
from leaderboard.improvement import (
    bootstrap_improvement,
    improvement_verdict,
    improvements_over_dqn,
    interquartile_mean,
    is_dqn,
    probability_of_improvement,
)


def test_probability_of_improvement_counts_pairs_and_half_ties() -> None:
    assert probability_of_improvement([3, 4], [1, 2]) == 1.0
    assert probability_of_improvement([1, 2], [3, 4]) == 0.0
    assert probability_of_improvement([2, 3], [2, 1]) == pytest.approx((0.5 + 1 + 1 + 1) / 4)
    assert probability_of_improvement([0.1, 0.0], [0.9, 1.0], higher_is_better=False) == 1.0  # fewer harms
    assert probability_of_improvement([1, math.nan], [0]) == 1.0
    assert math.isnan(probability_of_improvement([math.nan], [0]))


def test_bootstrap_interval_brackets_the_point_and_collapses_on_one_run() -> None:
    p, low, high = bootstrap_improvement([1, 2, 3, 4, 5], [2, 3, 4, 5, 6], n_resamples=500)
    assert p == pytest.approx((6 + 0.5 * 4) / 25)  # 6 of the 25 pairs won, 4 tied
    assert low <= p <= high and 0.0 <= low < high <= 1.0
    assert bootstrap_improvement([2.0], [1.0, 3.0]) == (0.5, 0.5, 0.5)
    again = bootstrap_improvement([1, 2, 3, 4, 5], [2, 3, 4, 5, 6], n_resamples=500)
    assert again == (p, low, high)  # seeded


@pytest.mark.parametrize(
    ("values", "expected"),
    [
        ([1, 2, 3], 2.0),  # fewer than 4: the mean
        ([1, 2, 3, 100], 2.5),  # 4: one dropped each side
        ([100, 1, 2, 3, -50], 2.0),  # 5 (the paper's seeds): the middle three
        ([1, 2, 3, 4, 5, 6, 7, 8], 4.5),
        ([math.nan, 1.0], 1.0),
    ],
)
def test_interquartile_mean(values, expected) -> None:
    assert interquartile_mean(values) == expected


def _run(method: str, seed: int, value: float, selfishness: float = 1.0, env: str = "coexistence_v0") -> RunResult:
    """A run whose one training episode and greedy episode survived ``value`` steps and harmed a
    cat in a run of short survival (below 5 steps)."""
    harms = [int(value < 5)]
    train = {"episode_end_step": [MAX_CYCLES], "survival": [value], "harms": harms}
    return hand_made_result(
        env,
        method,
        seed,
        train,
        [{"step": MAX_CYCLES, "survival": [value], "harms": harms}],
        settings={"selfishness": selfishness},
    )


def test_dqn_is_the_baseline_and_every_other_method_is_compared_with_it() -> None:
    assert is_dqn(_run("dqn", 0, 1)) and is_dqn(_run("empathic_dqn", 0, 1))
    assert not is_dqn(_run("empathic_dqn", 0, 1, selfishness=0.5))
    assert not is_dqn(_run("dqn_harm_penalty", 0, 1))
    runs = [_run("empathic_dqn", s, 5.0 + s) for s in range(3)] + [_run("empathic_dqn", s, 6.0 + s, 0.5) for s in range(3)]
    cells = improvements_over_dqn(runs, {"coexistence_v0": ["survival", "harms"]})
    assert {(c.method_label, c.metric) for c in cells} == {("empathic_dqn 0.5", "survival"), ("empathic_dqn 0.5", "harms")}
    survival = next(c for c in cells if c.metric == "survival" and c.phase == "eval")
    assert survival.probability == pytest.approx(7 / 9) and survival.iqm == 7.0 and survival.n_baseline_seeds == 3
    assert improvements_over_dqn(runs[3:], {"coexistence_v0": ["survival"]}) == []  # no DQN here: nothing


def test_the_leaderboard_shows_the_tables(tmp_path) -> None:
    from test_leaderboard_report import write_synthetic_results

    from leaderboard import write_leaderboard

    paths = write_synthetic_results(tmp_path / "runs")
    for path in paths:  # make the "DQN" rows standard DQN
        result = json.loads(path.read_text())
        if result["method_label"] == "DQN":
            result["method"], result["config"]["settings"] = "dqn", {"selfishness": 1.0}
            path.unlink()  # (the run's id, and so its file's name, is the one its changed config gives)
            path.with_name(f"{derive_run_id(result)['run_id']}.json").write_text(json.dumps(result))
    markdown = write_leaderboard(tmp_path, command="c")["markdown"].read_text(encoding="utf-8")
    assert markdown.count("### P(improves on DQN)") == 4 and "· IQM" in markdown
    # 3 seeds against 3: every cell is marked as too few seeds for a verdict, and the legend says so
    rows = [line for line in markdown.splitlines() if line.startswith("| ") and "· IQM" in line]
    assert rows and all("⊘" in row and "▲" not in row and "▼" not in row for row in rows)
    assert "⊘: too few seeds for a verdict" in markdown and "exact two-sided Mann–Whitney permutation test" in markdown
    assert "the two-sided Student-t interval mean ± t·s/√n at 97.5 % nominal" in markdown
    assert "percentile-bootstrap interval over seeds" not in markdown and "bootstrap interval, each" not in markdown


@pytest.mark.parametrize(
    "low, high, verdict",
    [
        (0.55, 1.0, "better"),
        (0.0, 0.45, "worse"),
        (0.5, 1.0, "no clear difference"),
        (0.0, 0.5, "no clear difference"),
        (0.2, 0.9, "no clear difference"),
        (math.nan, math.nan, "no clear difference"),
    ],
)
def test_a_method_is_better_or_worse_than_dqn_only_when_its_whole_interval_says_so(low, high, verdict) -> None:
    assert improvement_verdict(low, high) == verdict


def test_verdicts_on_synthetic_runs_separate_a_clear_gain_from_noise() -> None:
    dqn = [_run("dqn", s, 100.0 + s) for s in range(5)]
    better = [_run("empathic_dqn", s, 300.0 + s, 0.5) for s in range(5)]  # every run beats every DQN run
    mixed = [_run("empathic_dqn", s, 98.0 + 2 * s, 0.25) for s in range(5)]  # interleaved with DQN's
    cells = improvements_over_dqn(dqn + better + mixed, {"coexistence_v0": ["survival", "harms"]})
    verdict = {(c.method_label, c.metric, c.phase): c.verdict for c in cells}
    assert verdict[("empathic_dqn 0.5", "survival", "eval")] == "better"
    assert verdict[("empathic_dqn 0.25", "survival", "eval")] == "no clear difference"
