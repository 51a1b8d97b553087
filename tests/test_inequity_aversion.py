"""Inequity aversion (Hughes et al. 2018) on hand-made numbers: both inequities penalised, the
rewards smoothed, the trace reset at an episode's end; its state survives a checkpoint."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers_batches import one_other
from helpers_resume import whole_and_resumed

from agents.base import StepBatch
from agents.rewards import TrainRewards
from baselines.shaping import InequityAversion


def step(own: list[float], other: list[float], ended: list[bool] | None = None) -> StepBatch:
    k = len(own)
    zeros = np.zeros((k, 1, 4), dtype=np.float32)
    return StepBatch(
        obs=zeros,
        actions=np.zeros((k, 1), dtype=np.int64),
        rewards=np.array(own, dtype=np.float32)[:, None],
        terminated=np.array(ended or [False] * k)[:, None],
        next_obs=zeros,
        harms=np.zeros((k, 1)),
        battery_return=np.zeros((k, 1)),
        truncated=np.zeros((k, 1), bool),
        **one_other(zeros, np.ones((k, 1), bool), np.zeros((k, 1)), rewards=np.array(other, dtype=np.float32)[:, None]),
    )


def test_both_inequities_are_penalised_on_smoothed_rewards_and_reset_at_the_episode_end() -> None:
    ia = InequityAversion(disadvantageous=5.0, advantageous=0.05, smoothing=0.5)
    state = ia.initial_state(2, 1)
    # run 0 falls behind (other gets 1.0), run 1 gets ahead (own 1.0)
    shaped, state = ia(step([0.0, 1.0], [1.0, 0.0]), state)
    assert shaped[:, 0].tolist() == pytest.approx([0.0 - 5.0 * 1.0, 1.0 - 0.05 * 1.0])
    # nothing happens: the smoothed gap halves, and is still penalised
    shaped, state = ia(step([0.0, 0.0], [0.0, 0.0], ended=[False, True]), state)
    assert shaped[:, 0].tolist() == pytest.approx([-5.0 * 0.5, -0.05 * 0.5])
    assert state["own"][1, 0] == 0.0 and state["other"][1, 0] == 0.0 and state["other"][0, 0] == 0.5
    shaped, _ = ia(step([0.0, 0.0], [0.0, 0.0]), state)
    assert shaped[1, 0] == 0.0 and shaped[0, 0] == pytest.approx(-5.0 * 0.25)  # run 1 started afresh
    with pytest.raises(ValueError, match="other_rewards"):
        ia(StepBatch(**{**step([0.0], [0.0]).__dict__, "others_rewards": None}), ia.initial_state(1, 1))


def test_the_trainer_keeps_and_restores_the_state_only_for_the_runs_of_the_transform() -> None:
    ia = InequityAversion(smoothing=0.5)
    rewards = TrainRewards([ia, None])
    first = rewards(step([0.0, 0.0], [1.0, 1.0]))
    assert first.rewards[:, 0].tolist() == pytest.approx([-5.0, 0.0])  # run 1 trains on its own reward
    saved = rewards.state()
    again = TrainRewards([ia, None])
    again.load_state(json.loads(json.dumps([{k: v.tolist() for k, v in saved[0].items()}])))
    assert again(step([0.0, 0.0], [0.0, 0.0])).rewards.tolist() == rewards(step([0.0, 0.0], [0.0, 0.0])).rewards.tolist()
    with pytest.raises(ValueError, match="other reward transforms"):
        TrainRewards([None, None]).load_state(saved)


def test_a_resumed_inequity_averse_run_equals_an_uninterrupted_one(tmp_path, monkeypatch) -> None:
    from empathy_zoo.experiment.model import RunSpec

    spec = RunSpec.of(
        env="sharing_v0",
        method="dqn_inequity_aversion",
        steps=600,
        eval_interval=300,
        eval_episodes=2,
        settings={"learning_starts": 64, "replay_capacity": 1_000, "epsilon_decay_steps": 300, "target_update_interval": 50},
    )
    whole, resumed = whole_and_resumed(spec, tmp_path, monkeypatch)
    assert resumed["train"] == whole["train"] and resumed["eval"] == whole["eval"]
    assert resumed["config"]["reward"] == {
        "name": "inequity_aversion",
        "disadvantageous": 5.0,
        "advantageous": 0.05,
        "smoothing": pytest.approx(0.9405),
    }
