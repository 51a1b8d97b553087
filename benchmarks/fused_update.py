"""The compiled update (``update_kernel="numba"``, :mod:`agents.fused_update`) against the PyTorch
update: CPU µs per update, alternated in one process, at K = 1 (β = 0.5 and β = 1) and at one env's
share of the paper profile (K = 25: 15 runs with ``Q_emp``, 10 DQN-type), paper sizes
(Coexistence's 25 inputs, hidden 128, 5 actions, batch 32), one torch thread. Three updates:

* ``torch``: the PyTorch update (the default);
* ``numba, split``: the compiled passes with the batch drawn and decoded and the targets computed
  in torch in between (the compiled update as it was first built: :class:`SplitNumbaEmpathicDQN`);
* ``numba, one call``: the whole update in one compiled call (indices, gather and decode, next
  values, targets, forward, backward and Adam), what ``update_kernel="numba"`` runs now.

With ``--train``, also one whole training step at K = 1, β = 0.5 through
``empathy_zoo.training.train_runs`` (acting, the env, the replay write and the update) with the
torch and the one-call update, alternated, in env-steps per CPU second (and SB3 DQN's, as
``benchmarks/train_speed.py`` measures it, with ``--sb3``).

    python benchmarks/fused_update.py [--repeats 5] [--updates 300] [--train] [--sb3]
"""

from __future__ import annotations

import argparse
import os
import statistics

import numpy as np
import torch
from filled_learners import PAPER_BETAS, cpu_ms, filled_learner  # benchmarks/ is on sys.path
from machine import describe_machine
from train_speed import STOPWATCH, empathic_dqn_rates, sb3_dqn_rates

from agents import fused_update
from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.fused_update import NumbaUpdate
from agents.settings import EmpathicDQNSettings


class TorchEmpathicDQN(EmpathicDQN):
    """The learner with the PyTorch update."""

    update_kernel = "torch"


class NumbaEmpathicDQN(EmpathicDQN):
    """The learner with the compiled update."""

    update_kernel = "numba"


class SplitNumbaEmpathicDQN(NumbaEmpathicDQN):
    """The compiled update as first built: the batch from :meth:`sample_batch` (torch), the forward
    passes of the next states in one compiled call, :meth:`targets` in torch, then the compiled
    train step."""

    def _numba_step(self, fused: NumbaUpdate) -> float:
        k, emp = self.num_runs, self._emp.size
        batch = self.sample_batch()
        if emp:
            swapped = batch["others_swapped" if self.aggregated else "other_swapped"]
            q_next, target_next, target_swapped = fused.next_values(batch["next_obs"], swapped)
            assert target_swapped is not None
            with torch.no_grad():
                y, y_emp = self.targets(batch, q_next, target_next, target_swapped)
                targets = torch.cat([y, y_emp if emp == k else y_emp.index_select(0, self._emp_rows)])
        else:
            q_next, target_next, _ = fused.next_values(batch["next_obs"], None)
            targets = fused.dqn_targets(batch["reward"], batch["terminated"], q_next, target_next, self.config.gamma)
        return fused.train(batch["obs"], batch["action"], targets)


