"""Reward transforms of the DQN baselines (SPEC §6): a harm penalty (Coexistence) and equality
scaling (Sharing). A transform changes what a run trains on, never how it is scored: the suite's
metrics come from the environment's events. Each is a :class:`agents.base.RewardTransform` that
a :class:`agents.base.Method` composes (see :mod:`baselines.methods`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from agents.base import StepBatch
from empathy_zoo.metrics import equality

__all__ = ["HarmPenalty", "EqualityScaling", "HARM_PENALTY"]

HARM_PENALTY = -100.0
"""The Coexistence baseline's penalty for harming the cat."""


@dataclass(frozen=True)
class HarmPenalty:
    """``r' = r + penalty · (agents the learner harmed this step)``."""

    name: ClassVar[str] = "harm_penalty"
    penalty: float = HARM_PENALTY
    """Added to the reward once per agent harmed (the paper's baseline: −100)."""

    def __call__(self, batch: StepBatch) -> np.ndarray:
        return (batch.rewards.astype(np.float64) + self.penalty * batch.harmed_other).astype(np.float32)


@dataclass(frozen=True)
class EqualityScaling:
    """``r' = r · equality(own battery return, other's battery return)`` of the episode so far
    (SPEC §5's equality, this step included)."""

    name: ClassVar[str] = "equality_scaling"

    def __call__(self, batch: StepBatch) -> np.ndarray:
        current = equality(batch.battery_return, batch.other_battery_return)
        return (batch.rewards.astype(np.float64) * current).astype(np.float32)
