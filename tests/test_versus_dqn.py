"""The compact method-against-DQN table: DQN's means in the heading, a marker per phase and metric."""

from __future__ import annotations

from helpers_results import synthetic_result

from leaderboard.versus_dqn import versus_dqn_tables


def _row(text: str, prefix: str) -> list[str]:
    return next(line for line in text.splitlines() if line.startswith(f"| {prefix}")).split("|")


def test_a_clearly_better_method_is_marked_and_three_seeds_against_three_cannot_be_decided() -> None:
    dqn = [synthetic_result("coexistence_v0", "dqn", 1.0, seed, harms=0.9, survival=400.0) for seed in range(5)]
    better = [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, seed, harms=0.0, survival=400.0) for seed in range(5)]
    text = versus_dqn_tables(dqn + better)
    assert "### coexistence_v0" in text and "DQN (5 seeds): harms 0.9" in text
    assert _row(text, "empathic_dqn")[3].count("▲") == 2  # fewer harms, greedy and in training
    text = versus_dqn_tables(dqn[:3] + better[:3])
    assert _row(text, "empathic_dqn")[3].count("⊘") == 2  # 3 seeds against 3 can decide nothing
