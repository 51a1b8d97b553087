"""Matching the runs of two results directories and telling which computed the same."""

from __future__ import annotations

from helpers_results import edited, synthetic_result

from leaderboard.compare_runs import compare_runs


def test_runs_are_matched_by_experiment_and_seed_and_compared_column_by_column() -> None:
    old = [synthetic_result("coexistence_v0", "dqn", 1.0, seed, harms=0.5) for seed in range(3)]

    def one_more_harm(document: dict) -> None:  # one value of one column changed (within the one cat's 0 or 1)
        document["train"]["harms"][0] = 1 - document["train"]["harms"][0]

    new = [old[0], edited(old[1], one_more_harm), synthetic_result("coexistence_v0", "dqn", 1.0, 7, harms=0.5)]
    result = compare_runs(old, new)
    assert len(result["same"]) == 1 and len(result["different"]) == 1
    assert [key[-1] for key in result["only_old"]] == [2] and [key[-1] for key in result["only_new"]] == [7]
