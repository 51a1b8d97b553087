"""Env-steps/s of one env's share of the paper profile (25 runs: β ∈ {0.75, 0.5, 0.25} × 5 seeds
and 10 runs at β = 1) trained as the runner trains it, in one process on one thread.

For side-by-side comparisons of two trees (run it alternately, prints one number per call):

    python benchmarks/paper_ensemble_rate.py --steps 500                   # this checkout
    python benchmarks/paper_ensemble_rate.py --steps 500 --tree /tmp/old   # another tree, e.g.
                                                                           # `git archive REV | tar -x -C /tmp/old`
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=500, help="env steps per run (all with updates)")
    parser.add_argument("--tree", help="import the suite from this source tree instead of the installed one")
    args = parser.parse_args()
    if args.tree:  # bypass the editable install's finder so that the other tree's modules load
        sys.meta_path[:] = [finder for finder in sys.meta_path if "ditable" not in type(finder).__name__]
        sys.path.insert(0, args.tree)
    import torch

    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training import RunnerOptions, train_runs

    torch.set_num_threads(1)
    betas = [0.75, 0.5, 0.25] * 5 + [1.0] * 10
    specs = [
        RunSpec.of(
            env="coexistence_v0",
            method="empathic_dqn",
            seed=i,
            steps=args.steps,
            eval_interval=10 * args.steps,
            eval_episodes=1,
            settings={"learning_starts": 32, "replay_capacity": 100_000, "selfishness": beta},
        )
        for i, beta in enumerate(betas)
    ]
    out = tempfile.mkdtemp(prefix="ez-paper-rate-")
    try:
        start = time.perf_counter()
        train_runs(specs, out, RunnerOptions(progress=False, max_parallel_runs=len(specs), threads=1, checkpoint_interval=0))
        print(f"{len(specs) * args.steps / (time.perf_counter() - start):.0f} env-steps/s")
    finally:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
