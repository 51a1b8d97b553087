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

from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from machine import describe_machine  # benchmarks/machine.py (this directory is on sys.path)

PAPER_BETAS = [0.75, 0.5, 0.25] * 5 + [1.0] * 10


def learner(runs: int) -> EmpathicDQN:
    """``runs`` learners of the paper's mix (β = 0.5 alone), replay memories filled with 300
    random transitions (the same for every call)."""
    betas = PAPER_BETAS[:runs] if runs > 1 else [0.5]
    settings = [EmpathicDQNSettings(selfishness=b, learning_starts=10**9, replay_capacity=5_000) for b in betas]
    built = EmpathicDQN(settings, list(range(runs)), 25, 5, "cpu")
    rng = np.random.default_rng(0)
    for _ in range(300):
        o = rng.integers(-1, 11, (runs, 1, 3, 25)).astype(np.float32)
        built.replay.add(o[:, :, 0], o[:, :, 1], o[:, :, 2], rng.integers(0, 5, (runs, 1)), rng.normal(size=(runs, 1)),
                         rng.random((runs, 1)) < 0.1, rng.random((runs, 1)) < 0.9)
    return built


def cpu_us_per_update(update, count: int) -> float:
    start = time.process_time()
    for _ in range(count):
        update()
    return (time.process_time() - start) / count * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1, help="runs in the ensemble (K)")
    parser.add_argument("--updates", type=int, default=200, help="updates per timing")
    parser.add_argument("--repeats", type=int, default=3, help="alternations of the two")
    args = parser.parse_args()
    torch.set_num_threads(1)
    print("\n".join(describe_machine(f"torch {torch.__version__} (1 thread)")))
    eager, compiled = learner(args.runs), learner(args.runs)
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
    same = all(torch.equal(a, b) for a, b in zip(eager.online, compiled.online))
    diff = max(float((a - b).detach().abs().max()) for a, b in zip(eager.online, compiled.online))
    print(f"parameters after 60 updates: {'bit for bit equal' if same else 'differ'} (largest difference {diff:.3g})")
    timings = []
    for _ in range(args.repeats):
        timings.append((cpu_us_per_update(eager.update, args.updates), cpu_us_per_update(compiled_update, args.updates)))
        print(f"K = {args.runs}: as it is {timings[-1][0]:.0f} µs, compiled {timings[-1][1]:.0f} µs CPU per update")
    ratio = np.median([a / b for a, b in timings])
    print(f"median speed-up of the compiled update: {ratio:.2f}×")
    print(f"command: python benchmarks/compile_update.py --runs {args.runs} --updates {args.updates} --repeats {args.repeats}")


if __name__ == "__main__":
    main()
