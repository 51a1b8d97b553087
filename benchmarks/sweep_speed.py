"""Sweep speed: aggregate env-steps/s of K Empathic DQN runs in lockstep vs SB3 DQN.

Prints, in one run on this machine:
  (a) the measured float32 matmul peak (GFLOP/s),
  (b) aggregate env-steps/s with every gradient step, for K = 1, 8, 32, 64 runs in one process,
      and for two worker processes, with each update kernel (``--update-kernel``: torch and numba
      alternated row by row, so a busy machine slows both alike),
  (c) Stable-Baselines3 DQN env-steps/s on the same environment (same MLP, batch 32, one
      gradient step per env step), (d) the ratios, (e) achieved GFLOP/s as a fraction of the
      peak, (f) the projected wall time of the `paper` profile (50 runs × 1,000,000 steps).

    python benchmarks/sweep_speed.py [--quick] [--kernels torch,numba]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

import torch
from machine import describe_machine  # benchmarks/machine.py (this directory is on sys.path)

from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.training import RunnerOptions, train_runs

OBS, HIDDEN, ACTIONS, BATCH = 25, 128, 5, 32
PAPER_RUNS, PAPER_STEPS = 50, 1_000_000


def flops_per_run_step(empathic: bool = True) -> float:
    """Matmul FLOPs of one env step of one run: acting, the targets, and the forward and backward
    passes of Q and Q_emp (``empathic``, β < 1) or of Q alone (standard DQN, β = 1)."""
    mac_row = OBS * HIDDEN + HIDDEN * HIDDEN + HIDDEN * ACTIONS
    heads = 2 if empathic else 1
    forward_rows = 1 + BATCH + heads * BATCH + heads * BATCH  # act; Q(s'); Q̂(s'[, s_emp']); Q[, Q_emp] on s
    backward = heads * BATCH * (2 * mac_row - OBS * HIDDEN)  # weight and input grads (no input grad for layer 1)
    return 2.0 * (forward_rows * mac_row + backward)


def matmul_peak(seconds: float = 2.0) -> float:
    a, b = torch.randn(2048, 2048), torch.randn(2048, 2048)
    for _ in range(3):
        a @ b
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        a @ b
        count += 1
    return 2 * 2048**3 * count / (time.perf_counter() - start) / 1e9


def ensemble_rate(
    k: int,
    steps: int,
    workers: int = 1,
    threads: int | None = None,
    selfishness: float | list[float] = 0.5,
    kernel: str = "auto",
) -> float:
    """Aggregate env-steps/s of ``workers`` ensembles of ``k`` runs (all updates on); a list of
    ``k`` selfishness values mixes runs with and without ``Q_emp`` in one ensemble."""
    betas = selfishness if isinstance(selfishness, list) else [selfishness] * k
    specs = [
        RunSpec.of(
            env="coexistence_v0",
            method="empathic_dqn",
            seed=w * k + i,
            steps=steps,
            eval_interval=10 * steps,
            eval_episodes=1,
            settings={"learning_starts": BATCH, "replay_capacity": 100_000, "selfishness": betas[i], "epsilon_decay_steps": 1},
        )
        for w in range(workers)
        for i in range(k)
    ]
    out = Path(tempfile.mkdtemp(prefix="ez-sweep-speed-"))
    try:
        paths = train_runs(
            specs,
            out,
            RunnerOptions(
                progress=False, max_parallel_runs=k, workers=workers, threads=threads, checkpoint_interval=0, update_kernel=kernel
            ),
        )
        # each run's file records its ensemble's training time (from its first step: process start,
        # imports and the compiled kernels' loading are not counted), so Σ steps / wall time over
        # the runs is Σ over the ensembles of K·steps / their time: the rate of the ensembles
        # running side by side
        return sum(steps / _wall_time(path) for path in paths)
    finally:
        shutil.rmtree(out, ignore_errors=True)


def _wall_time(path: Path) -> float:
    """The training time a result file records (its ensemble's, from its first step)."""
    wall = read_result(path).wall_time_s
    if wall is None or wall <= 0:
        raise ValueError(f"result file {path} records no training time")
    return wall


def sb3_rate(steps: int) -> float | None:
    try:
        from stable_baselines3 import DQN

        from empathy_zoo.gym_adapter import make_single_agent_env
    except ImportError as error:
        print(f"(SB3 skipped: {error})")
        return None
    env = make_single_agent_env("coexistence_v0")
    model = DQN(
        "MlpPolicy",
        env,
        learning_starts=BATCH,
        batch_size=BATCH,
        train_freq=1,
        gradient_steps=1,
        buffer_size=100_000,
        policy_kwargs={"net_arch": [HIDDEN, HIDDEN]},
        seed=0,
        device="cpu",
    )
    model.learn(200)
    start = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    return steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps (noisier figures)")
    parser.add_argument("--kernels", default="torch,numba", help="update kernels to time, comma-separated (default: torch,numba)")
    args = parser.parse_args()
    kernels = args.kernels.split(",")
    scale = 0.3 if args.quick else 1.0
    print(f"command: python benchmarks/sweep_speed.py{' --quick' if args.quick else ''} --kernels {args.kernels}")
    print("\n".join(describe_machine(f"torch {torch.__version__} ({torch.get_num_threads()} threads)")))
    peak = matmul_peak()
    print(f"(a) float32 matmul peak (2048², {torch.get_num_threads()} threads): {peak:.1f} GFLOP/s")
    sb3 = sb3_rate(int(2000 * scale))
    per_step = flops_per_run_step()
    rows = []
    for k, steps, workers, threads in (
        (1, 3000, 1, 1),
        (8, 1200, 1, 1),
        (32, 500, 1, 1),
        (32, 500, 1, 2),
        (64, 300, 1, 2),
        (25, 800, 2, 1),
        (32, 700, 2, 1),
    ):
        for kernel in kernels:
            rate = ensemble_rate(k, max(50, int(steps * scale)), workers=workers, threads=threads, kernel=kernel)
            rows.append((k, workers, kernel, rate))
            print(
                f"(b) K={k:>3} runs × {workers} process(es), {threads} thread(s) each, {kernel:5s}: {rate:9.0f} env-steps/s",
                flush=True,
            )
    sb3_after = sb3_rate(int(2000 * scale))
    if sb3 and sb3_after:
        print(f"(c) SB3 DQN (same MLP, batch 32, 1 update/step): {sb3:.0f} env-steps/s before, {sb3_after:.0f} after")
        sb3 = (sb3 + sb3_after) / 2
    for k, workers, kernel, rate in rows:
        ratio = f"{rate / sb3:5.1f}× SB3" if sb3 else "   n/a"
        achieved = rate * per_step / 1e9
        print(f"(d,e) K={k:>3} × {workers} {kernel:5s}: {ratio}; {achieved:6.1f} GFLOP/s = {achieved / peak:5.1%} of peak")
    # the paper's ensembles: per env one ensemble of 25 runs, 15 with β < 1 (Q and Q_emp) and 10
    # DQN-type runs (Q only), one worker process per env
    paper_betas = [0.75, 0.5, 0.25] * 5 + [1.0] * 10
    mean_flops = (15 * per_step + 10 * flops_per_run_step(False)) / 25
    for kernel in kernels:
        paper_rate = ensemble_rate(25, max(50, int(700 * scale)), workers=2, threads=1, selfishness=paper_betas, kernel=kernel)
        print(
            f"(f) the paper's ensembles (K = 25: 15 with β < 1 and 10 with β = 1) × 2 processes, 1 thread each, {kernel}: "
            f"{paper_rate:.0f} env-steps/s ({paper_rate * mean_flops / 1e9 / peak:.1%} of peak); 50 runs × 1M at that rate = "
            f"{PAPER_RUNS * PAPER_STEPS / paper_rate / 60:.0f} minutes (+ greedy evaluations)"
        )
    print(
        f"FLOPs per run-step (analytic): {per_step / 1e6:.2f} MFLOP with Q_emp, "
        f"{flops_per_run_step(False) / 1e6:.2f} MFLOP standard DQN"
    )
    sys.stdout.flush()


if __name__ == "__main__":
    main()
