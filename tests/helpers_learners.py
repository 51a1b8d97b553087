"""Plug-in learners that say, through the result file, what the trainer told them (named as
``helpers_learners:NAME``: pytest puts tests/ on the path)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from agents.base import Method, StepBatch

REPLAY_BYTES_PER_OTHER = 100
"""What :class:`RecordingLearner` reports as its replay memory, per other agent it was told of."""


@dataclass(frozen=True)
class RecordingSettings:
    """A learner that acts at random."""

    highest: float = 1_000.0
    """The largest observation value :class:`RecordingLearner` takes."""


class PlainLearner:
    """Acts at random; has only the methods the :class:`agents.base.Learner` protocol requires,
    and checks that every batch holds as many other agents as it was told of."""

    def __init__(
        self,
        settings: Sequence[RecordingSettings],
        seeds: Sequence[int],
        obs_size: int,
        num_actions: int,
        device: str,
        *,
        num_others: int,
    ) -> None:
        self.settings, self.num_actions, self.num_others = list(settings), num_actions, num_others
        self.rng = np.random.default_rng(list(seeds))

    def act(self, observations: np.ndarray, greedy: bool = False) -> np.ndarray:
        return self.rng.integers(self.num_actions, size=observations.shape[:2])

    def observe(self, batch: StepBatch) -> None:
        if batch.others_swapped.shape[2] != self.num_others or batch.closest.max() >= self.num_others:
            raise ValueError(f"told of {self.num_others} other agents, got a batch of {batch.others_swapped.shape[2]}")

    def live_stats(self) -> dict[str, float]:
        return {}

    def state_dict(self) -> dict[str, Any]:
        return {"rng": self.rng.bit_generator.state}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.rng.bit_generator.state = state["rng"]

    def memory_bytes_per_run(self) -> int:
        return 7


class RecordingLearner(PlainLearner):
    """:class:`PlainLearner` with the optional methods: its replay memory is said to hold
    :data:`REPLAY_BYTES_PER_OTHER` bytes per other agent, and it refuses observations above its
    settings' ``highest``."""

    def replay_bytes_per_run(self) -> int:
        return REPLAY_BYTES_PER_OTHER * self.num_others

    def check_observation_range(self, low: float, high: float) -> None:
        highest = self.settings[0].highest
        if high > highest:
            raise ValueError(f"observations range over [{low:g}, {high:g}], this learner takes values up to {highest:g}")


PLAIN = Method(name="plain", learner=PlainLearner, settings=RecordingSettings)
RECORDING = Method(name="recording", learner=RecordingLearner, settings=RecordingSettings)
