"""The exact reference drawn beside Empathic DQN's Coexistence curves, and only there."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_results import synthetic_result

from empathy_zoo.reference import coexistence_optimum
from leaderboard.plots import plot_metric
from leaderboard.reference_curves import reference_curve


def test_reference_follows_the_runs_epsilon_schedule() -> None:
    runs = [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, seed, harms=0.1, survival=450) for seed in range(3)]
    steps = np.array([250.0, 10_000.0, 19_950.0, 50_000.0])  # warm-up, decaying, near the end, after
    harms = reference_curve(runs, "harms", steps)
    assert harms is not None
    settings = runs[0].config.settings
    assert harms[0] == coexistence_optimum(0.5, 1.0).harms  # ε = 1 in the warm-up
    assert harms[-1] == coexistence_optimum(0.5, 0.01).harms  # ε at its floor
    assert harms[0] > harms[1] > harms[2]  # less exploration, fewer harms for an empathic robot
    survival = reference_curve(runs, "survival", steps)
    assert survival[-1] == coexistence_optimum(0.5, 0.01, gamma=settings["gamma"]).survival


def test_no_reference_where_it_does_not_apply() -> None:
    steps = np.array([100.0])
    coexistence = [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0)]
    assert reference_curve(coexistence, "equality", steps) is None
    assert reference_curve([synthetic_result("coexistence_v0", "dqn_harm_penalty", 1.0, 0)], "harms", steps) is None
    assert reference_curve([synthetic_result("sharing_v0", "empathic_dqn", 0.5, 0)], "harms", steps) is None
    stay = [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0, fixed={"cat_0": "stay"})]
    assert reference_curve(stay, "harms", steps) is None
    mixed = [*coexistence, synthetic_result("coexistence_v0", "empathic_dqn", 0.25, 1)]
    assert reference_curve(mixed, "harms", steps) is None


def test_figure_with_references_is_written(tmp_path) -> None:
    runs = [
        synthetic_result("coexistence_v0", method, beta, seed, harms=harms, survival=400)
        for seed in range(2)
        for method, beta, harms in (("empathic_dqn", 1.0, 0.9), ("empathic_dqn", 0.25, 0.1), ("dqn_harm_penalty", 1.0, 0.2))
    ]
    path = plot_metric(runs, "coexistence_v0", "harms", tmp_path / "harms.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_in_view_and_silver_variants_get_their_own_target() -> None:
    steps = np.array([50_000.0])  # ε at its floor, 0.01
    for method, arguments in (("empathic_dqn_in_view", {"in_view_only": True}), ("empathic_dqn_silver", {"rule": "silver"})):
        runs = [synthetic_result("coexistence_v0", method, 0.25, 0)]
        harms = reference_curve(runs, "harms", steps)
        assert harms is not None and harms[0] == coexistence_optimum(0.25, 0.01, **arguments).harms
    in_view = reference_curve([synthetic_result("coexistence_v0", "empathic_dqn_in_view", 0.25, 0)], "harms", steps)
    golden = reference_curve([synthetic_result("coexistence_v0", "empathic_dqn", 0.25, 0)], "harms", steps)
    # an unseen cat fares as the robot does: the in-view optimum is the omniscient one
    assert in_view[0] == pytest.approx(golden[0], abs=1e-9)
