"""What live tracking costs: training time with and without ``--log tensorboard,csv``.

The same small sweep (Empathic DQN at β = 0.5, so ``Q`` and ``Q_emp`` both train and both are
logged, ``--seeds`` runs in one lockstep ensemble, the paper's MLP, batch 32, one gradient step
per env step after ``--warmup`` transitions, short episodes so that episode ends are logged
often) is trained by ``train_runs`` into a fresh directory, alternately without logging (A) and
with TensorBoard and CSV logging (B), ``--repeats`` times each, after one untimed run of each (so
neither pays the imports). Each training is timed on the wall clock and in CPU seconds of this
process (``time.process_time``, which counts TensorBoard's writer thread too); the medians of A
and B and of the per-pair ratios B / A are printed. On a busy machine a few percent are within
the noise of such pairs, so the time spent inside the tracker's calls in B (opening the loggers,
every step's episode check, the evaluations, the interval figures with Empathic DQN's
``tracked_scalars``, flushing and closing; CPU seconds of this thread) is printed too, as a
share of B's time, and the CPU seconds of the other threads (TensorBoard's writer): together they
are what logging adds, and they do not depend on the load. Then the one-off cost of importing
``torch.utils.tensorboard``, the command and the machine.

    python benchmarks/logging_cost.py [--steps 3000] [--warmup 500] [--seeds 2] [--repeats 5] [--max-cycles 100]
"""

from __future__ import annotations

import argparse
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from typing import Any

import torch
from machine import describe_machine  # benchmarks/machine.py (this directory is on sys.path)

from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.tracking import EnsembleTracker

BACKENDS = ("tensorboard", "csv")
INSIDE = [0.0]
"""CPU seconds of this thread spent inside the tracker's methods (:func:`count_tracker_time`)."""


def count_tracker_time() -> None:
    """Make every call of an :class:`EnsembleTracker` method add its thread CPU time to :data:`INSIDE`."""

    def counted(method: Callable[..., Any]) -> Callable[..., Any]:
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            started = time.thread_time()
            try:
                return method(*args, **kwargs)
            finally:
                INSIDE[0] += time.thread_time() - started

        return wrapper

    for name in ("start", "after_step", "evaluation", "interval", "finish", "close"):
        setattr(EnsembleTracker, name, counted(getattr(EnsembleTracker, name)))


def specs(args: argparse.Namespace) -> list[RunSpec]:
    settings = {"selfishness": 0.5, "learning_starts": args.warmup, "replay_capacity": 20_000}
    return [
        RunSpec.of(
            env="coexistence_v0",
            method="empathic_dqn",
            settings=settings,
            seed=seed,
            steps=args.steps,
            eval_interval=args.steps // 2,
            eval_episodes=2,
            env_kwargs={"max_cycles": args.max_cycles},
        )
        for seed in range(args.seeds)
    ]


def timed(args: argparse.Namespace, log: tuple[str, ...]) -> tuple[float, float, float]:
    """Wall-clock and CPU seconds of one training of the sweep into a fresh directory, and the CPU
    seconds of the threads other than this one."""
    options = RunnerOptions(progress=False, checkpoint_interval=0, log=log)
    with tempfile.TemporaryDirectory() as out:
        wall, cpu, own = time.perf_counter(), time.process_time(), time.thread_time()
        train_runs(specs(args), out, options)
        cpu, own = time.process_time() - cpu, time.thread_time() - own
        return time.perf_counter() - wall, cpu, cpu - own


def import_seconds() -> float:
    """Seconds a fresh Python takes to import ``torch.utils.tensorboard`` beyond importing torch."""
    code = "import time, torch; t = time.perf_counter(); import torch.utils.tensorboard; print(time.perf_counter() - t)"
    return float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--warmup", type=int, default=500)
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--max-cycles", type=int, default=100)
    args = parser.parse_args()
    torch.set_num_threads(1)
    timed(args, ())
    timed(args, BACKENDS)  # (untimed: imports, first allocations)
    count_tracker_time()
    INSIDE[0] = 0.0
    plain: list[tuple[float, float, float]] = []
    logged: list[tuple[float, float, float]] = []
    for repeat in range(args.repeats):
        order = [((), plain), (BACKENDS, logged)]
        for log, into in order if repeat % 2 == 0 else order[::-1]:  # (A B, B A, …: drift hits both alike)
            into.append(timed(args, log))
    print(f"command: python benchmarks/{__file__.rsplit('/', 1)[-1]} {shlex.join(sys.argv[1:])}")
    for line in describe_machine(f"torch {torch.__version__}"):
        print(line)
    print(
        f"sweep: {args.seeds} run(s) of Empathic DQN (β = 0.5) in one ensemble, {args.steps:,} env steps each, "
        f"{args.warmup:,} warm-up, episodes of {args.max_cycles} steps; {args.repeats} A/B pairs"
    )
    print("| | wall s, median | wall s, fastest | CPU s, median | CPU s, fastest |")
    print("|---|---:|---:|---:|---:|")
    for name, runs in (("A: no logging", plain), (f"B: --log {','.join(BACKENDS)}", logged)):
        walls, cpus = [run[0] for run in runs], [run[1] for run in runs]
        print(f"| {name} | {statistics.median(walls):.2f} | {min(walls):.2f} | {statistics.median(cpus):.2f} | {min(cpus):.2f} |")
    wall_ratio = statistics.median(b[0] / a[0] for a, b in zip(plain, logged, strict=True))
    cpu_ratio = statistics.median(b[1] / a[1] for a, b in zip(plain, logged, strict=True))
    fastest = [min(x[i] for x in logged) / min(x[i] for x in plain) for i in (0, 1)]
    print(f"| B / A (median of pairs; fastest) | {wall_ratio:.3f} | {fastest[0]:.3f} | {cpu_ratio:.3f} | {fastest[1]:.3f} |")
    print("pairs B / A, CPU: " + ", ".join(f"{b[1] / a[1]:.3f}" for a, b in zip(plain, logged, strict=True)))
    total = sum(run[1] for run in logged)
    threads = sum(run[2] for run in logged) - sum(run[2] for run in plain)  # (B's other threads, less A's)
    print(f"inside the tracker's calls: {INSIDE[0]:.3f} CPU s of B's {total:.1f} CPU s = {INSIDE[0] / total:.2%}")
    print(f"other threads (TensorBoard's writer), beyond A's: {threads:.3f} CPU s = {threads / total:.2%}")
    print(f"what logging adds: {(INSIDE[0] + threads) / total:.2%} of B's CPU time")
    print(f"one-off: importing torch.utils.tensorboard takes {import_seconds():.2f} s per process")


if __name__ == "__main__":
    main()
