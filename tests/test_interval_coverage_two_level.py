"""The coverage of the leaderboard's interval measured by resampling result files at two levels
(runs, then each drawn run's episodes), and how the tables say what was measured: the nominal
level, the coverage at the table's seed count, and a zero-width interval marked as such."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers_results import EVAL_EPISODES, synthetic_result

from leaderboard.aggregate import Score, run_scalars
from leaderboard.leaderboard_page import report_page
from leaderboard.measured_coverage import MeasuredCoverage, read_measured_coverage
from leaderboard.page_html import to_html
from leaderboard.page_markdown import to_markdown
from leaderboard.tables import Provenance, format_mean, table_rows

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import interval_coverage as ic  # benchmarks/interval_coverage.py


def _row(runs: list[list[float]], metric: str = "harms") -> ic.RowEpisodes:
    return ic.RowEpisodes("dir", "coexistence_v0", "label", "eval", metric, tuple(np.asarray(r, float) for r in runs), None)


def test_identical_runs_give_zero_width_intervals_that_always_cover() -> None:
    same = _row([[0.5] * 3] * 4)  # every episode of every run the same
    for n in (3, 5, 10):
        hits, flat = ic.two_level_coverage(same, n, 300, np.random.default_rng(n))
        assert hits.all() and flat.all()  # covered, and flagged as zero-width


def test_two_runs_of_one_episode_each_cover_exactly_when_the_draws_differ() -> None:
    # runs 0 and 1 (no episodes to resample): 3 draws are all equal with probability 1/4 and then miss
    # the mean 0.5; otherwise the mean is 1/3 or 2/3 with s = 0.577 and the t interval (±2.07) covers
    hits, flat = ic.two_level_coverage(_row([[0.0], [1.0]]), 3, 20_000, np.random.default_rng(2))
    assert flat.mean() == pytest.approx(0.25, abs=0.01)
    assert hits.mean() == pytest.approx(0.75, abs=0.01)
    assert not np.any(hits & flat)


def test_episodes_are_resampled_within_each_drawn_run() -> None:
    # one run: the run level draws it every time, so all spread comes from its episodes
    draws = ic.two_level_draws((np.array([0.0, 1.0]),), 4, 5_000, np.random.default_rng(3))
    assert draws.shape == (5_000, 4)
    assert set(np.unique(draws)) == {0.0, 0.5, 1.0}
    assert np.mean(draws == 0.5) == pytest.approx(0.5, abs=0.02)


def test_the_resampler_is_deterministic_for_a_seed() -> None:
    row = _row([[0.0, 1.0], [0.2, 0.2, 0.3], [1.0]])
    first = ic.two_level_coverage(row, 5, 300, np.random.default_rng(4))
    second = ic.two_level_coverage(row, 5, 300, np.random.default_rng(4))
    assert all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))


def test_rows_read_the_episodes_the_leaderboard_scores() -> None:
    runs = [synthetic_result("coexistence_v0", "dqn", 1.0, seed, harms=0.2, survival=300.0) for seed in range(3)]
    rows = ic.row_episodes(runs, "synthetic")
    keys = {(row.phase, row.metric) for row in rows}
    assert keys == {(phase, metric) for phase in ("eval", "train_final10") for metric in ("harms", "survival")}
    for row in rows:
        assert len(row.runs) == 3
        scored = [run_scalars(run)[row.phase][row.metric] for run in runs]
        assert [values.mean() for values in row.runs] == pytest.approx(scored)
        assert row.runs[0].size == (EVAL_EPISODES if row.phase == "eval" else 4)  # 10 % of 40 training episodes
        assert row.upper == (500 if row.metric == "survival" else None)


def test_the_summary_and_its_json(tmp_path: Path) -> None:
    rows = [_row([[0.0], [1.0]]), _row([[0.5]] * 3)]
    summary = ic.two_level_summary(rows, (3,), 4_000, np.random.default_rng(5))
    (entry,) = [e for e in summary if e["phase"] == "all"]
    assert entry["metric"] == "harms" and entry["seeds"] == 3 and entry["rows"] == 2
    assert entry["coverage"] == pytest.approx((0.75 + 1.0) / 2, abs=0.01)
    assert entry["zero_width"] == pytest.approx((0.25 + 1.0) / 2, abs=0.01)
    path = tmp_path / "coverage.json"
    ic.write_two_level_json(path, summary, command="python benchmarks/interval_coverage.py --two-level", seed=5, replicates=4000)
    measured = read_measured_coverage(path)
    assert measured is not None and measured.command.endswith("--two-level")
    assert measured.coverage("harms", "all", 3) == pytest.approx((entry["coverage"], entry["zero_width"]))
    assert measured.coverage("harms", "eval", 3) == measured.coverage("harms", "all", 3)  # every row is of eval
    assert measured.coverage("harms", "train_final10", 3) is None and measured.coverage("harms", "eval", 4) is None
    assert json.loads(path.read_text())["nominal_level"] == 0.975


MEASURED = MeasuredCoverage(
    command="python benchmarks/interval_coverage.py --two-level",
    entries={("harms", "eval", 5): (0.884, 0.12), ("survival", "eval", 5): (0.961, 0.0)},
)


def _scores(seeds: int, low: float = 0.1) -> list[Score]:
    return [
        Score("coexistence_v0", "DQN", "dqn", "eval", "harms", 0.5, low, 0.9 if low != 0.5 else 0.5, seeds),
        Score("coexistence_v0", "DQN", "dqn", "eval", "survival", 400.0, 300.0, 500.0, seeds),
    ]


def test_the_legend_says_the_nominal_level_and_the_coverage_measured_at_the_table_s_seeds() -> None:
    provenance = Provenance("cmd", "0.1.0", None)
    for page in (
        to_markdown(report_page(_scores(5), provenance, metrics=("survival", "harms"), coverage=MEASURED)),
        to_html(report_page(_scores(5), provenance, metrics=("survival", "harms"), coverage=MEASURED)),
    ):
        assert "97.5 % nominal" in page and "two-sided" in page
        assert "survival 96.1 %" in page and "harms 88.4 %" in page and "12 % zero-width" in page
        assert "--two-level" in page
    page = to_markdown(report_page(_scores(4), provenance, metrics=("survival", "harms"), coverage=MEASURED))
    assert "at 4 seeds: not measured" in page


def test_the_legend_says_not_measured_without_a_measurement() -> None:
    page = to_markdown(report_page(_scores(5), Provenance("cmd", "0.1.0", None), metrics=("survival", "harms"), coverage=None))
    assert "not measured" in page


def test_the_committed_measurement_is_read_by_default() -> None:
    measured = read_measured_coverage()
    assert measured is not None
    for metric in ("harms", "survival", "batteries", "equality"):
        for seeds in (3, 5, 10):
            assert measured.coverage(metric, "eval", seeds) is not None


def test_a_zero_width_interval_is_marked_not_printed_as_an_interval() -> None:
    assert format_mean(0.5, 0.5, 0.5, 3, mark_equal=True) == "0.50 ="
    assert format_mean(0.5, 0.5, 0.5, 3) == "0.50 [0.50, 0.50]"  # what other callers get, unchanged
    assert format_mean(0.5, 0.5, 0.5, 1, mark_equal=True) == "0.50 (n=1: no interval)"
    assert format_mean(0.5, 0.4999, 0.5001, 3, mark_equal=True) == "0.50 [0.50, 0.50]"  # narrow, not zero
    _, rows = table_rows(_scores(3, low=0.5), "coexistence_v0", "eval", ("harms", "survival"))
    assert rows[0][2] == "0.50 =" and rows[0][3] == "400.00 [300.00, 500.00]"
    page = to_markdown(
        report_page(_scores(3, low=0.5), Provenance("cmd", "0.1.0", None), metrics=("survival", "harms"), coverage=MEASURED)
    )
    assert "= every seed gave this value" in page
