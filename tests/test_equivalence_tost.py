"""The equivalence check's power and its TOST (leaderboard/equivalence.py): what the exact test
can reach at a seed count, whether Holm over the cells can reject anything at all, and the two
one-sided tests of equivalence within stated margins on hand-made samples."""

from __future__ import annotations

import math

import numpy as np
import pytest

from empathy_zoo.experiment.records import RunResult
from leaderboard.equivalence import (
    NO_DIFFERENCE,
    TOST_MARGINS,
    equivalence,
    holm_can_reject,
    smallest_p_value,
    tost,
    tost_cells,
)
from tests.helpers_results import synthetic_result


def test_the_margins_are_stated_before_any_data() -> None:
    assert TOST_MARGINS == {"survival": 25.0, "harms": 0.1, "batteries": 0.5, "equality": 0.05}


def test_the_smallest_reachable_p_and_holms_first_threshold() -> None:
    assert smallest_p_value(5, 5) == pytest.approx(2 / 252)
    assert smallest_p_value(3, 3) == pytest.approx(0.1)
    assert smallest_p_value(1, 1) == 1.0
    # 5 against 5 over 77 cells: 2/252 = 0.0079 > 0.05/77 = 0.00065: nothing can be rejected
    assert not holm_can_reject([(5, 5)] * 77)
    assert holm_can_reject([(10, 10)] * 77)
    assert holm_can_reject([(5, 5)] * 6)  # 0.05/6 = 0.0083 ≥ 0.0079
    assert not holm_can_reject([])


def test_tost_finds_clearly_equivalent_samples_equivalent() -> None:
    x = [0.50, 0.52, 0.48, 0.51, 0.49, 0.50, 0.51, 0.49, 0.50, 0.50]
    y = [v + 0.01 for v in x]
    result = tost(x, y, margin=0.1)
    assert result.verdict == "equivalent"
    assert result.difference == pytest.approx(-0.01)
    assert -0.1 < result.low < result.high < 0.1
    assert result.p_value < 0.05


def test_tost_does_not_call_clearly_different_samples_equivalent() -> None:
    x = [0.5, 0.52, 0.48, 0.51, 0.49]
    y = [v + 0.5 for v in x]
    result = tost(x, y, margin=0.1)
    assert result.verdict == "not shown equivalent" and result.p_value > 0.5


def test_tost_needs_the_interval_not_the_point_inside_the_margins() -> None:
    rng = np.random.default_rng(0)
    x, y = rng.normal(0.0, 1.0, 5), rng.normal(0.0, 1.0, 5)  # the same distribution, but spread ≫ margin
    result = tost(x, y, margin=0.1)
    assert result.verdict == "not shown equivalent"
    assert result.low < -0.1 or result.high > 0.1


def test_tost_with_too_few_seeds_gives_no_verdict() -> None:
    result = tost([0.5], [0.5, 0.51, 0.49], margin=0.1)
    assert result.verdict == "too few seeds" and math.isnan(result.p_value)


def test_tost_of_constant_samples_is_decided_by_the_difference() -> None:
    assert tost([0.0] * 5, [0.0] * 5, margin=0.1).verdict == "equivalent"
    assert tost([0.0] * 5, [0.2] * 5, margin=0.1).verdict == "not shown equivalent"


def test_tost_level_under_the_boundary_is_at_most_five_percent() -> None:
    """Samples whose true difference is exactly the margin are called equivalent in at most ~5 %."""
    rng = np.random.default_rng(3)
    hits = sum(tost(rng.normal(0.1, 0.05, 10), rng.normal(0.0, 0.05, 10), margin=0.1).verdict == "equivalent" for _ in range(400))
    assert hits / 400 <= 0.07


def _runs(draw_seed: int, harm_sd: float, seeds: int = 10) -> list[RunResult]:
    rng = np.random.default_rng(draw_seed)
    return [
        synthetic_result(
            "coexistence_v0",
            "empathic_dqn",
            0.5,
            seed,
            harms=float(rng.normal(1.0, harm_sd)),
            survival=float(rng.normal(400, 2)),
            other_return=float(rng.normal(450, 20)),
        )
        for seed in range(seeds)
    ]


def test_tost_over_the_cells_of_two_sets() -> None:
    close = tost_cells(_runs(1, 0.01), _runs(2, 0.01))
    assert {(c.phase, c.metric) for c in close.cells} == {
        (phase, metric) for phase in ("eval", "train_final10") for metric in ("survival", "harms")
    }  # other_return has no margin: not tested
    assert close.verdict == "equivalent"
    spread = tost_cells(_runs(1, 0.5), _runs(2, 0.5))
    assert spread.verdict == "not shown equivalent"
    assert {c.metric for c in spread.cells if c.verdict != "equivalent"} == {"harms"}
    few = tost_cells(_runs(1, 0.01, seeds=1), _runs(2, 0.01, seeds=1))
    assert few.verdict == "too few seeds"


def test_the_difference_test_says_no_difference_detected_not_equivalent() -> None:
    result = equivalence(_runs(1, 0.3), _runs(2, 0.3))
    assert result.verdict == NO_DIFFERENCE == "no difference detected"
    assert result.can_reject  # 10 against 10 over 6 cells
    assert result.seed_counts == [(10, 10)] * len(result.tested)


def test_the_report_prints_the_power_and_the_tost(tmp_path) -> None:
    from empathy_zoo.atomic import write_json_atomic
    from leaderboard.equivalence import report

    for name, draw in (("a", 1), ("b", 2)):
        for run in _runs(draw, 0.01, seeds=5):
            write_json_atomic(tmp_path / name / "runs" / f"{run.run_id}.json", run.to_document())
    text = report(str(tmp_path / "a"), str(tmp_path / "b"), with_tost=True)
    assert "**no difference detected**" in text
    assert "smallest p the exact test can reach is 0.0079" in text
    assert "**TOST: equivalent**" in text and "| harms |" in text


@pytest.mark.parametrize("df", [1, 2, 3, 7, 30])
def test_the_t_tail_matches_the_exact_series_at_integer_degrees_of_freedom(df: int) -> None:
    from leaderboard.aggregate import student_t_quantile
    from leaderboard.tost import t_quantile, t_upper_tail

    for probability in (0.6, 0.9, 0.95, 0.99):
        q = student_t_quantile(probability, df)
        assert t_upper_tail(q, df) == pytest.approx(1 - probability, rel=1e-9, abs=1e-12)
        assert t_quantile(probability, df) == pytest.approx(q, rel=1e-9)
    assert t_upper_tail(0.0, df + 0.5) == pytest.approx(0.5)
