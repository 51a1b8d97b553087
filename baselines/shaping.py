"""Reward shaping of the DQN baselines (SPEC §6). Shaping changes what a learner trains on,
never how it is scored: the suite's metrics come from the environment's events."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from empathy_zoo.metrics import equality

if TYPE_CHECKING:
    from agents.base import StepBatch

__all__ = ["shaped_reward", "HARM_PENALTY"]

HARM_PENALTY = -100.0
"""The Coexistence baseline's penalty for harming the cat."""


def shaped_reward(settings: Sequence, batch: StepBatch) -> np.ndarray:
    """``(K, M)`` training rewards: the env reward, plus ``harm_penalty`` per agent harmed, and
    (with ``equality_shaping``) multiplied by the episode's current equality of battery rewards."""
    penalty = np.array([s.harm_penalty for s in settings], dtype=np.float64)[:, None]
    scale_by_equality = np.array([s.equality_shaping for s in settings], dtype=bool)[:, None]
    reward = batch.rewards.astype(np.float64) + penalty * batch.harmed_other
    current = equality(batch.battery_return, batch.other_battery_return)
    return np.where(scale_by_equality, reward * current, reward).astype(np.float32)
