"""Several ▲/▼ on one page: Holm's and Benjamini–Hochberg's adjusted p against hand-computed
values (ties, NaN, monotonicity), the expected number of false marks, and how the pages say both."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers_results import synthetic_result

from leaderboard.improvement import Improvement
from leaderboard.leaderboard_page import report_page
from leaderboard.legends import IMPROVEMENT_NOTE, multiplicity_note
from leaderboard.multiplicity import (
    HOLM_MARK,
    benjamini_hochberg_adjusted,
    expected_false_marks,
    holm_adjusted,
    rejected,
)
from leaderboard.page_html import to_html
from leaderboard.page_markdown import to_markdown
from leaderboard.tables import Provenance, improvement_sections
from leaderboard.versus_dqn import versus_dqn_tables

NAN = math.nan


def test_holm_by_hand() -> None:
    # sorted: 0.005·4 = 0.02, 0.01·3 = 0.03, 0.03·2 = 0.06, 0.04·1 = 0.04 → running max 0.06
    np.testing.assert_allclose(holm_adjusted([0.01, 0.04, 0.03, 0.005]), [0.03, 0.06, 0.06, 0.02])
    assert rejected(holm_adjusted([0.01, 0.04, 0.03, 0.005])).tolist() == [True, False, False, True]
    np.testing.assert_allclose(holm_adjusted([0.5, 0.9]), [1.0, 1.0])  # capped at 1


def test_benjamini_hochberg_by_hand() -> None:
    # sorted: 0.005·4/1 = 0.02, 0.01·4/2 = 0.02, 0.03·4/3 = 0.04, 0.04·4/4 = 0.04 → running min from the top
    np.testing.assert_allclose(benjamini_hochberg_adjusted([0.01, 0.04, 0.03, 0.005]), [0.02, 0.04, 0.04, 0.02])
    np.testing.assert_allclose(benjamini_hochberg_adjusted([0.04, 0.5, 0.045]), [0.0675, 0.5, 0.0675])


def test_ties_share_one_adjusted_p() -> None:
    np.testing.assert_allclose(holm_adjusted([0.02, 0.02, 0.02]), [0.06, 0.06, 0.06])
    np.testing.assert_allclose(benjamini_hochberg_adjusted([0.02, 0.02, 0.02]), [0.02, 0.02, 0.02])
    np.testing.assert_allclose(holm_adjusted([0.01, 0.03, 0.01]), [0.03, 0.03, 0.03])


def test_nan_is_not_in_the_family() -> None:
    holm = holm_adjusted([NAN, 0.01, 0.02])
    assert math.isnan(holm[0])
    np.testing.assert_allclose(holm[1:], [0.02, 0.02])
    bh = benjamini_hochberg_adjusted([0.01, NAN, 0.02])
    np.testing.assert_allclose(bh[[0, 2]], [0.02, 0.02])
    assert rejected([NAN, 0.01]).tolist() == [False, True]
    assert holm_adjusted([]).shape == (0,)


def test_adjustments_keep_the_order_of_p_and_holm_rejects_no_more_than_bh() -> None:
    rng = np.random.default_rng(7)
    for _ in range(200):
        p = rng.choice([0.001, 0.01, 0.02, 0.03, 0.2, 0.5, 1.0], size=rng.integers(1, 12)) * rng.uniform(0.5, 1.0)
        holm, bh = holm_adjusted(p), benjamini_hochberg_adjusted(p)
        for adjusted in (holm, bh):
            assert np.all(adjusted >= p - 1e-15) and np.all(adjusted <= 1.0)
            order = np.argsort(p, kind="stable")
            assert np.all(np.diff(adjusted[order]) >= -1e-15)  # monotone in p
        assert np.all(bh <= holm + 1e-15)
        assert not np.any(rejected(holm) & ~rejected(bh))


def test_expected_false_marks() -> None:
    assert expected_false_marks(108) == pytest.approx(5.4)
    assert expected_false_marks(20, level=0.05) == pytest.approx(1.0)


def _cell(metric: str, p: float, low: float, high: float, n: int = 5, m: int = 5, label: str = "Empathic DQN") -> Improvement:
    return Improvement("coexistence_v0", label, "eval", metric, 0.9, low, high, 0.1, n, m, p, "DQN")


def test_the_note_counts_the_cells_that_can_give_a_mark_and_names_the_holm_survivors() -> None:
    cells = [
        _cell("harms", 0.0079, 0.6, 1.0),  # ▲, survives Holm over 3 (0.0079·3 < 0.05)
        _cell("survival", 0.03, 0.51, 1.0),  # ▲, does not (0.03·2 > 0.05)
        _cell("other_return", 0.5, 0.2, 0.8),
        _cell("harms", 0.1, 0.0, 1.0, 3, 3, "Other"),  # ⊘: cannot give a mark, not in the family
    ]
    note = multiplicity_note(cells)
    assert "≈ 0.15 false marks expected among 3 cells" in note and "at 5 %" in note
    assert "Holm" in note and "1 of the 2 marks" in note
    (section,) = [s for s in improvement_sections(cells, "coexistence_v0") if s[0] == "eval"]
    row = section[2][0]
    assert row[2].startswith(f"▲{HOLM_MARK} ") and row[3].startswith("▲ ") and HOLM_MARK not in row[3]
    assert section[2][1][2].startswith("⊘ ")


def test_the_pages_carry_the_multiplicity_note() -> None:
    cells = [_cell("harms", 0.0079, 0.6, 1.0), _cell("survival", 0.5, 0.2, 0.8)]
    provenance = Provenance("cmd", "0.1.0", None)
    from leaderboard.aggregate import Score

    scores = [Score("coexistence_v0", "DQN", "dqn", "eval", "harms", 0.5, 0.0, 1.0, 5)]
    for page in (
        to_markdown(report_page(scores, provenance, improvements=cells)),
        to_html(report_page(scores, provenance, improvements=cells)),
    ):
        assert "≈ 0.1 false marks expected among 2 cells" in page
        assert HOLM_MARK in page
    assert "Mann–Whitney" in IMPROVEMENT_NOTE


def test_versus_dqn_legend_counts_its_own_cells() -> None:
    dqn = [synthetic_result("coexistence_v0", "dqn", 1.0, seed, harms=0.9, survival=400.0) for seed in range(5)]
    better = [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, seed, harms=0.0, survival=400.0) for seed in range(5)]
    text = versus_dqn_tables(dqn + better)
    # one method row × 3 metrics × 2 phases = 6 cells, every one decidable at 5 against 5
    assert "≈ 0.3 false marks expected among 6 cells" in text
    row = next(line for line in text.splitlines() if line.startswith("| empathic_dqn"))
    assert row.split("|")[3].count(f"▲{HOLM_MARK}") == 2  # p = 2/252 each: 6 × 0.0079 < 0.05


def test_a_page_without_a_decidable_cell_says_so() -> None:
    note = multiplicity_note([_cell("harms", 0.1, 0.0, 1.0, 3, 3)])
    expected = "No cell of this page's P(improves on DQN) tables can give a ▲ or ▼ (too few seeds), so none can be a false mark."
    assert note == expected


def test_the_note_says_when_holm_is_out_of_reach_of_the_seed_counts() -> None:
    # 5 against 5 gives p ≥ 2/252 ≈ 0.0079: over 7 cells Holm needs p ≤ 0.05/7 ≈ 0.0071 for the first
    cells = [_cell(metric, 2 / 252, 0.6, 1.0, label=f"m{k}") for k in range(7) for metric in ("harms",)]
    note = multiplicity_note(cells)
    assert "0 of the 7 marks do" in note and "the smallest p these seed counts can give, 0.0079, is above 5 % / 7" in note
    assert "No cell can" not in multiplicity_note(cells[:6])
