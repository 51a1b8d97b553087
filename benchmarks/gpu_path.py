"""Env-steps/s of the paper profile's Coexistence sweep as one lockstep ensemble on a device.

The ensemble is the paper's Coexistence share at ``--seeds`` seeds: Empathic DQN at
β ∈ {1, 0.75, 0.5, 0.25} (so 4 × seeds runs), the paper's network, batch and replay, trained
as the runner trains it (``train_runs``), every step a gradient step (``learning_starts`` 32).
Prints one JSON line: the device and its name, the update kernel, runs, steps per run, wall
seconds and env-steps/s (runs × steps / wall). The result files are kept with ``--out``.

    python benchmarks/gpu_path.py --device cuda --kernel torch --seeds 20 --steps 2000
    python benchmarks/gpu_path.py --device cpu --kernel numba --seeds 20 --steps 2000

On a machine without a GPU, ``--device cpu`` runs the same measurement (tests/test_gpu_path.py).
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

BETAS = (1.0, 0.75, 0.5, 0.25)
"""The paper's Coexistence selfishness values (paper.toml)."""
WARM_UP = 32
"""``learning_starts`` of every run: from the first batch on, every env step is a gradient step."""


def specs(seeds: int, steps: int) -> list[Any]:
    """The runs: every β of :data:`BETAS` at seeds ``0 … seeds − 1``, ``steps`` env steps each."""
    from empathy_zoo.experiment.model import RunSpec

    return [
        RunSpec.of(
            env="coexistence_v0",
            method="empathic_dqn",
            seed=seed,
            steps=steps,
            eval_interval=steps,
            eval_episodes=1,
            settings={"learning_starts": WARM_UP, "replay_capacity": 500_000, "selfishness": beta},
        )
        for beta in BETAS
        for seed in range(seeds)
    ]


def measure(device: str, kernel: str, seeds: int, steps: int, out: Path) -> dict[str, Any]:
    """Train the ensemble into ``out``; what :func:`main` prints."""
    import torch

    from empathy_zoo.training import RunnerOptions, train_runs

    runs = specs(seeds, steps)
    options = RunnerOptions(
        device=device,
        progress=False,
        max_parallel_runs=len(runs),
        threads=1,
        checkpoint_interval=0,
        update_kernel=kernel,
    )
    if device.startswith("cuda"):
        torch.cuda.synchronize()
    start = time.perf_counter()
    train_runs(runs, out, options)
    if device.startswith("cuda"):
        torch.cuda.synchronize()
    wall = time.perf_counter() - start
    name = torch.cuda.get_device_name(torch.device(device)) if device.startswith("cuda") else platform.processor() or "cpu"
    return {
        "device": device,
        "device_name": name,
        "kernel": kernel,
        "runs": len(runs),
        "steps_per_run": steps,
        "wall_s": round(wall, 3),
        "env_steps_per_s": round(len(runs) * steps / wall, 1),
        "torch": torch.__version__,
        "python": platform.python_version(),
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cpu", help="torch device (cpu, cuda, cuda:1)")
    parser.add_argument("--kernel", default="auto", help="update kernel: auto, numba (CPU only) or torch")
    parser.add_argument("--seeds", type=int, default=20, help="seeds per β (runs = 4 × seeds)")
    parser.add_argument("--steps", type=int, default=2_000, help="env steps per run")
    parser.add_argument("--out", help="keep the result files here (default: a temporary directory, removed)")
    args = parser.parse_args(argv)
    if args.seeds < 1 or args.steps <= WARM_UP:
        parser.error(f"--seeds must be positive and --steps above {WARM_UP}")
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="ez-gpu-path-"))
    try:
        figures = measure(args.device, args.kernel, args.seeds, args.steps, out)
    finally:
        if not args.out:
            shutil.rmtree(out, ignore_errors=True)
    print(json.dumps(figures), flush=True)
    return figures


if __name__ == "__main__":
    main(sys.argv[1:])
