"""Adam over stacked per-run parameters, stepping each run's slice as its own tensor.

``torch.optim.Adam(fused=True)`` on a stacked tensor is fast, but its vectorised loop treats
elements differently depending on where they fall in the whole tensor, so a run's numbers would
depend on how many runs share the stack. Handing the fused kernel one view per run keeps every
run's update exactly what it would be alone, at fused speed. Without the fused kernel
(other builds), the same per-run views go through ``torch.optim.Adam``'s foreach path.
"""

from __future__ import annotations

import importlib
from typing import Any, cast

import torch

_reference_adam = importlib.import_module("torch.optim.adam").adam

__all__ = ["StackedAdam"]


class StackedAdam:
    """Adam (β₁ = 0.9, β₂ = 0.999, ε = 1e-8, no weight decay) for tensors with a leading run axis."""

    def __init__(
        self, params: list[torch.Tensor], lr: float, betas: tuple[float, float] = (0.9, 0.999), eps: float = 1e-8
    ) -> None:
        self.params = params
        self.lr, self.betas, self.eps = lr, betas, eps
        self.exp_avg = [torch.zeros_like(p, requires_grad=False) for p in params]
        self.exp_avg_sq = [torch.zeros_like(p, requires_grad=False) for p in params]
        runs = params[0].shape[0]
        self._step_table = torch.zeros((len(params), runs), dtype=torch.float32, device=params[0].device)
        """Adam's step count of every (tensor, run) slice: one distinct 0-d view each, since the
        reference implementation advances every step tensor it is handed by one."""
        self.fused = hasattr(torch, "_fused_adam_") and params[0].device.type in ("cpu", "cuda")
        """Use ``torch._fused_adam_`` (else the reference foreach implementation)."""
        # one view per (tensor, run); these tensors are never reallocated, so their views are made once
        self._param_views = self._views(params)
        self._avg_views = self._views(self.exp_avg)
        self._avg_sq_views = self._views(self.exp_avg_sq)
        self._step_views = self._views(list(self._step_table))

    @staticmethod
    def _views(tensors: list[torch.Tensor]) -> list[torch.Tensor]:
        return [view for t in tensors for view in t.unbind(0)]

    def zero_grad(self) -> None:
        for p in self.params:
            p.grad = None

    @torch.no_grad()
    def step(self) -> None:
        grads = [p.grad for p in self.params]
        if any(grad is None for grad in grads):
            raise RuntimeError("StackedAdam.step() before backward(): a parameter has no gradient")
        grads_v = self._views(cast(list[torch.Tensor], grads))
        params, avg, avg_sq, steps = self._param_views, self._avg_views, self._avg_sq_views, self._step_views
        if self.fused:
            self._step_table += 1  # the fused kernel reads the step counts; it does not advance them
            torch._fused_adam_(
                params,
                grads_v,
                avg,
                avg_sq,
                [],
                steps,
                lr=self.lr,
                beta1=self.betas[0],
                beta2=self.betas[1],
                weight_decay=0.0,
                eps=self.eps,
                amsgrad=False,
                maximize=False,
            )
        else:
            _reference_adam(  # the reference foreach implementation, same views; it advances the steps
                params,
                grads_v,
                avg,
                avg_sq,
                [],
                steps,
                foreach=True,
                capturable=False,
                differentiable=False,
                fused=None,
                grad_scale=None,
                found_inf=None,
                has_complex=False,
                amsgrad=False,
                beta1=self.betas[0],
                beta2=self.betas[1],
                lr=self.lr,
                weight_decay=0.0,
                eps=self.eps,
                maximize=False,
            )

    @property
    def step_count(self) -> torch.Tensor:
        """``(runs,)`` Adam steps taken by every run."""
        return self._step_table[0]

    def state_dict(self) -> dict[str, Any]:
        return {
            "exp_avg": [t.clone() for t in self.exp_avg],
            "exp_avg_sq": [t.clone() for t in self.exp_avg_sq],
            "steps": self.step_count.clone(),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        for mine, saved in zip(self.exp_avg + self.exp_avg_sq, state["exp_avg"] + state["exp_avg_sq"], strict=True):
            mine.copy_(saved)
        self._step_table.copy_(state["steps"].expand_as(self._step_table))
