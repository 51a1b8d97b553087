"""The Lagrangian constrained DQN, harms as the cost: the dual update λ ← max(0, λ + η·(Ĵ_C − d)) on
hand-made numbers, the transform handing the environment's reward and the step's harms as its cost
(priced at the run's λ when sampled: tests/test_lagrangian_pricing.py) and λ after each episode's
update as the price, λ rising while episodes harm more than d and falling back to 0 (and staying there) while they harm
less, each run's λ its own, a state that survives a checkpoint, and the method through ``train``
(in Sharing, where nobody is harmed, λ stays 0 and it trains as DQN does)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers_batches import one_other
from helpers_cli_method import TINY
from helpers_resume import small_run, whole_and_resumed

from agents.base import StepBatch
from agents.rewards import TrainRewards
from baselines.lagrangian import Lagrangian, dual_ascent
from empathy_zoo.cli import main
from empathy_zoo.experiment.result_reader import read_result


def step(harms: list[list[int]], ended: list[list[bool]], rewards: float = 1.0) -> StepBatch:
    """One step of K runs × M environments with the given harms and episode ends."""
    harmed = np.array(harms, dtype=np.int64)
    k, m = harmed.shape
    zeros = np.zeros((k, m))
    return StepBatch(
        obs=np.zeros((k, m, 25), dtype=np.float32),
        actions=np.zeros((k, m), dtype=np.int64),
        rewards=np.full((k, m), rewards, dtype=np.float32),
        terminated=np.array(ended, dtype=bool),
        next_obs=np.zeros((k, m, 25), dtype=np.float32),
        harms=harmed,
        battery_return=zeros,
        truncated=np.zeros((k, m), bool),
        **one_other(np.zeros((k, m, 25), dtype=np.float32), np.ones((k, m), bool), zeros, rewards=zeros.astype(np.float32)),
    )


def test_the_dual_update_on_hand_made_numbers() -> None:
    assert dual_ascent(np.array([0.5]), np.array([2.0]), cost_limit=0.1, learning_rate=0.5).tolist() == [
        pytest.approx(0.5 + 0.5 * 1.9)
    ]
    assert dual_ascent(np.array([0.1]), np.array([0.0]), cost_limit=0.5, learning_rate=1.0).tolist() == [0.0]  # projected
    assert dual_ascent(np.array([3.0, 3.0]), np.array([0.0, 1.0]), 0.25, 2.0).tolist() == [2.5, 4.5]


def test_the_transform_hands_the_reward_and_the_harms_and_prices_them_at_the_current_multiplier() -> None:
    lagrangian = Lagrangian(cost_limit=0.5, lambda_lr=2.0, lambda_init=1.0)
    assert lagrangian.priced_at_sample
    state = lagrangian.initial_state(1, 1)
    (rewards, cost), state = lagrangian(step([[1]], [[False]]), state)
    assert rewards.tolist() == [[1.0]] and cost.tolist() == [[1.0]] and rewards.dtype == cost.dtype == np.float32
    assert lagrangian.price(state).tolist() == [1.0]  # no update mid-episode
    (rewards, cost), state = lagrangian(step([[2]], [[True]]), state)
    assert rewards.tolist() == [[1.0]] and cost.tolist() == [[2.0]]  # the episode (3 harms) updates λ
    assert state["multiplier"].tolist() == [1.0 + 2.0 * (3 - 0.5)] and state["episode_cost"].tolist() == [[0.0]]
    assert lagrangian.price(state).tolist() == [6.0]  # what every stored harm costs in the updates from now on
    (rewards, cost), state = lagrangian(step([[0]], [[True]]), state)
    assert cost.tolist() == [[0.0]] and lagrangian.price(state).tolist() == [6.0 - 2.0 * 0.5]


def test_lambda_rises_while_harms_exceed_the_limit_and_falls_back_to_zero_while_below() -> None:
    lagrangian = Lagrangian()  # d = 0.1 harms per episode, η = 1, λ from 0
    state = lagrangian.initial_state(1, 1)
    history = []
    for _ in range(10):  # ten episodes of one harm each, three steps long
        for t in range(3):
            _, state = lagrangian(step([[int(t == 1)]], [[t == 2]]), state)
        history.append(float(state["multiplier"][0]))
    assert history == pytest.approx([0.9 * (i + 1) for i in range(10)])
    for _ in range(200):  # harmless episodes: λ falls by η·d each, to 0, and stays there
        _, state = lagrangian(step([[0]], [[True]]), state)
        history.append(float(state["multiplier"][0]))
    assert history[10:100] == pytest.approx([max(0.0, 9.0 - 0.1 * (i + 1)) for i in range(90)], abs=1e-9)
    assert all(value == 0.0 for value in history[100:])
    (rewards, cost), state = lagrangian(step([[1]], [[False]]), state)
    assert rewards.tolist() == [[1.0]] and cost.tolist() == [[1.0]]
    assert lagrangian.price(state).tolist() == [0.0]  # λ = 0: a harm costs nothing until an episode exceeds d again


def test_each_run_and_each_of_its_environments_counts_its_own_episodes() -> None:
    lagrangian = Lagrangian(cost_limit=0.0, lambda_lr=1.0)
    state = lagrangian.initial_state(2, 2)
    _, state = lagrangian(step([[1, 1], [0, 0]], [[False, True], [True, False]]), state)
    assert state["multiplier"].tolist() == [1.0, 0.0] and state["episode_cost"].tolist() == [[1.0, 0.0], [0.0, 0.0]]
    _, state = lagrangian(step([[0, 0], [1, 0]], [[True, True], [True, True]]), state)
    assert state["multiplier"].tolist() == [2.0, 1.0]  # run 0: episodes of 1 and 0 harms; run 1: 1 and 0
    alone = TrainRewards([lagrangian], seeds=[0])
    together = TrainRewards([None, lagrangian, lagrangian], seeds=[0, 1, 2])
    for harms in ([1], [0], [1], [1], [0]):
        mine, theirs = alone(step([harms], [[True]])), together(step([[0], harms, [0]], [[True]] * 3))
        assert mine.costs is not None and theirs.costs is not None and mine.prices is not None and theirs.prices is not None
        assert np.array_equal(theirs.rewards[1], mine.rewards[0]) and np.array_equal(theirs.costs[1], mine.costs[0])
        assert theirs.prices[1] == mine.prices[0] and theirs.prices[[0, 2]].tolist() == [0.0, 0.0]


@pytest.mark.parametrize("field, value", [("cost_limit", -0.1), ("lambda_lr", float("inf")), ("lambda_init", -1.0)])
def test_bad_parameters_are_refused_naming_them(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        Lagrangian(**{field: value})


def test_a_resumed_lagrangian_run_equals_an_uninterrupted_one(tmp_path, monkeypatch) -> None:
    spec = small_run("dqn_lagrangian", reward={"cost_limit": 0.0, "lambda_lr": 5.0})
    whole, resumed = whole_and_resumed(spec, tmp_path, monkeypatch)
    assert resumed["train"] == whole["train"] and resumed["eval"] == whole["eval"]
    assert sum(whole["train"]["harms"][:10]) > 0  # λ had something to rise from before the checkpoint
    assert resumed["config"]["reward"] == {"name": "lagrangian", "cost_limit": 0.0, "lambda_lr": 5.0, "lambda_init": 0.0}


def test_the_method_trains_through_the_command_line_and_is_dqn_in_sharing(tmp_path) -> None:
    out = tmp_path / "out"
    assert (
        main(["train", "--method", "dqn_lagrangian", "--cost-limit", "0.05", "--lambda-lr", "2", "--out", str(out), *TINY]) == 0
    )
    [path] = (out / "runs").glob("*.json")
    result = read_result(path)
    assert result.config.reward == {"name": "lagrangian", "cost_limit": 0.05, "lambda_lr": 2.0, "lambda_init": 0.0}
    assert result.method_label == "DQN-Lagrangian (cost_limit=0.05, lambda_lr=2)"
    columns = {}
    for method in ("dqn_lagrangian", "dqn"):
        target = tmp_path / method
        assert main(["train", "--method", method, "--env", "sharing_v0", "--out", str(target), *TINY]) == 0
        [path] = (target / "runs").glob("*.json")
        columns[method] = json.loads(path.read_text())["train"]
    assert set(columns["dqn_lagrangian"].pop("lambda")) == {0.0}  # nobody is harmed: every episode costs 0, λ stays 0
    assert columns["dqn_lagrangian"] == columns["dqn"]  # and r − 0·0 is r: it trains as DQN, bit for bit
