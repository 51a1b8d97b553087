"""SPEC §4 and §3b, as changed on 2026-12-01: an other out of view is *unseen*, not harmed (in-view
Empathic DQN then uses the robot's own target), and the closest other of a step is chosen when the
step begins (a cat harmed in the step is the one whose other-term is 0) — on hand-placed scenarios,
through the learner's replay, and at the exact optimum of Coexistence."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from helpers_placed import placed
from helpers_placed import step as _step

from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from empathy_zoo.reference import coexistence_optimum

ROBOT, DOWN, STAY = 0, 1, 4
BETA, GAMMA = 0.5, 0.99


def _placed(positions: dict, in_view_only: bool, num_cats: int = 1):
    fixed = {f"cat_{i}": "stay" for i in range(num_cats)}
    return placed("coexistence_v0", positions, fixed, in_view_only=in_view_only, env_kwargs={"num_cats": num_cats})


def _learned_targets(batch) -> tuple[float, float]:
    """``(y, y_emp)`` an Empathic DQN learner (β = 0.5) computes for ``batch`` after storing it in
    its replay and sampling it back, with every Q-value set by hand (Q̂(s') = 10, Q̂(s_emp') = 4)."""
    learner = EmpathicDQN([EmpathicDQNSettings(selfishness=BETA, learning_starts=10_000)], [0], obs_size=25)
    learner.observe(batch)
    sample = learner.sample_batch(torch.zeros((1, 1), dtype=torch.long))
    ones = torch.ones((1, 1, 5))
    y, y_emp = learner.targets(sample, ones, 10.0 * ones, 4.0 * ones)
    return float(y), float(y_emp)


def test_an_unseen_cat_gives_the_robots_own_target() -> None:
    # (0, 0) and (3, 3) on the 7 × 7 torus: 3 rows and 3 columns apart, outside the 5 × 5 window
    result, batch = _step(_placed({"robot_0": (0, 0), "cat_0": (3, 3)}, in_view_only=True), STAY)
    assert not batch.other_present[0, 0] and batch.other_unseen[0, 0]
    assert not result.other_swapped[0, 0].any()  # no picture of an unseen cat
    y, y_emp = _learned_targets(batch)
    assert y == pytest.approx(1.0 + GAMMA * 10.0) and y_emp == y  # the rule before gave β·y: this failed


def test_a_cat_in_view_is_cared_for_and_the_omniscient_swap_sees_the_unseen() -> None:
    result, batch = _step(_placed({"robot_0": (0, 0), "cat_0": (2, 2)}, in_view_only=True), STAY)
    assert batch.other_present[0, 0] and not batch.other_unseen[0, 0]
    y, y_emp = _learned_targets(batch)
    assert y_emp == pytest.approx(BETA * y + (1.0 - BETA) * GAMMA * 4.0)
    _, batch = _step(_placed({"robot_0": (0, 0), "cat_0": (3, 3)}, in_view_only=False), STAY)
    assert batch.other_present[0, 0] and not batch.other_unseen[0, 0]


@pytest.mark.parametrize("in_view_only", [False, True], ids=["omniscient", "in-view"])
def test_a_harmed_cat_still_gives_the_other_term_zero(in_view_only: bool) -> None:
    # the robot steps onto the cell right of the cat: the right one harms the left
    result, batch = _step(_placed({"robot_0": (2, 4), "cat_0": (3, 3)}, in_view_only), DOWN)
    assert result.harmed_by[0, 1] == ROBOT
    assert not batch.other_present[0, 0] and not batch.other_unseen[0, 0]
    y, y_emp = _learned_targets(batch)
    assert y_emp == pytest.approx(BETA * y)


def test_the_closest_cat_is_chosen_when_the_step_begins() -> None:
    # cat_0 (2 away) is the closest when the step begins and is harmed in it; cat_1 stays far away.
    # The rule before chose among the cats left at t+1 — cat_1, present — and charged nothing: this failed
    venv = _placed({"robot_0": (2, 4), "cat_0": (3, 3), "cat_1": (5, 6)}, in_view_only=False, num_cats=2)
    result, batch = _step(venv, DOWN)
    assert result.harmed_by[0, 1] == ROBOT and result.harmed_by[0, 2] == -1
    assert result.closest[0, 0] == 0 and result.other_terminated[0, 0] and not result.other_seen[0, 0]
    assert not batch.other_present[0, 0]
    assert batch.other_rewards[0, 0] == 0.0  # the harmed cat's reward, not the other cat's 1
    np.testing.assert_array_equal(result.others_present[0, 0], [False, True])
    y, y_emp = _learned_targets(batch)
    assert y_emp == pytest.approx(BETA * y)


def test_the_next_step_swaps_with_the_cat_still_there() -> None:
    venv = _placed({"robot_0": (2, 4), "cat_0": (3, 3), "cat_1": (5, 6)}, in_view_only=False, num_cats=2)
    _step(venv, DOWN)
    result, batch = _step(venv, STAY)
    assert result.closest[0, 0] == 1 and result.other_seen[0, 0] and batch.other_present[0, 0]
    np.testing.assert_array_equal(result.other_swapped[0, 0], venv.engine.observe_swapped(0, 2)[0])


# ---------------------------------------------------------------------------- the exact optimum
def test_the_in_view_optimum_no_longer_walks_into_the_cat_to_keep_it_in_sight() -> None:
    before = coexistence_optimum(0.25, 0.0, in_view_only=True, unseen="zero")
    after = coexistence_optimum(0.25, 0.0, in_view_only=True)
    assert before.survival < 30  # paid to keep the cat in view, it let the cat harm it after ≈ 22 steps
    assert after.survival == pytest.approx(500.0) and after.harms < 1e-9
    for beta in (0.75, 0.5, 0.25):
        omniscient = coexistence_optimum(beta, 0.01)
        old, new = (coexistence_optimum(beta, 0.01, in_view_only=True, unseen=u) for u in ("zero", "own"))
        # the unseen cat counted as a harmed one: the robot harmed it, or let it harm the robot, to keep it in view
        assert old.harms > omniscient.harms + 0.1 or old.survival < omniscient.survival - 100
        assert new.harms <= omniscient.harms and new.survival >= omniscient.survival
