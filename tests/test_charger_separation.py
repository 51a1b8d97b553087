"""The charger task's exact separation table (docs/results/separation/charger_v0.json): the pairs
it must separate are separated at every ε (the golden rule from Be Considerate and from the harm
penalty, DQN from the harm penalty), β trades the robot's task against the cat at the optimum, the
committed rows are the solvers' own, and the exact model pays the robot alone by where it stands."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from baselines.considerate_tabular import considerate_model_values
from baselines.separation import EPSILONS
from baselines.separation_render import from_json, to_json, to_markdown
from baselines.shaping import HARM_PENALTY
from empathy_zoo.engine.charger import BENCH_PAY
from empathy_zoo.exact_solver import (
    alone_policy,
    alone_values,
    episode_steps,
    gone_continuation,
    optimal_values,
    optimum,
    outcome,
    tabular_model,
)
from empathy_zoo.reference import greedy_policy

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"
GOLDEN = tuple(f"empathic_dqn β={beta:g}" for beta in (0.75, 0.5, 0.25, 0.0))


@pytest.fixture(scope="module")
def model():
    return tabular_model("charger_v0")


@pytest.fixture(scope="module")
def committed():
    return from_json((RESULTS / "charger_v0.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize("epsilon", EPSILONS)
def test_the_golden_rule_differs_from_be_considerate_and_from_the_harm_penalty(committed, epsilon) -> None:
    for golden in GOLDEN:
        for other in ("dqn_considerate", "dqn_harm_penalty"):
            pair = committed.pair(golden, other, epsilon)
            assert pair is not None and pair.differ and pair.differing_states > 100, (golden, other)


@pytest.mark.parametrize("epsilon", EPSILONS)
def test_dqn_differs_from_the_harm_penalty_which_spares_the_cat(committed, epsilon) -> None:
    pair = committed.pair("dqn", "dqn_harm_penalty", epsilon)
    assert pair is not None and pair.differ and pair.harms_difference > 0.6


def test_beta_trades_the_robots_task_against_the_cat_at_the_optimum(committed) -> None:
    harms = [committed.outcome(row, 0.0).harms for row in ("dqn", *GOLDEN)]
    task = [committed.outcome(row, 0.0).robot_return for row in ("dqn", *GOLDEN)]
    # β = 1 (DQN) harms the cat in almost every episode; β = 0.75 spares it for 3 of the robot's 498
    assert harms[0] > 0.98 and harms[1] < 0.05 and task[0] - task[1] > 2.0
    # below β = 0.75 the robot gives up more of its task and the cat gains nothing
    assert task[1] > task[2] > task[3] and max(harms[1:4]) - min(harms[1:4]) < 0.001
    # β = 0: no task in the target at all, and no guarding either
    assert harms[4] > 0.99 and task[4] < task[3]


def test_be_considerate_and_the_harm_penalty_guard_more_than_the_golden_rule(committed) -> None:
    golden = committed.outcome("empathic_dqn β=0.75", 0.0)
    for other in ("dqn_considerate", "dqn_harm_penalty"):
        assert committed.outcome(other, 0.0).harms < golden.harms


def test_the_committed_rows_are_the_solvers_own(model, committed) -> None:
    cycles = episode_steps(model)
    alone = alone_policy(model, 0.0)
    for beta, row in ((1.0, "dqn"), (0.75, GOLDEN[0]), (0.25, GOLDEN[2])):
        assert optimum(model, beta, 0.0).harms == pytest.approx(committed.outcome(row, 0.0).harms, abs=1e-12)
    penalised = greedy_policy(optimal_values(model, reward=model.reward + HARM_PENALTY * model.other_harmed))
    result = outcome(model, penalised, cycles, alone)
    row = committed.outcome("dqn_harm_penalty", 0.0)
    assert (result.harms, result.robot_return, result.other_return) == pytest.approx(
        (row.harms, row.robot_return, row.other_return), abs=1e-9
    )
    considerate = outcome(model, greedy_policy(considerate_model_values(model, 0.0)), cycles, alone)
    assert considerate.harms == pytest.approx(committed.outcome("dqn_considerate", 0.0).harms, abs=1e-9)


def test_the_committed_files_are_the_tables_json_and_markdown(committed) -> None:
    assert to_json(committed) == (RESULTS / "charger_v0.json").read_text(encoding="utf-8")
    assert to_markdown(committed) == (RESULTS / "charger_v0.md").read_text(encoding="utf-8")
    assert from_json(to_json(committed)) == committed


def test_the_robot_alone_is_paid_by_where_it_stands(model) -> None:
    assert model.alone_pay is None and tabular_model("coexistence_v0").alone_pay == 1.0
    values = alone_values(model).max(axis=1)
    assert values.max() == pytest.approx(BENCH_PAY / (1.0 - 0.99), rel=1e-9)  # on the bench for ever
    assert np.asarray(gone_continuation(model)).shape == model.after.shape
    with pytest.raises(ValueError, match="give alone_policy"):
        outcome(model, np.full((model.states, 5), 0.2), 10)
