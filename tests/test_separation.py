"""The separation table (baselines.separation): each row's exact values are the solvers' own (DQN
and the golden rule are exact_solver.optimum's, the silver rule is the reference module's), the
harm penalty's greedy optimum never harms, the Lagrangian's bisection finds a stated λ, pairs
identical by construction say so, and the committed files are the table's JSON and Markdown."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from baselines.separation import (
    EPSILONS,
    in_view_values,
    policies_differ,
    separation_table,
    silver_values,
)
from baselines.separation_lagrangian import lagrangian_multiplier
from baselines.separation_reachability import NO_OP, relative_reachability_reward
from baselines.separation_render import equivalence_classes, from_json, to_json, to_markdown
from baselines.shaping import HARM_PENALTY
from empathy_zoo.exact_solver import episode_steps, optimal_values, optimum, outcome, tabular_model
from empathy_zoo.reference import TIE_TOLERANCE, coexistence_optimum, greedy_policy

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"


@pytest.fixture(scope="module")
def paper():
    return tabular_model("coexistence_v0")


@pytest.fixture(scope="module")
def committed():
    return from_json((RESULTS / "coexistence_v0.json").read_text(encoding="utf-8"))


def acting(greedy: np.ndarray, epsilon: float) -> np.ndarray:
    return epsilon / 5 + (1.0 - epsilon) * greedy


@pytest.mark.parametrize("epsilon", EPSILONS)
def test_dqn_and_the_golden_rule_are_the_exact_solvers_optimum(paper, committed, epsilon) -> None:
    dqn, solved = committed.outcome("dqn", epsilon), optimum(paper, 1.0, epsilon)
    assert (dqn.harms, dqn.survival) == pytest.approx((solved.harms, solved.survival), abs=1e-9)
    for beta in (0.75, 0.5, 0.25, 0.0):
        row, solved = committed.outcome(f"empathic_dqn β={beta:g}", epsilon), optimum(paper, beta, epsilon)
        assert (row.harms, row.survival) == pytest.approx((solved.harms, solved.survival), abs=1e-9)


@pytest.mark.parametrize("epsilon", [0.0, 0.01])
@pytest.mark.parametrize("beta", [0.0, 0.5])
def test_the_silver_rule_is_the_reference_modules(paper, beta, epsilon) -> None:
    q = optimal_values(paper)
    result = outcome(paper, acting(greedy_policy(silver_values(paper, beta, q)), epsilon), episode_steps(paper))
    reference = coexistence_optimum(beta, epsilon, rule="silver")
    assert result.harms == pytest.approx(reference.harms, abs=1e-9)
    assert result.survival == pytest.approx(reference.survival, abs=1e-9)


@pytest.mark.parametrize("beta", [0.0, 0.5])
def test_the_in_view_rule_is_the_reference_modules(paper, beta) -> None:
    q = optimal_values(paper)
    result = outcome(paper, acting(greedy_policy(in_view_values(paper, beta, q)), 0.01), episode_steps(paper))
    reference = coexistence_optimum(beta, 0.01, in_view_only=True)
    assert (result.harms, result.survival) == pytest.approx((reference.harms, reference.survival), abs=1e-9)


def test_the_literal_silver_rule_has_no_negative_reward_to_feel(paper) -> None:
    assert paper.reward.min() >= 0.0
    assert tabular_model("coexistence_v0", rules="authors", max_cycles=501).reward.min() >= 0.0


def test_the_harm_penalty_optimum_never_harms_at_epsilon_zero(paper) -> None:
    q = optimal_values(paper, reward=paper.reward + HARM_PENALTY * paper.other_harmed)
    result = outcome(paper, greedy_policy(q), episode_steps(paper))
    assert result.harms == 0.0 and result.robot_harmed == 0.0 and result.survival == 500.0


def test_q_star_of_the_models_own_reward_is_unchanged(paper) -> None:
    assert np.array_equal(optimal_values(paper), optimal_values(paper, reward=paper.reward))


def test_relative_reachability_charges_no_op_nothing_and_a_harm_most(paper) -> None:
    shaped = relative_reachability_reward(paper)
    charged = paper.reward - shaped
    assert np.array_equal(shaped[:, NO_OP, :], paper.reward[:, NO_OP, :])  # the baseline's own action
    assert charged.min() >= 0.0 and not charged[paper.robot_harmed].any()
    still = ~paper.other_harmed[:, NO_OP : NO_OP + 1, :] & ~paper.robot_harmed[:, NO_OP : NO_OP + 1, :]
    harming = paper.other_harmed & ~paper.robot_harmed & still & (paper.start > 0)[:, None, None]  # the no-op: both stay
    assert charged[harming].min() > 90.0 > 1.0 > charged[~paper.other_harmed & ~paper.robot_harmed].max()


def test_the_lagrangian_bisection_finds_the_step_of_a_stated_harm_curve() -> None:
    def steps_at(price: float) -> float:  # harms 1 below λ = 0.3, 0.05 from there on
        return 1.0 if price < 0.3 else 0.05

    found = lagrangian_multiplier(steps_at, 0.1)
    assert found is not None and 0.3 <= found <= 0.3 * 1.001
    assert lagrangian_multiplier(lambda price: 0.05, 0.1) == 0.0
    assert lagrangian_multiplier(lambda price: 0.5, 0.1) is None


def test_the_lagrangian_rows_say_which_case_they_are(committed) -> None:
    at = {e: committed.outcome("dqn_lagrangian", e) for e in EPSILONS}
    # avoiding the cat costs Q* nothing, and a harming move harms with chance 1/5 at least: the
    # greedy policy drops every harm once λ/5 exceeds the tie tolerance, at λ = 5·TIE_TOLERANCE
    assert 5 * TIE_TOLERANCE < at[0.0].multiplier <= 5 * TIE_TOLERANCE * 1.001 and at[0.0].harms == 0.0
    assert at[0.01].harms <= committed.cost_limit
    assert at[0.05].multiplier is None and at[0.05].harms > committed.cost_limit and "no λ" in at[0.05].note


def test_pairs_identical_by_construction_are_labelled(committed) -> None:
    for epsilon in EPSILONS:
        for other in ("dqn_silver_literal", "dqn_equality"):
            pair = committed.pair("dqn", other, epsilon)
            assert pair is not None and not pair.differ and pair.by_construction
        assert committed.pair("dqn_silver_literal", "dqn_equality", epsilon).by_construction.startswith("both are dqn")
        assert not committed.pair("dqn", "dqn_harm_penalty", epsilon).by_construction


def test_the_differ_flag_is_symmetric_and_false_on_the_diagonal(committed) -> None:
    names = [row.name for row in committed.rows]
    for epsilon in EPSILONS:
        for a in names:
            assert not committed.differ(a, a, epsilon)
            for b in names:
                assert committed.differ(a, b, epsilon) == committed.differ(b, a, epsilon)


def test_policies_differ_is_symmetric_and_zero_for_one_policy(paper) -> None:
    q = optimal_values(paper)
    dqn, penalised = greedy_policy(q), greedy_policy(optimal_values(paper, reward=paper.reward - paper.other_harmed))
    for epsilon in (0.0, 0.01):
        assert policies_differ(paper, dqn, dqn, epsilon)[0] == 0
        assert policies_differ(paper, dqn, penalised, epsilon) == policies_differ(paper, penalised, dqn, epsilon)
        assert policies_differ(paper, dqn, penalised, epsilon)[0] > 0


def test_coexistence_separates_beta_zero_only_among_the_golden_rules(committed) -> None:
    for epsilon in EPSILONS:
        assert not committed.differ("empathic_dqn β=0.75", "empathic_dqn β=0.25", epsilon)
        assert committed.differ("empathic_dqn β=0.75", "empathic_dqn β=0", epsilon)
        assert not committed.differ("empathic_dqn β=0.5", "empathic_dqn_silver β=0.5", epsilon)
        assert committed.differ("empathic_dqn β=0", "empathic_dqn_silver β=0", epsilon)
        groups = equivalence_classes(committed, epsilon)
        assert sum(len(g) for g in groups) == len(committed.rows)


def test_the_json_round_trips(committed) -> None:
    assert from_json(to_json(committed)) == committed
    assert to_markdown(committed) == (RESULTS / "coexistence_v0.md").read_text(encoding="utf-8")


@pytest.mark.slow
def test_the_committed_table_is_the_computed_one(paper, committed) -> None:
    assert separation_table(paper) == committed
