"""Be Considerate (Alizadeh Alamdari et al. 2022): the bonus γ·α·F({V_j}) on hand-made values (sum
and min over the others, 0 for one that has left), paid on the learner's last step of an episode
only, with a value network whose output is known; a value learner that finds the other agent's
values from the other's rewards (never the robot's) on a tiny problem; a run's numbers independent
of its ensemble and drawn from its seed; a state that survives a checkpoint; the method through
``train`` on both environments."""

from __future__ import annotations

import json
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers_batches import one_other
from helpers_cli_method import TINY
from helpers_resume import SMALL_SETTINGS, small_run, whole_and_resumed

from agents.base import Method, StepBatch
from agents.empathic_dqn import EmpathicDQN
from agents.rewards import TrainRewards
from agents.settings import EmpathicDQNSettings
from baselines.aup import AttainableUtility
from baselines.considerate import Considerate, considerate_bonus
from baselines.registry import METHODS
from empathy_zoo.cli import main
from empathy_zoo.experiment.result_reader import read_result

V = 25
SMALL = Considerate(
    caring=2.0,
    discount=0.5,
    learning_starts=8,
    bonus_starts=16,
    train_interval=1,
    batch_size=8,
    replay_capacity=64,
    target_update_interval=20,
    hidden_size=16,
)
SMALL_CONSIDERATE = Method(
    name="dqn_considerate_small",
    learner=EmpathicDQN,
    settings=EmpathicDQNSettings,
    preset={"selfishness": 1.0},
    reward=Considerate(
        caring=20.0,
        learning_starts=32,
        bonus_starts=64,
        train_interval=1,
        replay_capacity=500,
        target_update_interval=50,
        hidden_size=16,
    ),
    label=lambda s: "DQN + Be Considerate (small)",
    description="Be Considerate whose value learner starts after 32 steps, its bonus weighed 20 times (its value is small yet)",
)


def one_hot(index: int) -> np.ndarray:
    cell = np.zeros(V, dtype=np.float32)
    cell[index] = 1.0
    return cell


def step(
    other_obs: np.ndarray,
    *,
    rewards: list[float] | None = None,
    other_rewards: list[float] | None = None,
    present: list[bool] | None = None,
    terminated: list[bool] | None = None,
    truncated: list[bool] | None = None,
) -> StepBatch:
    """One step of K runs × 1 environment in which the other agent is seen as ``other_obs`` (K, V)."""
    k = other_obs.shape[0]

    def column(values: list | None, default: float | bool, dtype: type) -> np.ndarray:
        return np.array(values if values is not None else [default] * k, dtype=dtype)[:, None]

    zeros = np.zeros((k, 1))
    return StepBatch(
        obs=np.zeros((k, 1, V), dtype=np.float32),
        actions=np.zeros((k, 1), dtype=np.int64),
        rewards=column(rewards, 1.0, np.float32),
        terminated=column(terminated, False, bool),
        next_obs=np.zeros((k, 1, V), dtype=np.float32),
        harms=zeros,
        battery_return=zeros,
        truncated=column(truncated, False, bool),
        **one_other(
            other_obs.reshape(k, 1, V).astype(np.float32),
            column(present, True, bool),
            zeros,
            rewards=column(other_rewards, 1.0, np.float32),
        ),
    )


def constant_value(state: dict, value: float) -> None:
    """Make every run's value network output ``value`` for every observation."""
    for i in range(6):
        state[f"online_{i}"][...] = 0.0
    state["online_5"][...] = value


