"""Performance profiles and the optimality gap (Agarwal et al. 2021) on hand-made numbers whose
values were computed by hand from the definitions; the stratified bootstrap's intervals where they
can be counted; the leaderboard's normalized scores and its section and figure."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers_results import hand_made_result, synthetic_result

from empathy_zoo.experiment.records import RunResult
from leaderboard.page import Page
from leaderboard.page_html import to_html
from leaderboard.page_markdown import section_markdown
from leaderboard.profile_plot import render_profiles_png
from leaderboard.profile_section import (
    SECTION_TITLE,
    normalization,
    normalized_score,
    normalized_scores,
    profile_metrics,
    profile_section,
)
from leaderboard.profiles import (
    GAMMA,
    average_score_distribution,
    optimality_gap,
    optimality_gaps,
    performance_profiles,
    run_score_distribution,
    stratified_bootstrap,
)

SCORES = np.array([[0.2, 1.0], [0.6, 0.4], [1.2, 0.0]])
"""3 runs × 2 tasks. Sorted, the six scores are 0.0, 0.2, 0.4, 0.6, 1.0, 1.2; the tasks' means
over runs are 2/3 and 1.4/3 ≈ 0.467."""


def test_the_run_score_distribution_counts_scores_strictly_above_tau() -> None:
    taus = np.array([-0.1, 0.0, 0.4, 0.5, 1.0, 1.2])
    # above −0.1: all 6; above 0: 5; above 0.4: 0.6, 1.0, 1.2 (0.4 itself is not above); above 0.5:
    # the same 3; above 1: 1.2 alone; above 1.2: none
    expected = np.array([6, 5, 3, 3, 1, 0]) / 6
    assert run_score_distribution(SCORES, taus) == pytest.approx(expected)


def test_the_average_score_distribution_counts_task_means_above_tau() -> None:
    taus = np.array([0.4, 0.5, 0.7])  # task means 0.667 and 0.467: both above 0.4, one above 0.5, none above 0.7
    assert average_score_distribution(SCORES, taus) == pytest.approx([1.0, 0.5, 0.0])


def test_the_optimality_gap_clips_at_gamma() -> None:
    # γ = 1: min(score, 1) = 0.2, 1.0, 0.6, 0.4, 1.0, 0.0 → mean 3.2 / 6, gap 1 − 3.2 / 6 = 2.8 / 6
    assert optimality_gap(SCORES) == pytest.approx(2.8 / 6)
    assert GAMMA == 1.0
    # γ = 0.5: min = 0.2, 0.5, 0.5, 0.4, 0.5, 0.0 → mean 2.1 / 6 = 0.35, gap 0.15
    assert optimality_gap(SCORES, gamma=0.5) == pytest.approx(0.15)
    assert optimality_gap(np.ones((4, 3))) == 0.0 and optimality_gap(np.full((2, 1), 2.5)) == 0.0


@pytest.mark.parametrize(
    "bad", [np.array([0.1, 0.2]), np.empty((0, 1)), np.array([[0.1], [math.nan]])], ids=["1-D", "no run", "NaN"]
)
def test_scores_that_are_no_runs_by_tasks_array_of_finite_values_are_refused(bad: np.ndarray) -> None:
    with pytest.raises(ValueError, match=r"runs × tasks|finite"):
        optimality_gap(bad)


def test_one_run_has_a_zero_width_interval() -> None:
    interval = stratified_bootstrap(np.array([[0.3, 0.9]]), optimality_gap)
    assert (
        interval.point == pytest.approx([0.4]) and interval.low == pytest.approx([0.4]) and interval.high == pytest.approx([0.4])
    )


def test_the_bootstrap_interval_of_two_runs_spans_what_their_resamples_can_give() -> None:
    # runs 0 and 1 of one task: a resample is (0, 0) (gap 1), (0, 1) or (1, 0) (gap 0.5), or (1, 1) (gap 0), with
    # chances 1/4, 1/2, 1/4, so the 2.5th and 97.5th percentiles of 4,000 resamples are 0 and 1
    interval = stratified_bootstrap(np.array([[0.0], [1.0]]), optimality_gap, n_resamples=4000, random_state=7)
    assert (interval.point[0], interval.low[0], interval.high[0]) == (0.5, 0.0, 1.0)


def test_the_bootstrap_resamples_each_task_s_runs_on_their_own() -> None:
    # runs (0, 0) and (1, 1): resampling whole runs would always give equal tasks; resampling each
    # task's runs apart gives a run whose two tasks differ in half the draws
    scores = np.array([[0.0, 0.0], [1.0, 1.0]])

    def differing(sample: np.ndarray) -> float:
        return float((sample[:, 0] != sample[:, 1]).mean())

    interval = stratified_bootstrap(scores, differing, n_resamples=2000, random_state=0)
    assert interval.point[0] == 0.0 and interval.high[0] == 1.0


def test_the_random_state_is_explicit() -> None:
    scores = np.array([[0.13], [0.52], [0.71], [0.88], [0.97]])

    def bounds(random_state: int | np.random.Generator) -> tuple[float, float]:
        interval = stratified_bootstrap(scores, optimality_gap, random_state=random_state, n_resamples=50)
        return float(interval.low[0]), float(interval.high[0])

    assert bounds(3) == bounds(np.random.default_rng(3)) and bounds(3) != bounds(4)


def test_profiles_and_gaps_per_method() -> None:
    scores = {"a": SCORES, "b": np.array([[0.5], [0.5]])}
    taus = np.array([0.0, 0.5])
    profiles = performance_profiles(scores, taus, n_resamples=200)
    assert profiles["a"].fraction == pytest.approx([5 / 6, 0.5]) and profiles["a"].runs == 3
    assert profiles["b"].fraction == pytest.approx([1.0, 0.0])
    assert profiles["b"].low == pytest.approx([1.0, 0.0]) and profiles["b"].high == pytest.approx([1.0, 0.0])
    gaps = optimality_gaps(scores, n_resamples=200)
    assert gaps["a"][0] == pytest.approx(2.8 / 6) and gaps["b"] == pytest.approx((0.5, 0.5, 0.5))
    alone = optimality_gaps({"a": SCORES}, n_resamples=200)
    assert alone["a"] == gaps["a"]  # (each method draws from its own generator: another method changes nothing)


def hand_run(seed: int, survival: list[float], harms: list[float], label: str = "A") -> RunResult:
    """A Coexistence run of two cats and 400-step episodes whose last greedy evaluation is given."""
    train = {"episode_end_step": [1], "survival": [1], "harms": [0]}
    evaluations = [{"step": 1, "survival": survival, "harms": harms}]
    return hand_made_result(
        "coexistence_v0", "dqn", seed, train, evaluations, label=label, env_kwargs={"num_cats": 2, "max_cycles": 400}
    )


def test_scores_are_normalized_by_each_run_s_own_world() -> None:
    runs = [hand_run(0, [100.0, 300.0], [1.0, 2.0]), hand_run(1, [400.0, 400.0], [0.0, 0.0])]
    # seed 0: survival 200 / 400 = 0.5, harms 1.5 of 2 cats: 1 − 0.75 = 0.25; seed 1: 1 and 1
    assert normalized_scores(runs, "coexistence_v0", "survival")["A"][:, 0] == pytest.approx([0.5, 1.0])
    assert normalized_scores(runs, "coexistence_v0", "harms")["A"][:, 0] == pytest.approx([0.25, 1.0])
    gaps = optimality_gaps({m: normalized_scores(runs, "coexistence_v0", m)["A"] for m in ("survival", "harms")})
    assert gaps["survival"][0] == pytest.approx(0.25) and gaps["harms"][0] == pytest.approx(0.375)
    assert normalized_score(runs[0], "equality", 0.3) == pytest.approx(0.3)
    assert math.isnan(normalized_score(runs[0], "batteries", 3.0)) and math.isnan(normalized_score(runs[0], "return", 9.0))


def test_a_vase_run_s_harms_are_normalized_by_the_most_its_episode_holds(tmp_path) -> None:
    """Vase counts the broken vase besides the harmed cat: 2 harms an episode beside one cat score 0, not −1."""
    train = {"episode_end_step": [1], "return": [1], "harms": [0]}
    runs = [
        hand_made_result("vase_v0", "dqn", seed, train, [{"step": 1, "harms": harms}], label="A")
        for seed, harms in ((0, [2.0, 2.0]), (1, [1.0, 0.0]))
    ]
    assert normalized_scores(runs, "vase_v0", "harms")["A"][:, 0] == pytest.approx([0.0, 0.75])
    assert normalization("harms", "vase_v0") == "1 − harms ÷ (other agents + 1)"
    assert normalization("harms", "coexistence_v0") == normalization("harms") == "1 − harms per other agent"
    found, _ = profile_section(runs, tmp_path, n_resamples=50)
    assert found is not None
    section = section_markdown(found)
    assert "| Method | Seeds | 1 − harms ÷ (other agents + 1) |" in section
    assert "In vase_v0 an episode may count 1 harm besides one per other agent" in section
    assert "| A | 2 | 0.625 " in section  # (the gap: 1 − (0 + 0.75) / 2)


def test_only_metrics_of_a_known_range_are_normalized() -> None:
    assert normalization("survival") == "survival ÷ max_cycles" and normalization("harms") == "1 − harms per other agent"
    assert normalization("equality") == "equality"
    assert all(normalization(metric) is None for metric in ("batteries", "other_batteries", "return", "other_return"))
    assert profile_metrics("coexistence_v0", "coexistence_v0") == ("survival", "harms")
    assert profile_metrics("sharing_v0", "sharing_v0") == ("equality",)


def test_the_section_states_its_normalization_and_gamma_and_draws_its_figure(tmp_path) -> None:
    results = [
        synthetic_result("coexistence_v0", method, beta, seed, survival=survival, harms=harms)
        for method, beta, survival, harms in (("empathic_dqn", 1.0, 450.0, 0.9), ("empathic_dqn", 0.5, 300.0, 0.1))
        for seed in range(5)
    ]
    found, figures = profile_section(results, tmp_path, n_resamples=200)
    assert found is not None and found.title == SECTION_TITLE
    section, html_page = section_markdown(found), to_html(Page("x", [found]))
    assert "γ = 1" in section and "survival ÷ max_cycles" in section and "1 − harms per other agent" in section
    assert "| Method | Seeds | survival ÷ max_cycles | 1 − harms per other agent |" in section
    # β = 0.5: survival 300 + 0.01·seed of 500 → gap 1 − 300.02 / 500 = 0.39996; harms 0.1 + 0.01·seed of 1 cat → gap 0.12
    assert "| empathic_dqn 0.5 | 5 | 0.400 [" in section and "| 0.120 [" in section
    assert set(figures) == {"figure:coexistence_v0:profiles"} and figures["figure:coexistence_v0:profiles"].is_file()
    assert f"<h2>{SECTION_TITLE}</h2>" in html_page and "data:image/png;base64," in html_page


def test_a_figure_of_more_rows_than_columns_wraps() -> None:
    taus = np.linspace(0, 1, 11)
    profiles = performance_profiles({f"row {i}": np.array([[0.1 * i], [0.5]]) for i in range(7)}, taus, n_resamples=50)
    png = render_profiles_png([("survival ÷ max_cycles", profiles)], title="seven rows", dqn_labels={"row 0"})
    assert png.startswith(b"\x89PNG")