def update_table(repeats: int, updates: int) -> None:
    """µs per update of the three updates, alternated ``repeats`` times, per setup."""
    setups = [("K = 1, β = 0.5", [0.5]), ("K = 1, β = 1", [1.0]), ("K = 25, the paper's mix", PAPER_BETAS)]
    kinds = [("torch", TorchEmpathicDQN), ("numba, split", SplitNumbaEmpathicDQN), ("numba, one call", NumbaEmpathicDQN)]
    rows = []
    for name, betas in setups:
        learners = [filled_learner(cls=cls, betas=betas) for _, cls in kinds]
        assert [learner.update_kernel for learner in learners] == ["torch", "numba", "numba"]
        calls = updates if len(betas) == 1 else max(updates // 10, 10)
        for _ in range(20):  # (warm all)
            for learner in learners:
                learner.update()
        times: list[list[float]] = [[] for _ in kinds]
        for _ in range(repeats):
            for row, learner in zip(times, learners, strict=True):
                row.append(cpu_ms(learner.update, calls) * 1e3)
        a, split, whole = (np.array(x) for x in times)
        rows.append(
            (name, np.median(a), np.median(split), np.median(whole), np.median(a / whole), (a / whole).min(), (a / whole).max())
        )
        print(
            f"{name}: "
            + "; ".join(
                f"{kind} " + " ".join(f"{x:.0f}" for x in row) + " µs" for (kind, _), row in zip(kinds, times, strict=True)
            )
        )
    print(
        "\n| setup | torch µs/update | numba, split µs/update | numba, one call µs/update | one call vs torch (median, min–max) |"
    )
    print("|---|---:|---:|---:|---:|")
    for name, a, split, whole, r, lo, hi in rows:
        print(f"| {name} | {a:,.0f} | {split:,.0f} | {whole:,.0f} | {r:.2f}× ({lo:.2f}–{hi:.2f}) |")


class _Timed:
    """Reports a learner's env-step count to train_speed's stopwatch after every step."""

    def observe(self, batch) -> None:  # type: ignore[no-untyped-def]
        super().observe(batch)  # type: ignore[misc]
        STOPWATCH.tick(self.env_steps)  # type: ignore[attr-defined]


class TimedEmpathicDQN(_Timed, TorchEmpathicDQN):
    """The PyTorch update, timed."""


class TimedNumbaEmpathicDQN(_Timed, NumbaEmpathicDQN):
    """The one-call compiled update, timed."""


TIMED_TORCH = Method(name="timed_torch", learner=TimedEmpathicDQN, settings=EmpathicDQNSettings, description="timed")
TIMED_NUMBA = Method(name="timed_numba", learner=TimedNumbaEmpathicDQN, settings=EmpathicDQNSettings, description="timed")


def train_rate(kind: str, warmup: int, settle: int, steps: int) -> float:
    """Env steps per CPU second of one run (K = 1, β = 0.5) through ``train_runs``, as
    ``benchmarks/train_speed.py`` times Empathic DQN, with the ``kind`` update."""
    return empathic_dqn_rates(warmup, settle, steps, method=f"{__name__}:TIMED_{kind.upper()}")[1]


def train_table(repeats: int, steps: int, sb3: bool) -> None:
    """Env-steps per CPU second of one run, torch and one-call numba (and SB3), alternated."""
    rates: dict[str, list[float]] = {"torch": [], "numba": []}
    if sb3:
        rates["sb3"] = []
    for repeat in range(repeats):
        for kind in rates:
            rate = sb3_dqn_rates(1000, 200, steps)[1] if kind == "sb3" else train_rate(kind, 1000, 200, steps)
            rates[kind].append(rate)
        print(
            f"repeat {repeat + 1}: " + "; ".join(f"{kind} {r[-1]:.0f} env-steps/CPU s" for kind, r in rates.items()), flush=True
        )
    medians = {kind: statistics.median(r) for kind, r in rates.items()}
    print("\n| one run, K = 1, β = 0.5, through train_runs | env-steps per CPU s (median) | µs per env step |")
    print("|---|---:|---:|")
    for kind, rate in medians.items():
        print(f"| {kind} | {rate:,.0f} | {1e6 / rate:,.0f} |")
    print(
        f"numba vs torch: {medians['numba'] / medians['torch']:.2f}×"
        + (f"; numba vs SB3: {medians['numba'] / medians['sb3']:.2f}×" if sb3 else "")
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="alternations of the updates")
    parser.add_argument("--updates", type=int, default=300, help="updates per timing at K = 1 (a tenth at K = 25)")
    parser.add_argument("--train", action="store_true", help="also time one whole training step at K = 1")
    parser.add_argument("--train-steps", type=int, default=2000, help="timed env steps of each training run")
    parser.add_argument("--sb3", action="store_true", help="with --train, also SB3 DQN (train_speed.py's measurement)")
    args = parser.parse_args()
    torch.set_num_threads(1)
    print("\n".join(describe_machine(f"torch {torch.__version__} (1 thread)")))
    if not fused_update.numba_available():
        raise SystemExit(f"numba kernels unavailable: {fused_update.numba_unavailable_reason()}")
    print(f"matrix products: {'MKL sgemm (torch’s)' if fused_update.BLAS else 'numba loops'}")
    print(f"load average before: {' '.join(f'{x:.1f}' for x in os.getloadavg())}", flush=True)
    update_table(args.repeats, args.updates)
    if args.train:
        train_table(max(args.repeats // 2, 1), args.train_steps, args.sb3)
    print(f"load average after: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    flags = (" --train" if args.train else "") + (" --sb3" if args.sb3 else "")
    print(f"command: python benchmarks/fused_update.py --repeats {args.repeats} --updates {args.updates}{flags}")


if __name__ == "__main__":
    main()