def test_the_bonus_is_discount_times_caring_times_the_sum_or_the_min_of_the_others_values() -> None:
    values = np.array([[[50.0, 80.0], [50.0, 80.0], [50.0, 80.0]]])  # one run, three envs, two others
    present = np.array([[[True, True], [True, False], [False, False]]])
    total = considerate_bonus(values, present, caring=2.0, aggregate="sum", discount=0.5)
    worst = considerate_bonus(values, present, caring=2.0, aggregate="min", discount=0.5)
    assert total.tolist() == [[130.0, 50.0, 0.0]]  # 0.5 · 2 · (50 + 80), one that left counts 0
    assert worst.tolist() == [[50.0, 0.0, 0.0]]  # with min, one harmed other makes F 0
    one = considerate_bonus(values[..., :1], present[..., :1], 1.0, "sum", 0.99)
    assert np.array_equal(one, considerate_bonus(values[..., :1], present[..., :1], 1.0, "min", 0.99))
    with pytest.raises(ValueError, match="aggregate"):
        considerate_bonus(values, present, 1.0, "mean", 0.99)


def test_the_bonus_is_paid_at_the_time_limit_only_and_only_after_the_warm_up() -> None:
    state = SMALL.initial_state(4, 1, seeds=[0, 1, 2, 3])
    obs = np.stack([one_hot(i) for i in range(4)])
    ended: dict[str, Any] = {
        "terminated": [True, False, True, False],
        "truncated": [False, True, False, False],
        "present": [True, True, False, True],
    }
    shaped, state = SMALL(step(obs, **ended), state)
    assert shaped[:, 0].tolist() == [1.0] * 4  # before bonus_starts: the environment's reward
    state["seen"][...] = SMALL.bonus_starts
    constant_value(state, 30.0)
    shaped, state = SMALL(step(obs, rewards=[1.0, 2.0, 3.0, 4.0], **ended), state)
    # terminated (its own harm) beside the other: 1, no bonus; truncated: 2 + 0.5·2·30; terminated,
    # other harmed: 3; going on: 4
    assert shaped[:, 0].tolist() == [1.0, 32.0, 3.0, 4.0]


def test_with_bonus_on_termination_the_learners_own_harm_is_paid_as_the_time_limit() -> None:
    """The rule before: the bonus whenever the learner's episode ends, its own harm included."""
    anywhere = replace(SMALL, bonus_on_termination=True)
    state = anywhere.initial_state(4, 1, seeds=[0, 1, 2, 3])
    obs = np.stack([one_hot(i) for i in range(4)])
    ended: dict[str, Any] = {
        "terminated": [True, False, True, False],
        "truncated": [False, True, False, False],
        "present": [True, True, False, True],
    }
    state["seen"][...] = 0
    _, state = anywhere(step(obs, **ended), state)
    state["seen"][...] = anywhere.bonus_starts
    constant_value(state, 30.0)
    shaped, state = anywhere(step(obs, rewards=[1.0, 2.0, 3.0, 4.0], **ended), state)
    assert shaped[:, 0].tolist() == [31.0, 32.0, 3.0, 4.0]


def test_the_bonus_starts_with_the_learners_warm_up_of_the_methods_profile_and_may_be_set() -> None:
    profile = tomllib.loads(Path("empathy_zoo/profiles/methods.toml").read_text())
    assert Considerate().bonus_starts == profile["settings"]["learning_starts"] == 2_000
    assert Considerate().bonus_starts == AttainableUtility().penalty_starts  # as AUP's penalty
    assert Considerate(bonus_starts=5_000).bonus_starts == 5_000
    assert not Considerate().bonus_on_termination


def test_the_method_says_it_is_dqn_on_sharing() -> None:
    assert METHODS["dqn_considerate"].identical_to.keys() == {"sharing_v0"}
    other, reason = METHODS["dqn_considerate"].identical_to["sharing_v0"]
    assert other == "dqn" and "last battery" in reason
    assert METHODS["dqn"].identical_to == {} and METHODS["dqn_aup"].identical_to == {}


