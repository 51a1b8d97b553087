"""Reward transforms of the DQN baselines: a harm penalty (Coexistence) and equality scaling
(Sharing), the paper's (SPEC §6); the paper's silver rule read literally; inequity aversion, from
the literature. A transform changes
what a run trains on, never how it is scored: the suite's metrics come from the environment's
events. Each is a :class:`agents.rewards.RewardTransform` that
a :class:`agents.base.Method` composes (see :mod:`baselines.methods`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from agents.base import StepBatch
from agents.transform_fields import MAX_TRANSFORM_WEIGHT
from agents.transform_state import StateBounds, check_smoothed
from empathy_zoo.metrics import equality

__all__ = ["HarmPenalty", "EqualityScaling", "InequityAversion", "NegativeRewardEmpathy", "HARM_PENALTY"]

HARM_PENALTY = -100.0
"""The Coexistence baseline's penalty for harming the cat."""


@dataclass(frozen=True)
class HarmPenalty:
    """``r' = r + penalty · (agents the learner harmed this step)``."""

    name: ClassVar[str] = "harm_penalty"
    penalty: float = HARM_PENALTY
    """Added to the reward once per agent harmed (the paper's baseline: −100)."""

    def __call__(self, batch: StepBatch) -> np.ndarray:
        return (batch.rewards.astype(np.float64) + self.penalty * batch.harms).astype(np.float32)


@dataclass(frozen=True)
class EqualityScaling:
    """``r' = r · equality(own battery return, other's battery return)`` of the episode so far
    (SPEC §5's equality, this step included)."""

    name: ClassVar[str] = "equality_scaling"

    def __call__(self, batch: StepBatch) -> np.ndarray:
        current = equality(batch.battery_return, batch.other_battery_return)
        return (batch.rewards.astype(np.float64) * current).astype(np.float32)


@dataclass(frozen=True)
class InequityAversion:
    """Inequity aversion (Hughes et al. 2018, "Inequity aversion improves cooperation in intertemporal
    social dilemmas"), for two agents:

        r'ᵢ = rᵢ − α·max(eⱼ − eᵢ, 0) − β·max(eᵢ − eⱼ, 0),    eᵗ = γλ·eᵗ⁻¹ + rᵗ

    with ``eᵢ`` and ``eⱼ`` the temporally smoothed environment rewards of the learner and of its
    closest other agent (``StepBatch.other_rewards``, what the environment reports for that agent),
    reset at each episode's start. Both inequities are *penalised*: being ahead costs β, being
    behind costs α. Defaults: the paper's α = 5, β = 0.05, and γλ = 0.99 · 0.95."""

    name: ClassVar[str] = "inequity_aversion"
    disadvantageous: float = 5.0
    """α: weight of the other agent being ahead."""
    advantageous: float = 0.05
    """β: weight of being ahead of the other agent."""
    smoothing: float = 0.99 * 0.95
    """γλ: how much of the smoothed reward carries to the next step."""

    def __post_init__(self) -> None:
        """Refuse a smoothing outside ``[0, 1)`` (the smoothed rewards would grow without end) and
        weights whose inequity can outweigh :data:`agents.transform_fields.MAX_TRANSFORM_WEIGHT` rewards of a
        step: the smoothed rewards differ by at most ``R/(1 − γλ)`` (``R`` the largest reward of a
        step), so ``max(|α|, |β|)/(1 − γλ)`` is the most one step's reward is multiplied by."""
        for field in ("disadvantageous", "advantageous", "smoothing"):
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{field} must be a finite number, got {value!r}")
        if not 0.0 <= self.smoothing < 1.0:
            raise ValueError(f"smoothing must be in [0, 1), got {self.smoothing!r}")
        gain = max(abs(self.disadvantageous), abs(self.advantageous)) / (1.0 - self.smoothing)
        if gain > MAX_TRANSFORM_WEIGHT:
            raise ValueError(
                f"max(|disadvantageous|, |advantageous|) / (1 − smoothing) must be at most {MAX_TRANSFORM_WEIGHT:,g} "
                f"(agents.transform_fields.MAX_TRANSFORM_WEIGHT: the most a step's reward is weighed by, docs/limits.md), "
                f"got {gain:,.6g}"
            )

    def initial_state(self, num_runs: int, envs_per_run: int) -> dict[str, np.ndarray]:
        return {side: np.zeros((num_runs, envs_per_run)) for side in ("own", "other")}

    def check_state(self, state: Mapping[str, Any], initial: Mapping[str, np.ndarray], bounds: StateBounds) -> None:
        """A checkpoint's smoothed rewards (:func:`agents.transform_state.check_smoothed`)."""
        check_smoothed(state, initial, bounds, self.smoothing)

    def __call__(self, batch: StepBatch, state: dict[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        if batch.other_rewards is None:
            raise ValueError("inequity aversion needs the other agent's rewards (StepBatch.other_rewards)")
        own = self.smoothing * state["own"] + batch.rewards
        other = self.smoothing * state["other"] + batch.other_rewards
        shaped = (
            batch.rewards - self.disadvantageous * np.maximum(other - own, 0.0) - self.advantageous * np.maximum(own - other, 0.0)
        )
        ended = batch.terminated | (batch.truncated if batch.truncated is not None else False)
        return shaped.astype(np.float32), {"own": np.where(ended, 0.0, own), "other": np.where(ended, 0.0, other)}


@dataclass(frozen=True)
class NegativeRewardEmpathy:
    """The paper's silver rule read literally: "considering only negative rewards as objects of
    empathy" (its Discussion). The learner feels the other's bad rewards and nothing else:

        r' = r + care · min(r_j, 0)

    with ``r_j`` the reward of the learner's closest other agent this step, as the environment
    reports it (``StepBatch.other_rewards``). In both of the suite's environments the other's reward
    is the robot's reward function in the other's place (the swap Empathic DQN imagines), and it is
    never negative: a harmed cat gets 0, a human's battery pays +1. So ``r' = r`` exactly, and the
    method trains as DQN, bit for bit (its registry entry says so). Where an environment gives
    negative rewards, the discounted sum of the other's along the robot's own episode is what the
    robot's value weighs against its own."""

    name: ClassVar[str] = "negative_reward_empathy"
    care: float = 0.5
    """Weight of the other's negative rewards beside the learner's own (whose weight is 1)."""

    def __post_init__(self) -> None:
        if isinstance(self.care, bool) or not (isinstance(self.care, int | float) and 0.0 <= float(self.care) < float("inf")):
            raise ValueError(f"care must be a finite number >= 0, got {self.care!r}")

    def __call__(self, batch: StepBatch) -> np.ndarray:
        if batch.other_rewards is None:
            raise ValueError("the literal silver rule needs the other agent's rewards (StepBatch.other_rewards)")
        felt = np.minimum(batch.other_rewards.astype(np.float64), 0.0)
        return (batch.rewards.astype(np.float64) + self.care * felt).astype(np.float32)
