"""Attainable utility preservation (Turner et al. 2020): the penalty on hand-made Q-values (none for
the no-op, the summed shift divided by the summed no-op values), the calibrated defaults, none
before the warm-up, an auxiliary learner that finds the Q-values of its random rewards on a tiny problem, a
run's numbers independent of its ensemble, and a state that survives a checkpoint."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from helpers_batches import one_other
from helpers_resume import whole_and_resumed

from agents.base import Method, StepBatch
from agents.empathic_dqn import EmpathicDQN
from agents.rewards import TrainRewards
from agents.settings import EmpathicDQNSettings
from baselines.aup import (
    NO_OP,
    TASK_VALUE,
    AttainableUtility,
    attainable_utility_penalty,
    auxiliary_reward_map,
    auxiliary_rewards,
)

V = 25
SMALL = AttainableUtility(
    num_rewards=3,
    learning_starts=32,
    penalty_starts=64,
    train_interval=1,
    replay_capacity=64,
    target_update_interval=50,
    discount=0.9,
)
SMALL_AUP = Method(
    name="dqn_aup_small",
    learner=EmpathicDQN,
    settings=EmpathicDQNSettings,
    preset={"selfishness": 1.0},
    reward=AttainableUtility(
        num_rewards=4, learning_starts=64, penalty_starts=128, train_interval=1, replay_capacity=500, target_update_interval=50
    ),
    label=lambda s: "DQN + AUP (small)",
    description="AUP whose learner starts after 64 transitions",
)


def one_hot(index: int) -> np.ndarray:
    cell = np.zeros(V, dtype=np.float32)
    cell[index] = 1.0
    return cell


def step(obs: np.ndarray, actions: list[int], next_obs: np.ndarray, rewards: list[float] | None = None) -> StepBatch:
    k = len(actions)
    zeros = np.zeros((k, 1))
    return StepBatch(
        obs=obs.reshape(k, 1, V),
        actions=np.array(actions, dtype=np.int64)[:, None],
        rewards=np.array(rewards or [1.0] * k, dtype=np.float32)[:, None],
        terminated=np.zeros((k, 1), bool),
        next_obs=next_obs.reshape(k, 1, V),
        harms=zeros,
        battery_return=zeros,
        truncated=np.zeros((k, 1), bool),
        **one_other(next_obs.reshape(k, 1, V), np.ones((k, 1), bool), zeros, rewards=np.zeros((k, 1), dtype=np.float32)),
    )


def test_the_penalty_is_the_summed_shift_against_the_no_op_over_the_summed_no_op_values() -> None:
    # one run, three steps (actions up, stay, left), two heads of five action values each
    q = np.zeros((1, 3, 2, 5))
    q[..., 0, :] = [3.0, 0.0, 5.0, 0.0, 1.0]  # head 0: Q(s, ∅) = 1
    q[..., 1, :] = [-2.0, 0.0, 10.0, 0.0, -6.0]  # head 1: Q(s, ∅) = −6 (its absolute value counts)
    actions = np.array([[0, NO_OP, 2]])
    penalty = attainable_utility_penalty(q, actions, weight=0.5)
    assert penalty[0].tolist() == pytest.approx([0.5 * (2 + 4) / 7, 0.0, 0.5 * (4 + 16) / 7])
    # a state whose no-op values are all 0 has no attainable utility to shift: no penalty
    flat = q.copy()
    flat[..., NO_OP] = 0.0
    assert attainable_utility_penalty(flat, actions, 0.5)[0].tolist() == [0.0, 0.0, 0.0]


def test_the_defaults_are_the_calibration_of_the_module_page() -> None:
    aup = AttainableUtility()
    assert TASK_VALUE == pytest.approx(100.0)  # noqa: SIM300 - the constant under test; +1 a step for ever at γ = 0.99
    assert aup.penalty_weight == pytest.approx(100.0 / 1.501) and aup.num_rewards == 30
    assert aup.penalty_starts == 2_000  # the learning_starts of the quick and methods profiles
    weights = auxiliary_reward_map(0, V, 30)
    assert weights.shape == (V, 30) and weights.dtype == np.float32
    assert -1.0 <= weights.min() < -0.9 and 0.9 < weights.max() < 1.0  # both signs: some goals like the cat
    assert np.array_equal(weights, auxiliary_reward_map(0, V, 30)) and not np.array_equal(weights, auxiliary_reward_map(1, V, 30))
    assert auxiliary_rewards(one_hot(3), weights).tolist() == pytest.approx((weights[3] / V).tolist())


def test_no_penalty_before_the_warm_up_then_none_for_the_no_op_and_the_formula_for_a_move() -> None:
    state = SMALL.initial_state(1, 1, [0])
    a, b = one_hot(0), one_hot(1)
    for i in range(SMALL.penalty_starts):
        shaped, state = SMALL(step(a if i % 2 else b, [i % 5], b if i % 2 else a), state)
        assert shaped[0, 0] == 1.0
    assert int(state["updates"][0]) == SMALL.penalty_starts - SMALL.learning_starts + 1
    stay, _ = SMALL(step(a, [NO_OP], a), state)
    assert stay[0, 0] == 1.0
    before = copy.deepcopy(state)
    move, state = SMALL(step(a, [0], b), state)
    expected = attainable_utility_penalty(SMALL.q_values(before, a.reshape(1, 1, V)), np.array([[0]]), SMALL.penalty_weight)
    assert expected[0, 0] > 0.0 and move[0, 0] == pytest.approx(1.0 - expected[0, 0], rel=1e-6)


def test_the_auxiliary_learner_finds_the_q_values_of_its_random_rewards() -> None:
    # two cells: from either, actions 0-3 go to the other and the no-op stays; Rᵢ(s') = wᵢ · o(s') / V
    a, b = one_hot(0), one_hot(1)
    moves = [(s, action, (t if action != NO_OP else s)) for s, t in ((a, b), (b, a)) for action in range(5)]
    state = SMALL.initial_state(1, 1, [0])
    for i in range(1_500):
        s, action, t = moves[i % len(moves)]
        _, state = SMALL(step(s, [action], t), state)
        if i == SMALL.learning_starts:
            first_loss = float(state["loss"][0])
    assert float(state["loss"][0]) < first_loss / 100
    reward = state["reward_map"][0][:2] / V  # (cell, head): the reward of arriving in a or b
    value = np.zeros((2, SMALL.num_rewards))
    for _ in range(500):  # value iteration: stay, or move to the other cell
        value = np.maximum(reward + SMALL.discount * value, reward[::-1] + SMALL.discount * value[::-1])
    exact_stay, exact_move = reward + SMALL.discount * value, reward[::-1] + SMALL.discount * value[::-1]
    learnt = SMALL.q_values(state, np.stack([a, b])[None])[0]  # (cell, head, action)
    close = {"rel": 0.05, "abs": 0.05 * float(np.abs(exact_stay).max())}  # (signed rewards: some values near 0)
    assert learnt[..., NO_OP] == pytest.approx(exact_stay, **close)
    for action in range(4):
        assert learnt[..., action] == pytest.approx(exact_move, **close)


def test_a_runs_rewards_are_the_same_alone_or_beside_other_runs() -> None:
    rng = np.random.default_rng(5)
    alone, together = TrainRewards([SMALL], seeds=[7]), TrainRewards([SMALL, None, SMALL], seeds=[7, 8, 9])
    for _ in range(SMALL.penalty_starts + 40):
        obs, next_obs = rng.integers(-1, 2, (2, 3, V)).astype(np.float32)
        actions = rng.integers(0, 5, 3).tolist()
        mine = alone(step(obs[:1], actions[:1], next_obs[:1])).rewards[0, 0]
        assert together(step(obs, actions, next_obs)).rewards[0, 0] == mine
    assert mine < 1.0 or actions[0] == NO_OP


@pytest.mark.parametrize(
    "field, value",
    [
        ("penalty_weight", -0.1),
        ("num_rewards", 0),
        ("discount", 1.0),
        ("penalty_starts", 1_000),
        ("replay_capacity", 8),
        ("train_interval", 0),
    ],
)
def test_bad_parameters_are_refused_naming_them(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        AttainableUtility(**{field: value})


def test_a_resumed_aup_run_equals_an_uninterrupted_one_and_differs_from_dqn(tmp_path, monkeypatch) -> None:
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training import RunnerOptions, train_runs

    settings = {"learning_starts": 64, "replay_capacity": 1_000, "epsilon_decay_steps": 300, "target_update_interval": 50}
    spec = RunSpec.of(
        env="sharing_v0", method="test_aup:SMALL_AUP", steps=600, eval_interval=300, eval_episodes=2, settings=settings
    )
    whole, resumed = whole_and_resumed(spec, tmp_path, monkeypatch)
    assert resumed["train"] == whole["train"] and resumed["eval"] == whole["eval"]
    assert resumed["config"]["reward"]["name"] == "attainable_utility" and resumed["config"]["reward"]["num_rewards"] == 4
    dqn = RunSpec.of(env="sharing_v0", method="dqn", steps=600, eval_interval=300, eval_episodes=2, settings=settings)
    plain = json.loads(train_runs([dqn], tmp_path / "dqn", RunnerOptions(progress=False))[0].read_text())
    assert plain["eval"] != whole["eval"]  # the penalty was in force (from step 128), and changed what was learnt


def test_each_run_draws_its_own_auxiliary_rewards_and_networks_from_its_seed() -> None:
    state = SMALL.initial_state(3, 1, [0, 1, 0])
    _, state = SMALL(step(np.stack([one_hot(0)] * 3), [0, 1, 2], np.stack([one_hot(1)] * 3)), state)
    rewards, weights = state["reward_map"], state["online_0"]
    assert not np.array_equal(rewards[0], rewards[1]) and np.array_equal(rewards[0], rewards[2])
    assert not np.array_equal(weights[0], weights[1]) and np.array_equal(weights[0], weights[2])
    with pytest.raises(ValueError, match="give TrainRewards the runs' seeds"):
        TrainRewards([SMALL])
