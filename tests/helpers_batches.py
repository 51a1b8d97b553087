"""The :class:`~agents.step_batch.StepBatch` fields of one other agent, for hand-made batches."""

from __future__ import annotations

from typing import Any

import numpy as np


def one_other(
    swapped: np.ndarray,
    present: np.ndarray,
    battery_return: np.ndarray,
    rewards: np.ndarray | None = None,
    unseen: np.ndarray | None = None,
) -> dict[str, Any]:
    """The ``closest`` and ``others_*`` fields of a batch whose learner has one other agent, from
    that agent's ``(K, M, V)`` swapped observations and its ``(K, M)`` presence, battery return,
    rewards (``None``: not said) and unseen flags (``None``: never unseen); it was there when the
    step began."""
    present = np.asarray(present, dtype=bool)
    shape = present.shape
    return {
        "closest": np.zeros(shape, dtype=np.int64),
        "others_swapped": np.asarray(swapped)[:, :, None],
        "others_present": present[:, :, None],
        "others_live": np.ones((*shape, 1), dtype=bool),
        "others_unseen": (np.zeros(shape, dtype=bool) if unseen is None else np.asarray(unseen, dtype=bool))[:, :, None],
        "others_battery_return": np.asarray(battery_return)[:, :, None],
        "others_rewards": None if rewards is None else np.asarray(rewards)[:, :, None],
    }