@pytest.mark.parametrize("env", ["sharing_v0", "coexistence_v0"])
def test_on_sharing_the_method_trains_as_dqn_seed_for_seed_and_on_coexistence_it_does_not(tmp_path, monkeypatch, env) -> None:
    """Sharing ends for everyone when the last battery is taken (within 49 steps: the patrolling
    human visits every cell), when the human has no future: the bonus is always 0 there."""
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training import RunnerOptions, train_runs

    bonuses: list[float] = []
    real_call = Considerate.__call__

    def spy(self, batch, state):
        shaped, after = real_call(self, batch, state)
        bonuses.extend((shaped - batch.rewards).ravel().tolist())
        return shaped, after

    monkeypatch.setattr(Considerate, "__call__", spy)
    small = {"learning_starts": 32, "bonus_starts": 64, "train_interval": 1, "replay_capacity": 500, "hidden_size": 16}

    def result(method: str) -> dict:
        spec = RunSpec.of(
            env=env,
            method=method,
            seed=3,
            steps=400,
            eval_interval=200,
            eval_episodes=2,
            settings=SMALL_SETTINGS,
            env_kwargs={"max_cycles": 60 if env == "sharing_v0" else 40},
            reward=small if method == "dqn_considerate" else None,
        )
        return json.loads(train_runs([spec], tmp_path / method, RunnerOptions(progress=False))[0].read_text())

    considerate, dqn = result("dqn_considerate"), result("dqn")
    assert len(bonuses) == 400
    columns = ("train", "eval")
    if env == "sharing_v0":
        assert not any(bonuses) and len(considerate["train"]["survival"]) >= 8
        assert [considerate[c] for c in columns] == [dqn[c] for c in columns]
    else:
        assert sum(b > 0.0 for b in bonuses) >= 2  # paid at the time limit, the cat unharmed
        assert [considerate[c] for c in columns] != [dqn[c] for c in columns]


def test_the_value_is_learnt_from_the_other_agents_rewards_not_the_robots() -> None:
    # the other agent cycles a → b → a …, earning 1 on arriving in b and 0 in a; with γ = 0.5:
    # V(a) = 1 + γ·V(b), V(b) = γ·V(a), so V(a) = 4/3 and V(b) = 2/3
    a, b = one_hot(0), one_hot(1)
    learner = Considerate(
        discount=0.5,
        learning_starts=16,
        bonus_starts=17,
        train_interval=1,
        batch_size=16,
        replay_capacity=64,
        target_update_interval=25,
        hidden_size=16,
        learning_rate=3e-3,
    )
    state = learner.initial_state(1, 1, seeds=[3])
    for i in range(1_500):
        into_b = i % 2 == 1
        _, state = learner(step((b if into_b else a)[None], rewards=[100.0], other_rewards=[1.0 if into_b else 0.0]), state)
    learnt = learner.values(state, np.stack([a, b])[None])[0]
    assert learnt.tolist() == pytest.approx([4 / 3, 2 / 3], rel=0.05)
    assert state["stored"][0] == 1_499  # every step but the first (the reset's observation is not known)


def test_a_transition_into_a_harm_is_terminal_and_a_new_episode_starts_afresh() -> None:
    state = SMALL.initial_state(1, 1, seeds=[0])
    a, b = one_hot(0), one_hot(1)
    _, state = SMALL(step(a[None]), state)
    _, state = SMALL(step(np.zeros((1, V)), other_rewards=[0.0], present=[False]), state)  # the cat is harmed
    assert state["stored"][0] == 1 and state["done"][0, 0] and state["reward"][0, 0] == 0.0
    assert np.array_equal(state["obs"][0, 0], a)
    _, state = SMALL(step(np.zeros((1, V)), other_rewards=[0.0], present=[False], truncated=[True]), state)
    assert state["stored"][0] == 1  # it has left: nothing to learn from until the next episode
    _, state = SMALL(step(b[None]), state)
    assert state["stored"][0] == 1  # the first step of an episode: no transition yet
    _, state = SMALL(step(a[None], truncated=[True]), state)
    assert state["stored"][0] == 2 and not state["done"][0, 1]  # a time-limit truncation bootstraps


