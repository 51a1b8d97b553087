"""K independent MLPs as stacked tensors: one batched matmul runs all of them."""

from __future__ import annotations

import itertools
import math

import torch

__all__ = ["StackedMLP", "init_stacked_mlp"]


def init_stacked_mlp(sizes: list[int], generators: list[torch.Generator], device: torch.device) -> list[torch.Tensor]:
    """Parameters ``[W1, b1, W2, b2, ...]`` with a leading run axis (``W: (K, in, out)``,
    ``b: (K, 1, out)``), each run drawn from its own generator like ``torch.nn.Linear`` does:
    uniform in ``±1/sqrt(fan_in)`` for weights and biases."""
    params: list[torch.Tensor] = []
    for fan_in, fan_out in itertools.pairwise(sizes):
        bound = 1.0 / math.sqrt(fan_in)
        w = torch.stack([(torch.rand(fan_in, fan_out, generator=g) * 2 - 1) * bound for g in generators])
        b = torch.stack([(torch.rand(1, fan_out, generator=g) * 2 - 1) * bound for g in generators])
        params += [w.to(device), b.to(device)]
    return params


class StackedMLP:
    """Forward pass of K stacked ReLU MLPs on inputs ``(K, rows, in)`` -> ``(K, rows, out)``."""

    @staticmethod
    def forward_exact(params: list[torch.Tensor], x: torch.Tensor) -> torch.Tensor:
        """:meth:`forward` computed as products and sums over each run's own tensors (no batched
        matmul), so a run's values are bit for bit the same alone or beside any other runs.

        The CPU's batched matmul may sum a run's products in an order that depends on how many
        runs share the call when a run has few rows (acting on one observation), and one flipped
        greedy action would make a run's trajectory depend on its ensemble. This costs more FLOP
        for FLOP, so it serves the passes with few rows (acting, greedy evaluation) on one thread.
        """
        last = len(params) // 2 - 1
        for layer in range(last + 1):
            weight, bias = params[2 * layer], params[2 * layer + 1]
            x = (x.unsqueeze(-1) * weight.unsqueeze(1)).sum(dim=2) + bias
            if layer < last:
                x = torch.relu(x)
        return x

    @staticmethod
    def forward(params: list[torch.Tensor], x: torch.Tensor) -> torch.Tensor:
        last = len(params) // 2 - 1
        for layer in range(last + 1):
            x = torch.baddbmm(params[2 * layer + 1], x, params[2 * layer])
            if layer < last:
                x = torch.relu(x)
        return x
