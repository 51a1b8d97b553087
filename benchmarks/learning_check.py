"""Does it learn? DQN vs a random robot, and Empathic DQN (β = 0.25) vs DQN, on Coexistence.

Trains DQN and Empathic DQN at β = 0.25 (same seeds, one lockstep ensemble) with a shortened
ε schedule, then compares greedy evaluation episodes (the last evaluation of each run) with a
uniformly random robot on the same environment.

    python benchmarks/learning_check.py [--steps 150000] [--seeds 3] [--out results/learning_check]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.vector import VectorEnv

SHORT_SCHEDULE = {
    "learning_starts": 5_000,
    "epsilon_decay_steps": 50_000,
    "target_update_interval": 2_000,
    "replay_capacity": 150_000,
}


def random_robot(episodes: int = 200, seed: int = 0) -> dict[str, float]:
    venv = VectorEnv("coexistence_v0", episodes, fixed={"cat_0": "random_walk"})
    venv.reset(seed=seed)
    rng = np.random.default_rng(seed)
    done = np.zeros(episodes, dtype=bool)
    survival, harms = np.zeros(episodes), np.zeros(episodes)
    while not done.all():
        step = venv.step(rng.integers(0, 5, (episodes, 1)))
        ids = step.finished["env"]
        if ids.size:
            fresh = ~done[ids]
            survival[ids[fresh]] = step.finished["survival"][fresh]
            harms[ids[fresh]] = step.finished["harms"][fresh]
            done[ids] = True
    return {"survival": float(survival.mean()), "harms": float(harms.mean())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=150_000)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--out", default="results/learning_check")
    parser.add_argument("--threads", type=int, default=None)
    args = parser.parse_args()
    print(f"command: python benchmarks/learning_check.py --steps {args.steps} --seeds {args.seeds} --out {args.out}")
    specs = [
        RunSpec.of(
            env="coexistence_v0",
            method="empathic_dqn",
            settings={**SHORT_SCHEDULE, "selfishness": beta},
            seed=seed,
            steps=args.steps,
            eval_interval=args.steps // 5,
            eval_episodes=20,
        )
        for beta in (1.0, 0.25)
        for seed in range(args.seeds)
    ]
    start = time.perf_counter()
    paths = train_runs(specs, args.out, RunnerOptions(threads=args.threads))
    print(f"trained {len(specs)} runs × {args.steps:,} steps in {time.perf_counter() - start:.0f} s")
    table: dict[float, list[tuple[float, float]]] = {}
    for spec, path in zip(specs, paths, strict=True):
        last = read_result(path).eval[-1].metrics
        table.setdefault(spec.method_settings().selfishness, []).append((np.mean(last["survival"]), np.mean(last["harms"])))
    baseline = random_robot()
    print(f"random robot:        survival {baseline['survival']:6.1f}   harms/episode {baseline['harms']:.2f}")
    for beta, rows in table.items():
        s, h = np.array(rows).T
        name = "DQN (β=1)" if beta == 1.0 else f"Empathic β={beta:g}"
        print(
            f"{name:<20} survival {s.mean():6.1f} (per seed {np.round(s, 1).tolist()})   "
            f"harms/episode {h.mean():.2f} (per seed {np.round(h, 2).tolist()})"
        )


if __name__ == "__main__":
    main()
