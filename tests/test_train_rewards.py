"""``TrainRewards``: each reward transform sees only the rows of the runs that use it, with a state
(and seeds) for those runs only."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from helpers_batches import one_other

from agents.rewards import TrainRewards
from agents.step_batch import StepBatch


@dataclass(frozen=True)
class Recorder:
    """Adds the run's seed to the reward and counts the steps it saw."""

    name: ClassVar[str] = "recorder"

    def initial_state(self, num_runs: int, envs_per_run: int, seeds: list[int]) -> dict[str, np.ndarray]:
        return {"seed": np.array(seeds, dtype=float)[:, None], "steps": np.zeros((num_runs, envs_per_run))}

    def __call__(self, batch: StepBatch, state: dict[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        assert batch.rewards.shape == state["steps"].shape  # only its own runs' rows
        return batch.rewards + state["seed"], {**state, "steps": state["steps"] + 1}


def _step(k: int) -> StepBatch:
    zeros = np.zeros((k, 1))
    return StepBatch(
        obs=np.zeros((k, 1, 25)),
        actions=zeros.astype(int),
        rewards=np.arange(k, dtype=np.float32)[:, None],
        terminated=zeros.astype(bool),
        next_obs=np.zeros((k, 1, 25)),
        harms=zeros.astype(int),
        battery_return=zeros,
        **one_other(np.zeros((k, 1, 25)), zeros.astype(bool), zeros),
    )


def test_a_transform_sees_and_keeps_state_for_its_own_runs_only() -> None:
    recorder = Recorder()
    rewards = TrainRewards([None, recorder, None, recorder], seeds=[10, 11, 12, 13])
    shaped = rewards(rewards(_step(4))).rewards[:, 0]
    assert shaped.tolist() == [0.0, 1.0 + 11 + 11, 2.0, 3.0 + 13 + 13]
    (state,) = rewards.state()
    assert state["steps"].tolist() == [[2.0], [2.0]] and state["seed"].ravel().tolist() == [11.0, 13.0]
