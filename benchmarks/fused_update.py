"""The compiled update (``update_kernel="numba"``, :mod:`agents.fused_update`) against the PyTorch
update: CPU µs per update, the two alternated in one process, at K = 1 (β = 0.5 and β = 1) and at
one env's share of the paper profile (K = 25: 15 runs with ``Q_emp``, 10 DQN-type), paper sizes
(Coexistence's 25 inputs, hidden 128, 5 actions, batch 32), one torch thread.

    python benchmarks/fused_update.py [--repeats 5] [--updates 300]
"""

from __future__ import annotations

import argparse

import numpy as np
import torch
from filled_learners import PAPER_BETAS, cpu_ms, filled_learner  # benchmarks/ is on sys.path
from machine import describe_machine

from agents import fused_update
from agents.empathic_dqn import EmpathicDQN


class NumbaEmpathicDQN(EmpathicDQN):
    """The learner with the compiled update."""

    update_kernel = "numba"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="alternations of the two updates")
    parser.add_argument("--updates", type=int, default=300, help="updates per timing at K = 1 (a tenth at K = 25)")
    args = parser.parse_args()
    torch.set_num_threads(1)
    print("\n".join(describe_machine(f"torch {torch.__version__} (1 thread)")))
    if not fused_update.numba_available():
        raise SystemExit(f"numba kernels unavailable: {fused_update.numba_unavailable_reason()}")
    print(f"matrix products: {'MKL sgemm (torch’s)' if fused_update.BLAS else 'numba loops'}")
    setups = [("K = 1, β = 0.5", [0.5]), ("K = 1, β = 1", [1.0]), ("K = 25, the paper's mix", PAPER_BETAS)]
    rows = []
    for name, betas in setups:
        eager, fused = filled_learner(betas=betas), filled_learner(cls=NumbaEmpathicDQN, betas=betas)
        assert fused.update_kernel == "numba"
        calls = args.updates if len(betas) == 1 else max(args.updates // 10, 10)
        for _ in range(20):  # (warm both)
            eager.update()
            fused.update()
        pairs = []
        for _ in range(args.repeats):
            pairs.append((cpu_ms(eager.update, calls) * 1e3, cpu_ms(fused.update, calls) * 1e3))
        a, b = (np.array(x) for x in zip(*pairs))
        ratios = a / b
        rows.append((name, np.median(a), np.median(b), np.median(ratios), ratios.min(), ratios.max()))
        print(f"{name}: torch " + " ".join(f"{x:.0f}" for x in a) + " µs; numba " + " ".join(f"{x:.0f}" for x in b) + " µs")
    print("\n| setup | torch µs/update | numba µs/update | speed-up (median, min–max) |")
    print("|---|---:|---:|---:|")
    for name, a, b, r, lo, hi in rows:
        print(f"| {name} | {a:,.0f} | {b:,.0f} | {r:.2f}× ({lo:.2f}–{hi:.2f}) |")
    print(f"\ncommand: python benchmarks/fused_update.py --repeats {args.repeats} --updates {args.updates}")


if __name__ == "__main__":
    main()
