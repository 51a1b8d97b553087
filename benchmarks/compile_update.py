"""``torch.compile`` of the learner's whole update, against the update as it is: is a run's
training still bit for bit the same, and how much faster is an update? (A lever of issue 10,
tried and dropped: see BENCHMARKS.md.)

    python benchmarks/compile_update.py --runs 1     # one run at β = 0.5
    python benchmarks/compile_update.py --runs 25    # one env's share of the paper profile

Needs a C++ compiler (torch's inductor generates and builds C++ for the CPU).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch
from filled_learners import (  # benchmarks/ is on sys.path
    PAPER_BETAS,
    cpu_ms,
    filled_learner,
)
from machine import describe_machine


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1, help="runs in the ensemble (K)")
    parser.add_argument("--updates", type=int, default=200, help="updates per timing")
    parser.add_argument("--repeats", type=int, default=3, help="alternations of the two")
    args = parser.parse_args()
    torch.set_num_threads(1)
    print("\n".join(describe_machine(f"torch {torch.__version__} (1 thread)")))
    betas = PAPER_BETAS[: args.runs] if args.runs > 1 else [0.5]  # (one run: β = 0.5, both networks)
    eager, compiled = filled_learner(betas=betas), filled_learner(betas=betas)
    # left to eager PyTorch, as dynamo cannot trace them: drawing the replay indices (numpy,
    # 64-bit keys) and the fused Adam step (one kernel already)
    compiled.sample_indices = torch.compiler.disable(compiled.sample_indices)
    compiled.optimizer.step = torch.compiler.disable(compiled.optimizer.step)
    compiled_update = torch.compile(compiled.update)
    start = time.perf_counter()
    for _ in range(60):
        eager.update()
        compiled_update()
    print(f"compiling and 60 updates of each: {time.perf_counter() - start:.1f} s")
    same = all(torch.equal(a, b) for a, b in zip(eager.online, compiled.online, strict=True))
    diff = max(float((a - b).detach().abs().max()) for a, b in zip(eager.online, compiled.online, strict=True))
    print(f"parameters after 60 updates: {'bit for bit equal' if same else 'differ'} (largest difference {diff:.3g})")
    timings = []
    for _ in range(args.repeats):
        timings.append((cpu_ms(eager.update, args.updates) * 1e3, cpu_ms(compiled_update, args.updates) * 1e3))
        print(f"K = {args.runs}: as it is {timings[-1][0]:.0f} µs, compiled {timings[-1][1]:.0f} µs CPU per update")
    ratio = np.median([a / b for a, b in timings])
    print(f"median speed-up of the compiled update: {ratio:.2f}×")
    print(f"command: python benchmarks/compile_update.py --runs {args.runs} --updates {args.updates} --repeats {args.repeats}")


if __name__ == "__main__":
    main()
