"""Training speed of one run: Empathic DQN (the suite's runner and learner) vs Stable-Baselines3 DQN.

Both train on Coexistence with the paper's MLP (25 → 128 → 128 → 5), batch 32, one gradient step
per env step, the same ``learning_starts`` and replay size, ε already at its final 0.01 in the
timed window (so both pay the greedy forward pass on almost every step) and the same torch thread
count:

* Empathic DQN at β = 0.5 (so ``Q`` and ``Q_emp`` both take a gradient step every env step),
  driven by ``empathy_zoo.training.runner.train_runs`` (one run, K = 1);
* SB3 DQN through its own ``learn()`` on the Gymnasium adapter (``empathy_zoo.gym_adapter``).

Each is timed over ``--steps`` env steps that start ``--settle`` steps after its warm-up; the
two alternate ``--repeats`` times (the medians are reported, so a noisy neighbour on the machine
hits both alike). Prints env-steps/s of both, the ratio, the command and the machine.

    python benchmarks/train_speed.py [--steps 5000] [--warmup 1000] [--settle 200] [--repeats 3] [--threads 1]
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from empathy_zoo.training.runner import RunnerOptions, train_runs
from empathy_zoo.training.spec import RunSpec

REPLAY = 500_000
FINAL_EPSILON = 0.01


class Stopwatch:
    """Times between two env-step counts of a run."""

    def __init__(self) -> None:
        self.start_step = self.end_step = 0
        self.started = self.stopped = float("nan")

    def arm(self, start_step: int, end_step: int) -> None:
        self.start_step, self.end_step = start_step, end_step
        self.started = self.stopped = float("nan")

    def tick(self, step: int) -> None:
        if step == self.start_step:
            self.started = time.perf_counter()
        elif step == self.end_step:
            self.stopped = time.perf_counter()

    def rate(self) -> float:
        return (self.end_step - self.start_step) / (self.stopped - self.started)


STOPWATCH = Stopwatch()


class TimedEmpathicDQN(EmpathicDQN):
    """Empathic DQN that reports its env-step count to :data:`STOPWATCH` after every step."""

    def observe(self, batch) -> None:
        super().observe(batch)
        STOPWATCH.tick(self.env_steps)


TIMED_EMPATHIC_DQN = Method(
    name="timed_empathic_dqn", learner=TimedEmpathicDQN, settings=EmpathicDQNSettings,
    preset={"harm_penalty": 0.0, "equality_shaping": False}, description="Empathic DQN with a stopwatch",
)


def empathic_dqn_rate(warmup: int, settle: int, steps: int) -> float:
    settings = {
        "selfishness": 0.5, "batch_size": 32, "learning_starts": warmup, "replay_capacity": REPLAY,
        "epsilon_end": FINAL_EPSILON, "epsilon_decay_steps": 1,
    }
    start = warmup + settle
    spec = RunSpec(env="coexistence_v0", method=f"{__name__}:TIMED_EMPATHIC_DQN", settings=settings, seed=0,
                   steps=start + steps, eval_interval=10 * (start + steps), eval_episodes=1)
    STOPWATCH.arm(start, start + steps)
    with tempfile.TemporaryDirectory(prefix="ez-train-speed-") as out:
        train_runs([spec], out, RunnerOptions(progress=False, checkpoint_interval=0))
    return STOPWATCH.rate()


def sb3_dqn_rate(warmup: int, settle: int, steps: int) -> float:
    from stable_baselines3.common.callbacks import BaseCallback

    from baselines.sb3 import SB3Settings, make_sb3_model
    from empathy_zoo.gym_adapter import make_single_agent_env

    class Tick(BaseCallback):
        def _on_step(self) -> bool:
            STOPWATCH.tick(self.num_timesteps)
            return True

    start = warmup + settle
    settings = SB3Settings(algorithm="dqn", learning_rate=1e-3, batch_size=32, net_arch=(128, 128), algorithm_kwargs={
        "buffer_size": REPLAY, "learning_starts": warmup, "train_freq": 1, "gradient_steps": 1,
        "exploration_fraction": warmup / (start + steps), "exploration_final_eps": FINAL_EPSILON,
    })
    model = make_sb3_model(settings, make_single_agent_env("coexistence_v0"), seed=0)
    STOPWATCH.arm(start, start + steps)
    model.learn(start + steps, callback=Tick())
    return STOPWATCH.rate()


def machine() -> list[str]:
    model = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                  if line.startswith("model name")), platform.processor() or "unknown CPU")
    import stable_baselines3

    return [
        f"CPU: {model}, {os.cpu_count()} logical cores, load average {' '.join(f'{x:.1f}' for x in os.getloadavg())}",
        f"Python {platform.python_version()}, numpy {np.__version__}, torch {torch.__version__} "
        f"({torch.get_num_threads()} thread(s)), stable-baselines3 {stable_baselines3.__version__}",
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000, help="timed env steps of each run")
    parser.add_argument("--warmup", type=int, default=1000, help="learning_starts of both")
    parser.add_argument("--settle", type=int, default=200, help="untimed learning steps before the timed ones")
    parser.add_argument("--repeats", type=int, default=3, help="alternating measurements of each")
    parser.add_argument("--threads", type=int, default=1, help="torch threads of both")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    print("command: python " + shlex.join(sys.argv))
    print("\n".join(machine()), flush=True)
    ours, theirs = [], []
    for repeat in range(args.repeats):
        ours.append(empathic_dqn_rate(args.warmup, args.settle, args.steps))
        theirs.append(sb3_dqn_rate(args.warmup, args.settle, args.steps))
        print(f"repeat {repeat + 1}: Empathic DQN {ours[-1]:7.0f} env-steps/s, SB3 DQN {theirs[-1]:7.0f} env-steps/s", flush=True)
    a, b = statistics.median(ours), statistics.median(theirs)
    print(f"Empathic DQN (runner, β = 0.5, Q and Q_emp updated): {a:7.0f} env-steps/s (median of {args.repeats})")
    print(f"SB3 DQN (learn() on the Gymnasium adapter):          {b:7.0f} env-steps/s (median of {args.repeats})")
    print(f"ratio: {a / b:.2f}× SB3 per run (target ≥ 3×)")
    print(f"load average after: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
