"""The helping task's exact separation table (docs/results/separation/helping_v0.json): DQN, the
silver rule and the golden rule have pairwise different optima at every β and ε; at ε = 0 DQN harms
the human in every episode, the silver and golden rules never do, and the golden rule carries the
human more batteries than the silver rule; β trades the robot's task against the human's welfare;
the committed rows are the solvers' own, and the exact model's swap exchanges who carries."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from baselines.separation import EPSILONS, SELFISHNESS
from baselines.separation_render import from_json, to_json, to_markdown
from baselines.separation_values import silver_values
from empathy_zoo.exact_solver import (
    alone_policy,
    empathic_values,
    episode_steps,
    optimal_values,
    outcome,
    tabular_model,
)
from empathy_zoo.reference import greedy_policy

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"
GOLDEN = tuple(f"empathic_dqn β={beta:g}" for beta in SELFISHNESS)
SILVER = tuple(f"empathic_dqn_silver β={beta:g}" for beta in SELFISHNESS)
CELLS = 25
"""Cells of the default 5×5 torus."""
HUMAN_GAIN = 8.0
"""Batteries per episode the golden rule at β = 0.5 carries the human beyond the silver rule's, at least."""
ROBOT_COST = 5.0
"""Batteries per episode of its own the golden rule at β = 0.5 gives up for it, at most."""


@pytest.fixture(scope="module")
def model():
    return tabular_model("helping_v0")


@pytest.fixture(scope="module")
def committed():
    return from_json((RESULTS / "helping_v0.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize("epsilon", EPSILONS)
def test_dqn_the_silver_rule_and_the_golden_rule_pairwise_differ(committed, epsilon) -> None:
    for golden, silver in zip(GOLDEN, SILVER, strict=True):
        for first, second in (("dqn", golden), ("dqn", silver), (golden, silver)):
            pair = committed.pair(first, second, epsilon)
            assert pair is not None and pair.differ and pair.differing_states > 50, (first, second, epsilon)
    for rows in (GOLDEN, SILVER):  # and every β of either rule has an optimum of its own
        for first, second in itertools.pairwise(rows):
            assert committed.differ(first, second, epsilon), (first, second, epsilon)


def test_dqn_harms_the_silver_rule_spares_and_the_golden_rule_helps(committed) -> None:
    dqn, silver, golden = (committed.outcome(row, 0.0) for row in ("dqn", SILVER[1], GOLDEN[1]))  # β = 0.5
    assert dqn.harms > 0.999 and silver.harms == golden.harms == 0.0
    assert dqn.robot_harmed == silver.robot_harmed == golden.robot_harmed == 0.0  # the robot is never harmed
    assert dqn.other_return < 1.0 and silver.other_return > 14.0  # a harmed human uses no more batteries
    assert golden.other_return - silver.other_return > HUMAN_GAIN
    assert 0.0 < silver.robot_return - golden.robot_return < ROBOT_COST
    assert dqn.robot_return - silver.robot_return > 10.0  # sparing a human that takes batteries costs the robot
    assert all(o.changed is None for o in committed.outcomes)  # who carries is no change to the world


def test_beta_trades_the_robots_task_against_the_humans_welfare(committed) -> None:
    task = [committed.outcome(row, 0.0).robot_return for row in ("dqn", *GOLDEN)]
    human = [committed.outcome(row, 0.0).other_return for row in ("dqn", *GOLDEN)]
    assert task == sorted(task, reverse=True) and len(set(task)) == len(task) and task[-1] == 0.0
    assert human == sorted(human) and len(set(human)) == len(human)
    silver_task = [committed.outcome(row, 0.0).robot_return for row in SILVER]
    assert max(silver_task[:3]) - min(silver_task[:3]) < 2.0  # the silver rule barely moves until β = 0
    for golden, silver in zip(GOLDEN, SILVER, strict=True):
        assert committed.outcome(golden, 0.0).other_return > committed.outcome(silver, 0.0).other_return


def test_the_committed_rows_are_the_solvers_own(model, committed) -> None:
    cycles, q = episode_steps(model), optimal_values(model)
    alone = alone_policy(model, 0.0)
    values = {"dqn": q, GOLDEN[1]: empathic_values(model, 0.5, q), SILVER[1]: silver_values(model, 0.5, q)}
    for row, value in values.items():
        result = outcome(model, greedy_policy(value), cycles, alone)
        o = committed.outcome(row, 0.0)
        assert (result.harms, result.robot_return, result.other_return) == pytest.approx(
            (o.harms, o.robot_return, o.other_return), abs=1e-9
        )


def test_the_committed_files_are_the_tables_json_and_markdown(committed) -> None:
    assert to_json(committed) == (RESULTS / "helping_v0.json").read_text(encoding="utf-8")
    assert to_markdown(committed) == (RESULTS / "helping_v0.md").read_text(encoding="utf-8")
    assert from_json(to_json(committed)) == committed


def test_the_model_holds_who_carries_and_the_swap_exchanges_it(model) -> None:
    assert model.layers == 4 and model.states == 4 * CELLS * CELLS and model.alone_states == 4 * CELLS
    assert model.layer_swap == (0, 2, 1, 3)
    assert model.start[CELLS * CELLS :].sum() == 0.0 and model.start.sum() == pytest.approx(1.0)
    np.testing.assert_array_equal(model.swapped[model.swapped], np.arange(model.states))
    robot_carries, human_carries = model.layer % 2, model.layer // 2
    np.testing.assert_array_equal(robot_carries[model.swapped], human_carries)
    assert not model.robot_harmed.any() and model.other_harmed.any()
    assert set(np.unique(model.reward).tolist()) == {0.0, 1.0} and set(np.unique(model.other_reward).tolist()) == {0.0, 1.0}
