"""StackedAdam: each run's slice gets exactly ``torch.optim.Adam``'s update, on the fused path
and on the reference (non-fused) path another device or build would take."""

from __future__ import annotations

import pytest
import torch

from agents.stacked_adam import StackedAdam

RUNS, STEPS, LR = 3, 20, 1e-2
SHAPES = [(RUNS, 6, 4), (RUNS, 1, 4), (RUNS, 4, 5)]


def _grads(step: int) -> list[torch.Tensor]:
    generator = torch.Generator().manual_seed(1000 + step)
    return [torch.randn(shape, generator=generator) for shape in SHAPES]


def _stacked_run(fused: bool) -> tuple[list[torch.Tensor], StackedAdam]:
    generator = torch.Generator().manual_seed(0)
    params = [torch.randn(shape, generator=generator).requires_grad_() for shape in SHAPES]
    optimizer = StackedAdam(params, lr=LR)
    if not fused:
        optimizer.fused = False
    elif not optimizer.fused:
        pytest.skip("this torch build has no fused Adam kernel")
    for step in range(STEPS):
        for p, g in zip(params, _grads(step), strict=True):
            p.grad = g.clone()
        optimizer.step()
    return params, optimizer


def _reference_run(run: int, **adam_options) -> list[torch.Tensor]:
    generator = torch.Generator().manual_seed(0)
    params = [torch.randn(shape, generator=generator)[run].clone().requires_grad_() for shape in SHAPES]
    optimizer = torch.optim.Adam(params, lr=LR, **adam_options)
    for step in range(STEPS):
        for p, g in zip(params, _grads(step), strict=True):
            p.grad = g[run].clone()
        optimizer.step()
    return params


@pytest.mark.parametrize("fused", [True, False], ids=["fused", "reference"])
def test_every_run_counts_one_adam_step_per_update(fused: bool) -> None:
    _, optimizer = _stacked_run(fused)
    assert optimizer.step_count.tolist() == [float(STEPS)] * RUNS
    assert all(float(view) == STEPS for view in optimizer._step_views)


@pytest.mark.parametrize("fused", [True, False], ids=["fused", "reference"])
def test_each_run_matches_torch_adam(fused: bool) -> None:
    params, _ = _stacked_run(fused)
    exact = {"fused": True} if fused else {"foreach": True}
    for run in range(RUNS):
        reference = _reference_run(run, **exact)
        for mine, theirs in zip(params, reference, strict=True):
            torch.testing.assert_close(mine[run].detach(), theirs.detach(), rtol=0, atol=0)
        default = _reference_run(run)  # torch's default implementation on this device
        for mine, theirs in zip(params, default, strict=True):
            torch.testing.assert_close(mine[run].detach(), theirs.detach(), rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("fused", [True, False], ids=["fused", "reference"])
def test_state_round_trip_continues_exactly(fused: bool) -> None:
    params, optimizer = _stacked_run(fused)
    state = optimizer.state_dict()
    copies = [p.detach().clone().requires_grad_() for p in params]
    other = StackedAdam(copies, lr=LR)
    other.fused = optimizer.fused
    other.load_state_dict(state)
    assert other.step_count.tolist() == [float(STEPS)] * RUNS
    for opt, ps in ((optimizer, params), (other, copies)):
        for p, g in zip(ps, _grads(STEPS), strict=True):
            p.grad = g.clone()
        opt.step()
    for a, b in zip(params, copies, strict=True):
        assert torch.equal(a, b)