def test_a_runs_rewards_are_the_same_alone_or_beside_other_runs_and_repeat_with_its_seed() -> None:
    def rollout(transforms: list, seeds: list[int], rows: int) -> list[float]:
        rng = np.random.default_rng(5)
        rewards = TrainRewards(transforms, seeds=seeds)
        mine = []
        for t in range(SMALL.bonus_starts + 60):
            obs = rng.integers(-1, 2, (3, V)).astype(np.float32)[:rows]
            batch = step(
                obs,
                other_rewards=rng.random(3)[:rows].tolist(),
                truncated=[t % 7 == 6] * rows,
                present=(rng.random(3) > 0.2)[:rows].tolist(),
            )
            mine.append(float(rewards(batch).rewards[0, 0]))
        return mine

    alone = rollout([SMALL], [7], 1)
    assert rollout([SMALL, None, SMALL], [7, 8, 9], 3) == alone
    assert rollout([SMALL], [7], 1) == alone
    assert any(r != 1.0 for r in alone)  # the bonus was paid
    assert rollout([SMALL], [8], 1) != alone  # another seed, another value network


def test_several_other_agents_are_refused_naming_the_problem() -> None:
    state = SMALL.initial_state(1, 1, seeds=[0])
    batch = step(one_hot(0)[None])
    batch.others_swapped = np.zeros((1, 1, 2, V), dtype=np.float32)
    with pytest.raises(ValueError, match=r"this environment has 2 other agents.*num_cats = 1"):
        SMALL(batch, state)


@pytest.mark.parametrize(
    "field, value",
    [
        ("caring", -1.0),
        ("aggregate", "mean"),
        ("discount", 1.0),
        ("bonus_starts", 8),
        ("replay_capacity", 4),
        ("train_interval", 0),
    ],
)
def test_bad_parameters_are_refused_naming_them(field: str, value) -> None:
    with pytest.raises(ValueError, match=field):
        Considerate(**{field: value}) if field != "bonus_starts" else Considerate(learning_starts=8, bonus_starts=value)


def test_a_resumed_considerate_run_equals_an_uninterrupted_one_and_differs_from_dqn(tmp_path, monkeypatch) -> None:
    from empathy_zoo.training import RunnerOptions, train_runs

    spec = small_run("test_considerate:SMALL_CONSIDERATE", seed=1)  # (some episodes reach the time limit, the cat unharmed)
    whole, resumed = whole_and_resumed(spec, tmp_path, monkeypatch)
    assert resumed["train"] == whole["train"] and resumed["eval"] == whole["eval"]
    assert resumed["config"]["reward"]["name"] == "considerate" and resumed["config"]["reward"]["bonus_starts"] == 64
    plain = json.loads(train_runs([small_run("dqn", seed=1)], tmp_path / "dqn", RunnerOptions(progress=False))[0].read_text())
    # the bonus was paid (from step 64, at the time limit), and changed what was learnt
    assert (plain["train"], plain["eval"]) != (whole["train"], whole["eval"])


@pytest.mark.parametrize("env", ["coexistence_v0", "sharing_v0"])
def test_the_method_trains_through_the_command_line(tmp_path, env) -> None:
    out = tmp_path / "out"
    assert (
        main(
            [
                "train",
                "--method",
                "dqn_considerate",
                "--env",
                env,
                "--caring",
                "0.5",
                "--bonus-starts",
                "100",
                "--reward-learning-starts",
                "50",
                "--reward-replay-capacity",
                "200",
                "--out",
                str(out),
                *TINY,
            ]
        )
        == 0
    )
    [path] = (out / "runs").glob("*.json")
    result = read_result(path)
    assert result.config.reward is not None
    assert result.config.reward["caring"] == 0.5 and result.config.reward["learning_starts"] == 50
    assert result.method_label == (
        "DQN + Be Considerate (caring=0.5, reward.replay_capacity=200, reward.learning_starts=50, bonus_starts=100)"
    )  # in the fields' order
    assert result.train.episodes and result.eval
