"""Where one gradient step of the paper's ensemble goes, and why its matmuls run at half speed.

The ensemble is one env's share of the paper profile (25 runs: β ∈ {0.75, 0.5, 0.25} × 5 seeds,
10 at β = 1), one process, one thread, replay filled with random transitions. Prints:

1. CPU ms per update of the learner as it is, alternated with a variant that computes the same
   numbers by a hand-written backward pass (no autograd; ``Q(s')`` folded into the forward pass
   of ``Q`` on ``[s; s']``, each weight read once), and whether the two stay bit-identical;
2. the update's aten calls by self time and input shape (``torch.profiler``);
3. the update's matmul shapes timed alone, with warm caches and after streaming 32 MB (as the rest
   of an update does between two calls), against the machine's float32 matmul peak.

    python benchmarks/update_profile.py            # figures in BENCHMARKS.md
"""

from __future__ import annotations

import argparse

import numpy as np
import torch
from filled_learners import cpu_ms, filled_learner  # benchmarks/filled_learners.py

from agents.empathic_dqn import EmpathicDQN, double_dqn_target
from agents.stacked_mlp import StackedMLP


def _forward_saving(params: list[torch.Tensor], x: torch.Tensor) -> tuple[torch.Tensor, list[torch.Tensor]]:
    inputs, last = [x], len(params) // 2 - 1
    for layer in range(last + 1):
        x = torch.baddbmm(params[2 * layer + 1], x, params[2 * layer])
        if layer < last:
            x = torch.relu_(x)
            inputs.append(x)
    return x, inputs


def _backward(
    params: list[torch.Tensor],
    inputs: list[torch.Tensor],
    grad: torch.Tensor,
    rows: int,
    grads: list[torch.Tensor],
    stacks: slice,
) -> None:
    for layer in range(len(params) // 2 - 1, -1, -1):
        x = inputs[layer][:, :rows]
        torch.bmm(x.transpose(1, 2), grad, out=grads[2 * layer][stacks])
        torch.sum(grad, dim=1, keepdim=True, out=grads[2 * layer + 1][stacks])
        if layer:
            grad = torch.ops.aten.threshold_backward(torch.bmm(grad, params[2 * layer].transpose(1, 2)), x, 0)


class ManualBackward(EmpathicDQN):
    """The same update without autograd (a lever tried: bit-identical, not faster)."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._grads = [torch.zeros_like(p) for p in self.online]
        for p in self.online:
            p.requires_grad_(False)

    def _loss_grad(self, values: torch.Tensor, action: torch.Tensor, target: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        diff = values.gather(2, action.unsqueeze(2)).squeeze(2) - target
        b = diff.shape[1]
        grad = torch.zeros_like(values).scatter_(2, action.unsqueeze(2), (diff * (2.0 / b)).unsqueeze(2))
        return (diff**2).mean(dim=1).sum(), grad

    def update(self) -> float:
        k, cfg, emp, b = self.num_runs, self.config, self._emp.size, self.config.batch_size
        batch = self.sample_batch()
        obs, action = batch["obs"], batch["action"]
        q_params, e_params = [p[:k] for p in self.online], [p[k:] for p in self.online]
        out_q, inputs_q = _forward_saving(q_params, torch.cat([obs, batch["next_obs"]], dim=1))
        q_next = out_q[:, b:]
        if emp:
            rows = None if emp == k else self._emp_rows
            out_e, inputs_e = _forward_saving(e_params, obs if rows is None else obs.index_select(0, rows))
            target_both = StackedMLP.forward(self.target, torch.cat([batch["next_obs"], batch["other_swapped"]], dim=1))
            y, y_emp = self.targets(batch, q_next, target_both[:, :b], target_both[:, b:])
            if rows is not None:
                y_emp = y_emp.index_select(0, rows)
        else:
            y = double_dqn_target(
                batch["reward"], batch["terminated"], q_next, StackedMLP.forward(self.target, batch["next_obs"]), cfg.gamma
            )
        loss, grad = self._loss_grad(out_q[:, :b], action, y)
        _backward(q_params, inputs_q, grad, b, self._grads, slice(0, k))
        if emp:
            loss_e, grad = self._loss_grad(out_e, action if rows is None else action.index_select(0, rows), y_emp)
            loss = loss + loss_e
            _backward(e_params, inputs_e, grad, b, self._grads, slice(k, k + emp))
        for p, g in zip(self.online, self._grads, strict=True):
            p.grad = g
        self.optimizer.step()
        self.grad_steps += 1
        if self.grad_steps % cfg.target_update_interval == 0:
            self.sync_target()
        self.last_loss = float(loss) / (k + emp)
        return self.last_loss


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--updates", type=int, default=50, help="updates per timing (10 alternations)")
    args = parser.parse_args()
    torch.set_num_threads(1)
    print("command: python benchmarks/update_profile.py" + (f" --updates {args.updates}" if args.updates != 50 else ""))

    ours, manual = filled_learner(EmpathicDQN), filled_learner(ManualBackward)
    for _ in range(120):
        ours.update(), manual.update()
    same = all(torch.equal(a.detach(), b) for a, b in zip(ours.online, manual.online, strict=True))
    times: dict[str, list[float]] = {"autograd (as trained)": [], "hand-written backward": []}
    for _ in range(10):
        times["autograd (as trained)"].append(cpu_ms(ours.update, args.updates))
        times["hand-written backward"].append(cpu_ms(manual.update, args.updates))
    print(f"\n1. CPU ms per update (K = 25, paper mix; median of 10 alternations); bit-identical after 120 updates: {same}")
    for name, values in times.items():
        print(f"   {name:24s} {np.median(values):6.2f}  (min {min(values):.2f})")

    from torch.profiler import ProfilerActivity, profile

    with profile(activities=[ProfilerActivity.CPU], record_shapes=True) as prof:
        for _ in range(100):
            ours.update()
    print("\n2. aten calls of 100 updates, by self time and shape")
    print(
        prof.key_averages(group_by_input_shape=True).table(
            sort_by="self_cpu_time_total", row_limit=14, max_name_column_width=22, max_shapes_column_width=70
        )
    )

    flush = torch.zeros(8_000_000)
    shapes = {
        "forward W2 (40×32×128 @ 128×128)": (torch.randn(40, 32, 128), torch.randn(40, 128, 128)),
        "weight grad W2 (40×128×32 @ 32×128)": (torch.randn(40, 32, 128).transpose(1, 2), torch.randn(40, 32, 128)),
        "target W2 (25×64×128 @ 128×128)": (torch.randn(25, 64, 128), torch.randn(25, 128, 128)),
    }
    base = cpu_ms(lambda: flush.add_(1.0), 50)
    print("\n3. the update's largest matmuls alone (µs per call, GFLOP/s)")
    for name, (a, b) in shapes.items():
        flops = 2 * a.shape[0] * a.shape[1] * a.shape[2] * b.shape[2]
        warm = cpu_ms(lambda a=a, b=b: torch.bmm(a, b), 200) * 1e3
        cold = (cpu_ms(lambda a=a, b=b: (flush.add_(1.0), torch.bmm(a, b)), 50) - base) * 1e3
        print(
            f"   {name:38s} warm {warm:6.0f} ({flops / warm / 1e3:5.1f})   after 32 MB streamed {cold:6.0f} "
            f"({flops / cold / 1e3:5.1f})"
        )


if __name__ == "__main__":
    main()
