"""SPEC §4 and §3b: an other out of view is *unseen*, not harmed (since 2026-12-04 in-view
Empathic DQN puts the robot's own continuation in its place, ``y_emp = y − (1 − β)·r``), and the
closest other of a step is chosen when the step begins (a cat harmed in the step is the one whose
other-term is 0) — on hand-placed scenarios, through the learner's replay, in the compiled
targets, and at the exact optimum of Coexistence."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from helpers_placed import placed
from helpers_placed import step as _step

from agents import fused_update
from agents.empathic_dqn import EmpathicDQN, empathic_targets
from agents.settings import EmpathicDQNSettings
from empathy_zoo.reference import coexistence_optimum, coexistence_values

ROBOT, DOWN, STAY = 0, 1, 4
BETA, GAMMA = 0.5, 0.99


@pytest.fixture
def needs_numba() -> None:
    pytest.importorskip("numba")
    if not fused_update.numba_available():
        pytest.skip(f"numba kernels do not build here: {fused_update.numba_unavailable_reason()}")


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


def test_an_unseen_cat_fares_as_the_robot_does() -> None:
    # (0, 0) and (3, 3) on the 7 × 7 torus: 3 rows and 3 columns apart, outside the 5 × 5 window
    result, batch = _step(_placed({"robot_0": (0, 0), "cat_0": (3, 3)}, in_view_only=True), STAY)
    assert not batch.other_present[0, 0] and batch.other_unseen[0, 0]
    assert not result.other_swapped[0, 0].any()  # no picture of an unseen cat
    y, y_emp = _learned_targets(batch)
    assert y == pytest.approx(1.0 + GAMMA * 10.0)
    # the robot's continuation γ·10 in the cat's place (the rule of 2026-12-01 gave y: this failed)
    assert y_emp == pytest.approx(y - (1.0 - BETA) * 1.0) and y_emp == pytest.approx(BETA * y + (1.0 - BETA) * GAMMA * 10.0)


def _hand_made_targets(others: str) -> dict[str, np.ndarray]:
    """One batch of three runs (β = 0, 0.5, 0.75) and four transitions whose other agents are all
    unseen: rewards 1, 0, 3 and −2, the third terminated; Q̂(s') by hand, the swapped values large
    (they must not count)."""
    n = 1 if others == "closest" else 2
    k, b, a = 3, 4, 5
    reward = np.tile(np.array([1.0, 0.0, 3.0, -2.0], np.float32), (k, 1))
    terminated = np.tile(np.array([False, False, True, False]), (k, 1))
    q_next = np.zeros((k, b, a), np.float32)
    target_next = np.tile(np.array([10.0, 7.0, 50.0, -4.0], np.float32)[None, :, None], (k, 1, a))
    swapped = np.full((k, b, n, a), 1000.0, np.float32)
    present = np.zeros((k, b, n), np.bool_)
    live = np.ones((k, b, n), np.bool_)
    unseen = np.ones((k, b, n), np.bool_)
    if others == "closest":
        swapped, present, live, unseen = swapped[:, :, 0], present[:, :, 0], live[:, :, 0], unseen[:, :, 0]
    return {
        "reward": reward, "terminated": terminated, "q_next": q_next, "target_next": target_next,
        "swapped": swapped, "present": present, "live": live, "unseen": unseen,
        "selfishness": np.array([[0.0], [0.5], [0.75]], np.float32),
    }  # fmt: skip


@pytest.mark.parametrize("others", ["closest", "mean", "min"])
def test_an_unseen_other_gives_y_less_the_unselfish_share_of_the_reward(needs_numba: None, others: str) -> None:
    """With every other unseen, ``y_emp = y − (1 − β)·r`` in the PyTorch targets and in the
    compiled ones, bit for bit alike (the rule of 2026-12-01 gave ``y``: this failed)."""
    x = _hand_made_targets(others)
    live = None if others == "closest" else x["live"]
    args = (x["reward"], x["terminated"], x["q_next"], x["target_next"], x["swapped"], x["present"])
    reward, terminated, q_next, target_next, swapped, present = (torch.from_numpy(v) for v in args)
    y, y_emp = (
        t.numpy()
        for t in empathic_targets(
            reward, terminated, q_next, target_next, swapped, present, GAMMA, torch.from_numpy(x["selfishness"]),
            others, None if live is None else torch.from_numpy(live), torch.from_numpy(x["unseen"]),
        )
    )  # fmt: skip
    expected_y = x["reward"] + GAMMA * np.where(x["terminated"], 0.0, x["target_next"][:, :, 0])
    np.testing.assert_allclose(y, expected_y, rtol=1e-6)
    np.testing.assert_allclose(y_emp, expected_y - (1.0 - x["selfishness"]) * x["reward"], rtol=1e-6, atol=1e-5)
    assert not np.allclose(y_emp[:2], y[:2])  # β < 1 and r ≠ 0: not the robot's own target
    mine = fused_update.empathic_targets(*args, GAMMA, x["selfishness"], others, live, x["unseen"])
    np.testing.assert_array_equal(mine[0], y)
    np.testing.assert_array_equal(mine[1], y_emp)


def test_a_cat_in_view_is_cared_for_and_the_omniscient_swap_sees_the_unseen() -> None:
    _result, batch = _step(_placed({"robot_0": (0, 0), "cat_0": (2, 2)}, in_view_only=True), STAY)
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
        old, own = (coexistence_optimum(beta, 0.01, in_view_only=True, unseen=u) for u in ("zero", "own"))
        # the unseen cat counted as a harmed one: the robot harmed it, or let it harm the robot, to keep it in view
        assert old.harms > omniscient.harms + 0.1 or old.survival < omniscient.survival - 100
        # the robot's own target where unseen charged it (1 − β)·r for keeping the cat in view: it kept away
        assert own.harms < omniscient.harms - 0.05 and own.survival > omniscient.survival + 10


@pytest.mark.parametrize("epsilon", [0.0, 0.01, 0.05])
def test_the_in_view_optimum_is_the_omniscient_one(epsilon: float) -> None:
    """An unseen cat fares as the robot does, so at the exact optimum the in-view target equals
    the omniscient one: the same harms and survival at every β < 1 (the rule of 2026-12-01 kept
    the cat out of sight: this failed)."""
    for beta in (0.0, 0.25, 0.5, 0.75):
        in_view, omniscient = coexistence_optimum(beta, epsilon, in_view_only=True), coexistence_optimum(beta, epsilon)
        assert in_view.harms == pytest.approx(omniscient.harms, abs=1e-9), beta
        assert in_view.survival == pytest.approx(omniscient.survival, abs=1e-6), beta


@pytest.mark.parametrize("beta", [0.0, 0.25, 0.5, 0.75])
def test_the_in_view_target_is_the_omniscient_one_at_the_optimum(beta: float) -> None:
    """At ``Q*`` a seen cat's term on a harmless step is the robot's own continuation, so putting
    that continuation in an unseen cat's place gives the omniscient ``Q_emp``."""
    in_view, omniscient = coexistence_values(beta, in_view_only=True)[1], coexistence_values(beta)[1]
    np.testing.assert_allclose(in_view, omniscient, rtol=0.0, atol=1e-9)
    own = coexistence_values(beta, in_view_only=True, unseen="own")[1]
    assert np.abs(own - omniscient).max() > 0.1  # the rule of 2026-12-01


def test_selfishness_moves_the_in_view_optimum() -> None:
    """β moves the in-view optimum where it moves the omniscient one: β = 0 lets the cat's good
    future pay for the robot's own harm, β = 0.5 does not (the rule of 2026-12-01 gave the same
    outcome at every β < 1: this failed)."""
    for epsilon in (0.0, 0.01, 0.05):
        zero, half = (coexistence_optimum(beta, epsilon, in_view_only=True) for beta in (0.0, 0.5))
        assert zero.survival < half.survival - 300, epsilon
    for epsilon in (0.01, 0.05):
        zero, half = (coexistence_optimum(beta, epsilon, in_view_only=True) for beta in (0.0, 0.5))
        assert zero.harms < half.harms - 0.05, epsilon
