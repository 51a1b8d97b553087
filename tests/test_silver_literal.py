"""The paper's silver rule read literally (``dqn_silver_literal``): the learner feels only the other's
negative rewards, ``r' = r + care·min(r_j, 0)``. Checked on hand-made batches, and the premise of
its mark (DQN on both environments, by construction) on every reward the environments give."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers_batches import one_other

from agents.base import StepBatch
from baselines.methods import NO_NEGATIVE_REWARDS
from baselines.registry import METHODS
from baselines.shaping import NegativeRewardEmpathy
from empathy_zoo.vector import VectorEnv


def batch(rewards: list[float], other_rewards: list[float] | None) -> StepBatch:
    k = len(rewards)
    return StepBatch(
        obs=np.zeros((k, 1, 25), np.float32),
        actions=np.zeros((k, 1), int),
        rewards=np.array(rewards, np.float32)[:, None],
        terminated=np.zeros((k, 1), bool),
        next_obs=np.zeros((k, 1, 25), np.float32),
        harms=np.zeros((k, 1)),
        battery_return=np.zeros((k, 1)),
        **one_other(
            np.zeros((k, 1, 25), np.float32),
            np.ones((k, 1), bool),
            np.zeros((k, 1)),
            None if other_rewards is None else np.array(other_rewards, np.float32)[:, None],
        ),
    )


def test_only_the_others_negative_rewards_are_felt():
    shaped = NegativeRewardEmpathy(care=0.5)(batch([1.0, 1.0, 0.0, 0.75], [-2.0, 0.0, 3.0, -0.5]))
    assert shaped.dtype == np.float32
    np.testing.assert_array_equal(shaped[:, 0], np.array([0.0, 1.0, 0.0, 0.5], np.float32))


def test_where_the_other_loses_nothing_the_reward_is_the_learners_bit_for_bit():
    rewards = np.random.default_rng(0).random(100).astype(np.float32).tolist()
    shaped = NegativeRewardEmpathy(care=3.0)(batch(rewards, [0.0] * 50 + [1.0] * 50))
    assert np.array_equal(shaped[:, 0], np.array(rewards, np.float32))


def test_it_needs_the_others_rewards_and_a_finite_care():
    with pytest.raises(ValueError, match="other agent's rewards"):
        NegativeRewardEmpathy()(batch([1.0], None))
    for care in (-0.1, math.nan, math.inf, True):
        with pytest.raises(ValueError, match="care must be a finite number >= 0"):
            NegativeRewardEmpathy(care=care)


@pytest.mark.parametrize("env", ["coexistence_v0", "sharing_v0"])
def test_no_environment_gives_a_negative_reward_so_the_mark_holds(env):
    # the premise of the mark ≡ DQN: every agent's reward, over many random steps of every agent, is >= 0
    vector = VectorEnv(env, 64)
    rng = np.random.default_rng(1)
    vector.reset(seed=list(range(64)))
    lowest = math.inf
    for _ in range(600):
        step = vector.step(rng.integers(0, 5, (64, len(vector.learners))))
        lowest = min(lowest, float(step.rewards.min()))
    assert lowest >= 0.0
    assert METHODS["dqn_silver_literal"].identical_to[env] == ("dqn", NO_NEGATIVE_REWARDS)
