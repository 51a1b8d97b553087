"""A network a reward transform learns beside its runs, kept in the transform's state.

AUP's auxiliary Q-values (:mod:`baselines.aup`) and Be Considerate's value of the other agent
(:mod:`baselines.considerate`) are small stacked MLPs (one per run) whose parameters, target copy
and Adam moments live in the transform's state as numpy arrays (``online_i``, ``target_i``,
``avg_i``, ``avg_sq_i``, ``adam_steps``), so a checkpoint of the state is a checkpoint of the
learner. :func:`train_side_network` runs some gradient steps on them in place.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from agents.stacked_adam import StackedAdam

__all__ = ["train_side_network"]

Update = Callable[[list[torch.Tensor], list[torch.Tensor], StackedAdam], None]
"""One gradient step, given the online parameters, the target copy and the optimiser."""


def train_side_network(state: dict[str, np.ndarray], tensors: int, learning_rate: float, updates: int, update: Update) -> None:
    """Run ``update`` ``updates`` times on the network of ``state`` (``tensors`` parameter arrays,
    weights and biases), Adam with ``learning_rate``, and write its moments back into ``state``
    (the parameters are updated in place: the tensors share the arrays' memory)."""
    online = [torch.from_numpy(state[f"online_{i}"]).requires_grad_() for i in range(tensors)]
    target = [torch.from_numpy(state[f"target_{i}"]) for i in range(tensors)]
    optimizer = StackedAdam(online, lr=learning_rate)
    optimizer.load_state_dict(
        {
            "exp_avg": [torch.from_numpy(state[f"avg_{i}"]) for i in range(tensors)],
            "exp_avg_sq": [torch.from_numpy(state[f"avg_sq_{i}"]) for i in range(tensors)],
            "steps": torch.from_numpy(state["adam_steps"]),
        }
    )
    for _ in range(updates):
        update(online, target, optimizer)
    for i in range(tensors):
        np.copyto(state[f"avg_{i}"], optimizer.exp_avg[i].numpy())
        np.copyto(state[f"avg_sq_{i}"], optimizer.exp_avg_sq[i].numpy())
    np.copyto(state["adam_steps"], optimizer.step_count.numpy())
